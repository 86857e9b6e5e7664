//! What the operator's tools, the ground-side planner and the robot-side executor say to
//! each other, in the `footfall.` namespace.
//!
//! | name | class | from → to |
//! | --- | --- | --- |
//! | `footfall.maps` | query → [`LegMaps`] | operator → planner: one leg's maps as the robot stands now |
//! | `footfall.plan` | query → [`FootfallPlan`] | operator → planner: a step of a leg to a target |
//! | `footfall.execute` | command | operator → executor (robot side): carry a plan out |
//!
//! The planner reads the robot's state from the Controller's telemetry (`legged.robotModel`,
//! `legged.bodyPose`, `legged.legState`); the executor sends `legged.legMove`.

use serde::{Deserialize, Serialize};
use tca_footfall::maps::{LegMaps, PolygonKind};
use tca_footfall::plan::{FootfallPlan, PlannerKind};
use tca_messages::message;

/// Query: the maps of one leg, as the robot stands now.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootfallMaps {
    /// The leg, by its name in the robot's description.
    pub leg: String,
    /// The polygon stability is judged against (the planner's default when `None`).
    pub polygon: Option<PolygonKind>,
    /// Cell size, metres (the planner's default when `None`).
    pub resolution_m: Option<f64>,
}
message!(FootfallMaps: query "footfall.maps" -> LegMaps);

/// Query: plan a step of one leg, from where it stands now to a target on the ground.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootfallPlanStep {
    /// The leg.
    pub leg: String,
    /// Where the wheel should go, world XY, metres.
    pub target: [f64; 2],
    /// Which planner plans the swing.
    pub planner: PlannerKind,
    /// Plan with the field heuristics (the terrain raised 15 cm, way-points 20 cm above the
    /// start and the target).
    pub heuristics: bool,
}
message!(FootfallPlanStep: query "footfall.plan" -> FootfallPlan);

/// Command: carry a plan out. The executor refuses a plan made for another robot, for the
/// leg where it no longer is, or for the body where it no longer stands (plan again), and
/// otherwise moves the leg through the plan's way-points to ground contact.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootfallExecute {
    /// The plan.
    pub plan: FootfallPlan,
}
message!(FootfallExecute: command "footfall.execute");
