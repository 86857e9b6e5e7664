//! The Controller module of a multi-legged robot on the bus, driving the quasi-static
//! simulator ([`tca_legged_sim::LeggedSim`]): a thin adapter between the `legged.`
//! messages and the simulator.
//!
//! ```no_run
//! use std::sync::Arc;
//! use nalgebra::Point2;
//! use tca_legged_controller::{LeggedControllerConfig, connect};
//! use tca_legged_model::{BUILTIN_ROBOTS, RobotModel};
//! use tca_legged_sim::StartPose;
//! use tca_module::Connector;
//! use tca_robot::HeightField;
//!
//! # async fn run(connector: Connector) -> Result<(), Box<dyn std::error::Error>> {
//! let model = Arc::new(RobotModel::builtin("ambler")?);
//! let urdf = BUILTIN_ROBOTS.iter().find(|r| r.name == "ambler").unwrap().urdf;
//! let ground = Arc::new(HeightField::flat(Point2::new(-10.0, -10.0), Point2::new(30.0, 10.0), 0.1, 0.0)?);
//! let start = StartPose { x_m: 0.0, y_m: 0.0, yaw_rad: 0.0 };
//! let _controller = connect(&connector, LeggedControllerConfig::new(model, urdf, ground, start)).await?;
//! # Ok(()) }
//! ```
//!
//! # What it serves
//!
//! - Queries: `legged.robotModel`, `legged.bodyPose`, `legged.legState`,
//!   `legged.controllerStatus`, answered from the simulator as it is.
//! - Commands: `legged.legMove`, `legged.bodyMove`, one at a time. A move that fails raises
//!   `legged.moveFailed` (or `legged.tipOver`) in the command's context and ends the
//!   command with failure.
//! - Injected hardware faults ([`InjectedFault`]): from a set simulated time on, every
//!   command that would move a given leg is refused and raises `legged.hardwareFault`
//!   naming the leg, so that what a walk does when a drive dies can be tried.
//! - Informs it sends: `legged.supportState` at the first command (the state before it), at
//!   every lift-off and after every move carried out; `legged.footContact` at every lift-off
//!   and touch-down. Their `t_s` is the simulator's clock.
//! - Telemetry ([`LeggedControllerConfig::telemetry_hz`]): `legged.telemetry` (joint angles,
//!   body pose, foot forces, centre of mass, margin) at a set rate on the wall clock, once a
//!   module handles it; moves under way in wall-clock time are sampled part-way.
//!
//! # Time
//!
//! The module runs on simulated time (`simulated_time(true)`): a command's handler spends
//! the move's simulated duration ([`tca_module::Module::spend`]), so on central's causal
//! simulated clock the command ends that much later in simulated time, and a whole walk
//! runs as fast as the machine allows with durations that add up like the robot's.
//!
//! With a speed ([`LeggedControllerConfig::speed`]) it runs on the wall clock instead, like a
//! real robot's Controller: a move takes its duration divided by the speed, its informs go
//! out as their events happen, and its messages carry wall-clock stamps. Telemetry and a
//! speed need a central on wall-clock time.
//!
//! # Layout
//!
//! - [`config`] has [`LeggedControllerConfig`].
//! - `serve.rs`: [`connect`], the handlers, the telemetry loop.
//! - `telemetry.rs`: telemetry samples, at rest and interpolated along a move under way.

pub mod config;
mod serve;
mod telemetry;

pub use config::{DEFAULT_MODULE_NAME, InjectedFault, LeggedControllerConfig, MAX_TELEMETRY_HZ};
pub use serve::connect;

#[cfg(test)]
mod bus_tests;
