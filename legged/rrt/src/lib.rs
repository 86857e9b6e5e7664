//! Integrated motion planning for a multi-legged robot walking statically on rough
//! terrain, after Belter and Skrzypczyński, *Integrated Motion Planning for a Hexapod
//! Robot Walking on Rough Terrain*.
//!
//! [`Planner::plan`] runs RRT-Connect over the body's (x, y): one tree grows from the
//! start and one from the goal (the robot walks forward in the first, backward in the
//! second); each iteration extends one tree toward a random point and then the other
//! toward the new node until it reaches it (the trees then share that posture) or is
//! blocked, and the trees swap roles. A step is at most `max_step_m` long; a failed step
//! is halved up to `extend_attempts` times (Reached, Advanced, Trapped as in the paper).
//!
//! Each node is a full configuration ([`create_posture`]): the body's roll and pitch from
//! a robust (Tukey biweight) plane fit of the ground under the robot, its height the
//! neutral height over that plane or more if the body would come nearer than
//! `body_clearance_m` to the highest ground under it, and a foothold per leg
//! ([`select_foothold`]): the best footfall quality (slope and roughness under the foot)
//! summed over the 3 x 3 cells around each candidate, among candidates near the neutral
//! foot position that inverse kinematics reaches, preferring joints away from their
//! limits. The paper's learned slip predictor is replaced by that footfall evaluation.
//!
//! Each edge is a checked move ([`check_traverse`]): the body on a straight line with its
//! angles interpolated, the legs swinging in the gait's groups (tripod or wave) along the
//! upper convex hull of the terrain profile raised by `foot_clearance_m`
//! ([`foot_trajectory`]); every posture along the move (every `check_spacing_m`) must keep
//! every foot within reach, the centre of mass (legs included) inside the standing feet's
//! support polygon shrunk by `stability_margin_m` (the triangle-area test,
//! [`statically_stable`]), no leg's capsule touching another's or the body, and no link
//! in the ground.

pub mod checks;
pub mod create;
pub mod error;
pub mod foothold;
pub mod params;
pub mod picture;
pub mod pose;
pub mod robot;
pub mod rrt;
pub mod terrain;
pub mod trajectory;
pub mod traverse;

#[cfg(test)]
mod tests;

pub use checks::statically_stable;
pub use create::{Refusal, create_posture};
pub use error::PlanError;
pub use foothold::{Foothold, select_foothold};
pub use params::{Gait, RrtParams};
pub use picture::{RouteDrawing, draw_plan, draw_route, write_plan_png};
pub use pose::{BodyPose, Posture};
pub use robot::Robot;
pub use rrt::{Extension, Node, Plan, PlanStats, Planner, Tree};
pub use terrain::Terrain;
pub use trajectory::foot_trajectory;
pub use traverse::{Phase, Swing, Transition, check_traverse};

/// The geometry and terrain crates of this crate's interface, for users that do not
/// depend on them themselves.
pub use nalgebra;
pub use tca_robot;
