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

/// Inform: a planner of the whole walk (RRT-Connect or CG-space) planned it (at its first
/// step, and again after a failed move): the path, the footholds and, for RRT-Connect,
/// both trees, for the report and its picture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoutePlanned {
    /// The step that asked for the plan.
    pub step: u32,
    /// The body at each posture of the path (RRT-Connect) or the CG at each cell of the
    /// route (CG-space), `[x, y, yaw]`, world frame, metres and radians.
    pub path: Vec<[f64; 3]>,
    /// Every planned foothold `[x, y]` (contact-sphere centres), world frame, metres.
    pub footholds: Vec<[f64; 2]>,
    /// The start tree's edges `[x0, y0, x1, y1]`, world frame, metres.
    pub start_tree: Vec<[f64; 4]>,
    /// The goal tree's edges `[x0, y0, x1, y1]`.
    pub goal_tree: Vec<[f64; 4]>,
    /// Nodes of both trees (RRT-Connect) or of the foot-level search (CG-space).
    pub nodes: u64,
    /// Iterations of the search (RRT-Connect) or routes planned (CG-space).
    pub iterations: u64,
    /// Length of the body's path over the ground, metres.
    pub length_m: f64,
    /// Wall-clock time the planning took, milliseconds.
    pub planning_ms: f64,
}
message!(RoutePlanned: inform "legged.routePlanned");

impl RoutePlanned {
    /// The inform for a CG-space plan, planned at step `step` in `elapsed`.
    pub fn of_cg_space(
        step: u32,
        plan: &crate::cg_steps::CgPlanned,
        elapsed: std::time::Duration,
    ) -> Self {
        RoutePlanned {
            step,
            path: plan.route.clone(),
            footholds: plan.footholds.clone(),
            start_tree: Vec::new(),
            goal_tree: Vec::new(),
            nodes: plan.nodes as u64,
            iterations: plan.routes as u64,
            length_m: plan.length_m,
            planning_ms: elapsed.as_secs_f64() * 1e3,
        }
    }

    /// The inform for `plan`, planned at step `step` in `elapsed`.
    pub fn of(step: u32, plan: &tca_rrt::Plan, elapsed: std::time::Duration) -> Self {
        let edges = |tree: &[(nalgebra::Point2<f64>, nalgebra::Point2<f64>)]| {
            tree.iter().map(|(a, b)| [a.x, a.y, b.x, b.y]).collect()
        };
        RoutePlanned {
            step,
            path: plan
                .postures
                .iter()
                .map(|p| [p.body.x, p.body.y, p.body.yaw])
                .collect(),
            footholds: plan
                .postures
                .iter()
                .flat_map(|p| p.feet.iter().map(|f| [f.x, f.y]))
                .collect(),
            start_tree: edges(&plan.start_tree),
            goal_tree: edges(&plan.goal_tree),
            nodes: plan.stats.nodes as u64,
            iterations: plan.stats.iterations as u64,
            length_m: plan.length_m(),
            planning_ms: elapsed.as_secs_f64() * 1e3,
        }
    }
}
