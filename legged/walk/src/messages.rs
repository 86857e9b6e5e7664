//! The walking module's own messages: one step of a walk, and what it planned.

use serde::{Deserialize, Serialize};
use tca_legged_messages::{Pose, WorldPoint};
use tca_messages::{MessageId, message};

/// One leg's state at the start of a step planned ahead.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlannedLeg {
    /// Joint positions, body outwards.
    pub joints: Vec<f64>,
    /// Whether the foot stands.
    pub stance: bool,
    /// The foot's contact point, world frame.
    pub foot: WorldPoint,
}

/// Where a step planned ahead starts: where the step before it will leave the robot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlannedStart {
    /// The body's pose.
    pub body: Pose,
    /// Every leg, in the description's order.
    pub legs: Vec<PlannedLeg>,
}

/// Goal: plan one step of a walk and send its moves; inside a walk it then sends the next.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaitStep {
    /// The step's number in its walk, from 1.
    pub step: u32,
    /// The walk's goal, world X, metres.
    pub goal_x_m: f64,
    /// The walk's goal, world Y, metres.
    pub goal_y_m: f64,
    /// How near the goal the body must come, metres.
    pub tolerance_m: f64,
    /// Plan each step while the one before executes.
    pub concurrent: bool,
    /// Planned ahead: where the step before will leave the robot (else the Controller is
    /// asked where it is).
    pub start: Option<PlannedStart>,
    /// Planned ahead: the last move of the step before, which this step's first move follows.
    pub after: Option<MessageId>,
}
message!(GaitStep: goal "legged.gaitStep");

/// Inform: a step was planned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepPlanned {
    /// The step's number in its walk.
    pub step: u32,
    /// The footholds chosen, by leg, world frame.
    pub footholds: Vec<(String, WorldPoint)>,
    /// Where the step leaves the body.
    pub body_target: Pose,
    /// The least stability margin the plan keeps, metres.
    pub min_margin_m: f64,
    /// Wall-clock time the planning took, milliseconds.
    pub planning_ms: f64,
}
message!(StepPlanned: inform "legged.stepPlanned");
