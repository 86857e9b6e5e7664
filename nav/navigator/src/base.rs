//! What the navigator drives.

use tca_nav_sensing::{Attitude, Pose2};

/// The outcome of one drive command.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// The true pose after the command.
    pub pose: Pose2,
    /// The base hit something it could not cross (it stayed where it was).
    pub collided: bool,
    /// The base tipped over.
    pub fell: bool,
}

/// A robot base that obeys forward and turn speeds: the body-level interface the
/// navigator sees, whatever the robot.
pub trait Base {
    /// A short name for reports.
    fn name(&self) -> &str;
    /// The true pose (for the simulation and the report; the navigator never reads it).
    fn true_pose(&self) -> Pose2;
    /// The true height and tilt (where the simulated camera is placed; the navigator is
    /// given them as measured: drift is planar).
    fn attitude(&self) -> Attitude;
    /// Drives at `forward_mps` and `turn_rps` for `dt_s` seconds.
    fn drive(&mut self, forward_mps: f64, turn_rps: f64, dt_s: f64) -> Motion;
}
