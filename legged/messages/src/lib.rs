//! The vocabulary of multi-legged walking: what a walker, its planners and the robot's
//! Controller (real or simulated) say to each other, for any robot described in URDF.
//!
//! Every name is in the `legged.` namespace, apart from the single-leg testbed's messages,
//! whose formats stay as they are. SI units and radians; the world frame is ROS REP 103
//! (X east, Y north, Z up) and a body pose is its position and its roll, pitch and yaw
//! (rotations about X, Y, Z applied in that order, the yaw last). A leg is named as in the
//! robot's description (its foot link without `_foot`), and its joint positions are one
//! value per moving joint from the body out.
//!
//! # Layout
//!
//! - [`geometry`]: [`WorldPoint`], [`Pose`].
//! - [`controller`]: the robot's side: [`RobotModel`], [`BodyPose`], [`LegState`] queries;
//!   [`LegMove`] and [`BodyMove`] commands, the emergency stop [`Halt`] and [`Resume`]; the
//!   [`FootContact`] inform.
//! - [`exceptions`]: [`MoveFailed`], [`HardwareFault`], [`TipOver`].
//! - [`walking`]: the [`LeggedWalk`] goal, the [`SupportState`] inform every support change
//!   sends, and the Controller's counters ([`LeggedStatus`]).
//! - [`telemetry`]: the [`Telemetry`] inform a Controller publishes at a set rate (joint
//!   angles, body pose, foot forces) and the operator side's [`LatestTelemetry`] query.

pub mod controller;
pub mod exceptions;
pub mod geometry;
pub mod telemetry;
pub mod walking;

pub use controller::{
    BodyMove, BodyPose, FootContact, Halt, LegMove, LegState, LegStateReply, Resume,
    RobotDescription, RobotModel,
};
pub use exceptions::{HardwareFault, MoveFailed, MoveFailureKind, TipOver};
pub use geometry::{Pose, WorldPoint};
pub use telemetry::{LatestTelemetry, LatestTelemetryReply, Telemetry};
pub use walking::{FootState, LeggedStatus, LeggedStatusReply, LeggedWalk, SupportState};

#[cfg(test)]
mod tests;
