//! The single-leg walking system assembled (the report): the Controller (simulated), Imaging
//! Sensor Manager, Local Terrain Map Manager, Perception Display Manager, Gait Planner and Leg
//! Recovery Planner on one central, one `walk` goal driving the leg down an obstacle course,
//! and what happened, reported.
//!
//! # Layout
//!
//! - [`terrain`]: the course or terrain file, and where the leg starts.
//! - [`system`]: the settings the modules share ([`SystemSetup`]) and connecting each of the
//!   six walking modules.
//! - [`module_options`]: one walking module on its own, as `tca module NAME` runs it.
//! - [`walk`](mod@walk): walking to a goal (and back), in-process or against a running
//!   system, and the [`WalkReport`].
//! - [`report`]: the map picture with footfalls and leg paths, the figures taken from the
//!   traffic log, the timeline, the summary text.
//! - [`replay`]: a recorded walk replayed with some modules played from its log.

pub mod module_options;
pub mod replay;
pub mod report;
pub mod system;
pub mod terrain;
pub mod walk;

pub use module_options::{ModuleOptions, connect_standalone};
pub use replay::{WALK_GOAL, WalkReplayOptions, comparison_rules, replay_walk};
pub use system::{ComputeModel, SystemSetup, WALKING_MODULES, connect_all, connect_module};
pub use terrain::{START_Y_M, TerrainChoice};
pub use walk::{DEFAULT_GOAL_Y_M, Progress, WALK_TIMEOUT, WalkLeg, WalkOptions, WalkReport, walk};
