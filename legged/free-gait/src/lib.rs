//! A free gait for any multi-legged robot described in URDF (`tca-legged-model`): any
//! number and layout of legs.
//!
//! Each [`FreeGait::plan_step`] moves the body toward the goal and re-places one leg:
//!
//! 1. **Leg.** Every standing foot is tested for how far along the full body move (a
//!    translation of up to `max_body_step_m` toward the goal, a turn toward it) it stays
//!    within reach; the legs that run out first, then those farthest behind, are tried
//!    first. The body's height at the end of the move: for legs with a vertical slide,
//!    `height_bias` of the way up the heights every foot's sampled workspace allows; for
//!    legs of revolute joints, the neutral height over the feet, or the nearest height a
//!    few steps above or below it at which inverse kinematics reaches every foot.
//! 2. **Body move.** The largest fraction of the move every standing leg can follow, or
//!    less; each is checked every `sample_m` for inverse kinematics of every standing leg,
//!    the stability margin over the standing feet (`tca_stability::margin_along_path` on
//!    the centre of mass sampled along the move), every link's collision shapes against
//!    the terrain and the legs' links against each other. If lifting the leg afterwards would leave less than `min_margin_m`, the
//!    body also shifts toward the middle of the feet that stay.
//! 3. **Foothold.** Candidates are drawn from the leg's sampled workspace, placed by the
//!    body's new pose, kept to the leg's own side of the body (no nearer its centre line
//!    than half the neutral foot's distance from it), and ranked by progress toward the
//!    goal, the terrain's [`TerrainView::foothold_cost`] and the margin of the stance they
//!    give. Unknown ground is never stepped on.
//! 4. **Swing.** Lift, travel above the terrain with `clearance_m`, lower to a way-point
//!    `below_foothold_m` under the foothold so that the executor's transition move stops at
//!    contact. A leg with a vertical prismatic joint (the Ambler's kind) lifts and lowers
//!    with that joint alone, as the single-leg testbed's Envelope Trajectory Finding
//!    Algorithm does; any other leg reaches the raised points by inverse kinematics. Every
//!    segment is a straight line in joint space, sampled for the foot's clearance, the
//!    leg's link shapes and the margin of the feet that stay; higher travel is tried when
//!    blocked.
//!
//! 5. **Own legs.** No foothold, no sample of a swing and no sample of a body move brings
//!    the links of two legs within `leg_clearance_m` of each other
//!    (`RobotModel::legs_touching`, capsules); nor is a foothold taken where the leg would
//!    touch another once the body has gone on by half or all of a full step, which would
//!    block the next body move.
//!
//! The moves use the model's own kinematics (`Leg::inverse_kinematics`,
//! `Leg::foot_position`, `RobotModel::collision_shapes`), as the executor does.

mod collision;
pub mod error;
pub mod gait;
mod geometry;
pub mod params;
pub mod state;
pub mod terrain;

pub use error::GaitError;
pub use gait::{FreeGait, stand};
pub use params::GaitParams;
pub use state::{Action, GaitState, LegGaitState, StepPlan};
pub use terrain::{GridView, TerrainView};
