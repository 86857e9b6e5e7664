//! Telemetry: what the robot's side publishes at a set rate for the operator far away, and
//! what the operator's side answers about the latest it received.

use serde::{Deserialize, Serialize};
use tca_messages::message;

use crate::controller::LegStateReply;
use crate::geometry::{Pose, WorldPoint};

/// Inform: the robot's state sampled at the Controller's telemetry rate: joint angles, body
/// pose and foot forces, for an operator who sees the robot only through these (after a
/// delay, across a bridge between two centrals).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Telemetry {
    /// Running number of the sample since the Controller started (0, 1, 2, ...): a gap is a
    /// sample lost on the way.
    pub seq: u64,
    /// The Controller's motion clock when the sample was taken, seconds (the `t_s` of its
    /// `legged.supportState`; moves under way are sampled part-way).
    pub t_s: f64,
    /// The body's pose, world frame.
    pub body: Pose,
    /// The centre of mass, legs included, world frame.
    pub com: WorldPoint,
    /// Static stability margin of the centre of mass over the standing feet, metres
    /// (negative outside their polygon).
    pub margin_m: f64,
    /// Every leg, in the description's order: its joint positions (radians or metres), its
    /// foot's contact point, whether it stands and the ground's force on it (newtons along
    /// world Z, 0 in the air).
    pub legs: Vec<LegStateReply>,
}
message!(Telemetry: inform "legged.telemetry");

/// Query: the latest telemetry the operator's side received, and how much it received.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LatestTelemetry;
message!(LatestTelemetry: query "legged.latestTelemetry" -> LatestTelemetryReply);

/// The answer to [`LatestTelemetry`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LatestTelemetryReply {
    /// The latest sample, if any came.
    pub latest: Option<Telemetry>,
    /// When it arrived, nanoseconds since the UNIX epoch (0 when none came).
    pub received_ns: u64,
    /// Samples received so far.
    pub received: u64,
    /// Samples that never arrived: gaps in the running numbers so far.
    pub missing: u64,
}
