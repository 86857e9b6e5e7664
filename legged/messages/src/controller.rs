//! What the robot's Controller answers and carries out.

use serde::{Deserialize, Serialize};
use tca_messages::message;

use crate::geometry::{Pose, WorldPoint};

/// Query: the robot the Controller drives.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotModel;
message!(RobotModel: query "legged.robotModel" -> RobotDescription);

/// The answer to [`RobotModel`]: the robot's description, so that planners plan for the
/// robot that is really there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotDescription {
    /// The robot's name.
    pub name: String,
    /// Its URDF text.
    pub urdf: String,
    /// Its legs' names, in the order of the description.
    pub legs: Vec<String>,
}

/// Command: the emergency stop. From now on the Controller refuses every move, each
/// refusal raising [`crate::HardwareFault`] (which halts a walk), until [`Resume`]. A move
/// already under way is carried out to its end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Halt;
message!(Halt: command "legged.halt");

/// Command: lifts an emergency stop ([`Halt`]): the Controller carries out moves again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resume;
message!(Resume: command "legged.resume");

/// Query: where the body is now.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyPose;
message!(BodyPose: query "legged.bodyPose" -> Pose);

/// Query: one leg's state now.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LegState {
    /// The leg.
    pub leg: String,
}
message!(LegState: query "legged.legState" -> LegStateReply);

/// The answer to [`LegState`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LegStateReply {
    /// The leg.
    pub leg: String,
    /// Its joint positions, body outwards (radians or metres).
    pub joints: Vec<f64>,
    /// The foot's contact point (the bottom of its contact sphere), world frame.
    pub foot: WorldPoint,
    /// Whether the foot stands on the ground.
    pub stance: bool,
    /// The ground's force on the foot along world Z, newtons (0 in the air).
    pub force_n: f64,
}

/// Command: move one leg through joint-space way-points, every joint arriving at each
/// way-point together. A foot that stands is lifted by the move; with `transition`, the last
/// segment stops when the foot touches the ground (and reaching its end without touching is
/// a failure).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LegMove {
    /// The leg.
    pub leg: String,
    /// Way-points, each one value per moving joint of the leg; at least one.
    pub waypoints: Vec<Vec<f64>>,
    /// Stop the last segment at ground contact.
    pub transition: bool,
}
message!(LegMove: command "legged.legMove");

/// Command: move the body to a pose with the standing feet where they are. Refused, or failed
/// with [`TipOver`](crate::TipOver) or [`MoveFailed`](crate::MoveFailed), when fewer than
/// three feet stand, a foot would leave its workspace, or the centre of mass would leave the
/// support polygon along the way.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyMove {
    /// The pose to reach.
    pub target: Pose,
}
message!(BodyMove: command "legged.bodyMove");

/// Inform: a foot touched down (or lifted off).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootContact {
    /// The leg.
    pub leg: String,
    /// Where the foot touched, world frame.
    pub at: WorldPoint,
    /// True at touch-down, false at lift-off.
    pub stance: bool,
}
message!(FootContact: inform "legged.footContact");
