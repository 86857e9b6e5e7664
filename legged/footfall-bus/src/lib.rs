//! FootFall on the bus: thin modules around `tca-footfall`.
//!
//! | module | side | handles |
//! | --- | --- | --- |
//! | [`planner`] (`footfall-planner`) | ground | `footfall.maps`, `footfall.plan`: one leg's maps and a step's plan, from the robot's state as its telemetry reports it (`legged.robotModel`, `legged.bodyPose`, `legged.legState`) on the ground's terrain |
//! | [`executor`] (`footfall-exec`) | robot | `footfall.execute`: checks that a plan still fits the robot as it stands, then sends its `legged.legMove` and ends as it ends |
//!
//! [`operator::send_plan`] is the operator's side: it sends a plan and passes on the
//! telemetry that comes back while it runs. [`setup`] says where the robot and terrain come
//! from; [`messages`] has the vocabulary.
//!
//! With the robot's Controller (`tca-legged-controller`, or a real robot) the three make the
//! operator's loop: maps, plan, preview, send, watch.

pub mod executor;
pub mod messages;
pub mod operator;
pub mod planner;
pub mod setup;

pub use executor::{EXECUTOR_MODULE, connect_executor};
pub use messages::{FootfallExecute, FootfallMaps, FootfallPlanStep};
pub use operator::{Telemetry, send_plan};
pub use planner::{PLANNER_MODULE, PlannerConfig, connect_planner, scene_from_telemetry};
pub use setup::{FootfallSetup, TerrainSource, load_robot};
