//! What the simulator reports: move reports and force readings.

use std::time::Duration;

use nalgebra::{Point3, Vector3};
use tca_robot::JointPosition;

/// One sample of a leg's path during a move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSample {
    /// Simulated time since the move began.
    pub time: Duration,
    /// Joint position.
    pub joints: JointPosition,
    /// Real foot sole centre, world frame (includes any compliance deflection).
    pub foot_world: Point3<f64>,
}

/// Where a transition move touched the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Foot sole centre at touch-down, world frame.
    pub foot_world: Point3<f64>,
    /// Force on the foot when the move stopped, newtons.
    pub force_n: f64,
}

/// The result of a successful `leg_move`.
#[derive(Debug, Clone, PartialEq)]
pub struct MoveReport {
    /// Simulated time the move took.
    pub duration: Duration,
    /// The path, sampled every `simulation.report_period_s` and at the end.
    pub path: Vec<PathSample>,
    /// Ground contact of a transition move.
    pub contact: Option<Contact>,
    /// Joint position at the end.
    pub final_joints: JointPosition,
}

/// The result of a successful `body_move`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyMoveReport {
    /// Simulated time of the whole procedure (compress, relieve, propel, relieve strain).
    pub duration: Duration,
    /// Carriage Y before, metres.
    pub start_y_m: f64,
    /// Carriage Y after, metres.
    pub final_y_m: f64,
    /// Size of the strain (joint overshoot, as a foot displacement) relieved at the end, metres.
    pub strain_relieved_m: f64,
    /// Number of ~60 Hz control cycles of the propulsion.
    pub control_cycles: usize,
    /// The procedure that propelled the carriage.
    pub law: super::BodyMoveLaw,
    /// Carriage Y commanded, metres (`final_y_m` less this is the move's error).
    pub target_y_m: f64,
    /// Path length the foot slid on the ground during the propulsion, metres.
    pub foot_slid_m: f64,
}

/// A force/torque sensor reading: the force the ground exerts on the foot and its moment
/// about the sensor, in the foot frame (carriage axes: +Z up, so a loaded foot reads a
/// positive Z force).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceReading {
    /// Force, newtons.
    pub force_n: Vector3<f64>,
    /// Moment about the sensor, newton metres.
    pub moment_nm: Vector3<f64>,
}
