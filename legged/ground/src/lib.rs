//! The ground side of a legged robot far away, across a telemetry bridge (`tca-bridge`): what
//! the operators' central runs to see the robot and move it.
//!
//! # Layout
//!
//! - [`monitor`]: the telemetry monitor module ([`connect_monitor`]): takes
//!   `legged.telemetry`, `legged.supportState` and `legged.footContact` as they come, answers
//!   `legged.latestTelemetry`, counts samples lost on the way, records everything.
//! - [`session`]: an operator's session of leg moves ([`run_session`]), planned from the
//!   robot's state as it came across.
//! - [`footfall`]: an operator's session with FootFall ([`run_footfall_session`]): each step
//!   picked from a leg's maps, planned by FootFall's ground-side planner, carried out by its
//!   robot-side executor.
//! - [`demo`](mod@demo): the whole session on one machine: two centrals, the Controller, the
//!   monitor, the bridge and the operator (and FootFall's modules when it works with them);
//!   the bridge's log played back and compared.
//! - [`error`]: the errors, [`GroundError`].

pub mod demo;
pub mod error;
pub mod footfall;
pub mod monitor;
pub mod session;

pub use demo::{DOWN, DemoOptions, DemoReport, FOOTFALL_UP, Operator, ReplayCheck, UP, demo};
pub use error::GroundError;
pub use footfall::{FootfallSessionOptions, FootfallStep, run_footfall_session};
pub use monitor::{MONITOR_NAME, MonitorOptions, Received, connect_monitor};
pub use session::{SessionOptions, SessionReport, StepRecord, plan_steps, run_session};

#[cfg(test)]
mod footfall_session_tests;
