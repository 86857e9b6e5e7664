//! Multi-legged walking assembled on the bus: the walk report and its consistency check, and
//! the messages of the walking module.
//!
//! # Layout
//!
//! - [`report`]: [`LeggedWalkReport`], what a walk did, with one [`StateRecord`] per support
//!   change (body pose, centre of mass, every foot, margin).
//! - [`check`]: [`check_states`], the states checked against the terrain from the report's
//!   numbers alone.
//! - [`messages`]: `legged.gaitStep` and `legged.stepPlanned`.
//!
//! The walking module itself (`gait_module.rs`, `map_view.rs`, `walks.rs`, `terrain.rs` in
//! this directory) is written against the simulator, courses and free gait crates and joins
//! the module tree when they land.

pub mod check;
pub mod messages;
pub mod report;

pub use check::{StateProblem, check_states};
pub use report::{FootRecord, LeggedWalkReport, StateRecord};
