//! Multi-legged walking assembled on the bus: the simulated Controller, the body-mounted
//! scanner (ISM), the scrolling terrain map (LTM Manager) and the walking module with its free
//! gait, driven by one `legged.walk` goal, and a report an outside checker can verify.
//!
//! # Layout
//!
//! - [`system`]: the modules of one walk ([`LeggedSetup`], [`connect_module`]).
//! - [`gait_module`]: the walking module (`gait`): `legged.walk` and its `legged.gaitStep`s.
//! - [`map_view`]: the LTM Manager's maps seen as the free gait's terrain.
//! - [`walk`]: a whole walk in one process, with its log, picture and report.
//! - [`report`]: [`LeggedWalkReport`], what a walk did, with one [`StateRecord`] per support
//!   change (body pose, centre of mass, every foot, margin).
//! - [`check`]: [`check_states`], the states checked against the terrain from the report's
//!   numbers alone.
//! - [`terrain`]: the ground (a course or a file) and the checks on start and goal.
//! - [`messages`]: `legged.gaitStep` and `legged.stepPlanned`.
//! - [`cg_workers`]: worker modules for the CG-space planner's route joins.

pub mod cg_steps;
pub mod cg_workers;
pub mod check;
pub mod gait_module;
pub mod map_view;
pub mod messages;
pub mod mount;
pub mod picture;
pub mod report;
pub mod rrt_steps;
pub mod system;
pub mod terrain;
pub mod walk;
mod walks;

pub use cg_workers::{CgWorkerStart, CgWorkers};
pub use check::{StateProblem, check_states};
pub use report::{FootRecord, LeggedWalkReport, StateRecord};
pub use system::{LEGGED_MODULES, LeggedPlanner, LeggedSetup, connect_all, connect_module};
pub use tca_legged_controller::InjectedFault;
pub use terrain::LeggedTerrain;
pub use walk::{LeggedWalkOptions, WalkWorkers, walk};

#[cfg(test)]
mod cg_workers_tests;
