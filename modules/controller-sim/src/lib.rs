//! Simulated Controller (the report, §4): the single leg, its carriage and the true terrain
//! behind the Controller's interface of §4.2, served on the TCA bus.
//!
//! ```no_run
//! use tca_controller_sim::{ControllerConfig, SpeedFactor};
//! use tca_single_leg_messages::{BodyMove, GlobalLegPosition};
//! use tca_module::{Connector, Module};
//!
//! # async fn run(connector: Connector) -> Result<(), Box<dyn std::error::Error>> {
//! let config = ControllerConfig::course(3)?.with_speed(SpeedFactor::Times(10.0));
//! let _controller = tca_controller_sim::connect(&connector, config).await?;
//! // Any other module talks to it through central, without knowing it is simulated.
//! let gait = Module::builder("gait").connect(&connector).await?;
//! let foot = gait.query(&GlobalLegPosition).await?;
//! gait.command(&BodyMove { target_y_m: 1.5 })?;
//! # let _ = foot; Ok(()) }
//! ```
//!
//! # Layout
//!
//! - [`sim`]: the pure, bus-free simulator core: [`sim::LegSimulator`] with `leg_move`,
//!   `body_move`, `set_trans_force` and the position and force queries, in simulated time,
//!   with fault injection for testing.
//! - [`config`]: [`ControllerConfig`] (terrain, leg parameters, start pose, faults, module
//!   name) and [`SpeedFactor`] (real time x k, or as fast as possible).
//! - [`controller`]: [`controller::Controller`], the state behind the bus: moves playing out
//!   in wall-clock time, the simulated clock, the collision count, what queries see mid-move.
//! - `serve.rs`: [`connect`] and [`run_builtin`]: the module and its handlers; failures
//!   raised as exceptions.
//! - [`convert`]: message types to and from the simulator's types; which exception a
//!   simulator error raises.
//! - [`persist`]: the state file that survives a restart (leg, carriage, clock, collisions)
//!   and the remembered outcomes of the latest commands.

pub mod config;
pub mod controller;
pub mod convert;
pub mod persist;
mod serve;
pub mod sim;

pub use config::{ConfigError, ControllerConfig, DEFAULT_MODULE_NAME, SpeedFactor};
pub use serve::{connect, run_builtin};
