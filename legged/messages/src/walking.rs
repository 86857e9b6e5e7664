//! What a walk is asked for and what it leaves behind: the user's goal, the Controller's
//! record of every support change, and its counters.

use serde::{Deserialize, Serialize};
use tca_messages::message;

use crate::geometry::{Pose, WorldPoint};

/// Goal: walk the body's origin to a point on the ground (world X, Y), whatever the robot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeggedWalk {
    /// East of the goal, metres.
    pub goal_x_m: f64,
    /// North of the goal, metres.
    pub goal_y_m: f64,
    /// The walk is done when the body's origin is within this of the goal (horizontally),
    /// metres (> 0).
    pub tolerance_m: f64,
    /// Plan the next step while the current one executes.
    pub concurrent: bool,
}
message!(LeggedWalk: goal "legged.walk");

/// One foot in a [`SupportState`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootState {
    /// The leg.
    pub leg: String,
    /// The foot's contact point (the bottom of its contact sphere), world frame; for a foot
    /// in the air, the point of its sphere nearest the ground.
    pub at: WorldPoint,
    /// Whether the foot stands on the ground.
    pub stance: bool,
}

/// Inform: the robot's state after a change of support (a foot touched down or lifted off)
/// or a body move, as the Controller knows it; walk reports list these so that an outside
/// checker can verify the walk against the terrain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SupportState {
    /// Simulated (or wall-clock) time since the Controller started, seconds.
    pub t_s: f64,
    /// The body's pose, world frame.
    pub body: Pose,
    /// The centre of mass, legs included, world frame.
    pub com: WorldPoint,
    /// Every foot, in the description's leg order.
    pub feet: Vec<FootState>,
    /// Static stability margin of the centre of mass in the standing feet's support
    /// polygon, metres (negative outside).
    pub margin_m: f64,
}
message!(SupportState: inform "legged.supportState");

/// Query: the Controller's counters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeggedStatus;
message!(LeggedStatus: query "legged.controllerStatus" -> LeggedStatusReply);

/// The answer to [`LeggedStatus`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeggedStatusReply {
    /// Simulated time since the Controller started, seconds.
    pub clock_s: f64,
    /// Tip-overs so far.
    pub falls: u32,
    /// Contacts of a link (not a foot's sphere) with the terrain so far, and feet driven into
    /// the ground.
    pub collisions: u32,
    /// Moves so far during which parts of the robot touched each other.
    pub self_collisions: u32,
    /// Whether the robot lies tipped over (it then refuses every move).
    pub fallen: bool,
    /// Leg moves and body moves carried out so far.
    pub moves: u32,
}
