//! A quasi-static simulator of any multi-legged robot described in URDF
//! ([`tca_legged_model::RobotModel`]) on a height-field terrain ([`tca_robot::HeightField`]):
//! no bus, no wall clock, only the robot's state and a causal simulated clock.
//!
//! ```
//! use std::sync::Arc;
//! use nalgebra::Point2;
//! use tca_legged_model::RobotModel;
//! use tca_legged_sim::{LeggedSim, SimParams, StartPose};
//! use tca_robot::HeightField;
//!
//! let model = Arc::new(RobotModel::builtin("hexapod")?);
//! let ground = Arc::new(HeightField::flat(Point2::new(-1.0, -1.0), Point2::new(2.0, 1.0), 0.02, 0.0)?);
//! let params = SimParams::for_model(&model);
//! let start = StartPose { x_m: 0.0, y_m: 0.0, yaw_rad: 0.0 };
//! let mut sim = LeggedSim::new(model.clone(), ground, start, params)?;
//! assert!(sim.stance().iter().all(|&s| s) && sim.margin() > 0.0);
//! // Lift the left front foot 3 cm by bending its hip up, then put it down again.
//! let q = sim.posture()[0].clone();
//! let up = vec![q[0], q[1] + 0.15, q[2]];
//! let down = vec![q[0], q[1] - 0.1, q[2]];
//! sim.leg_move("left_front", &[up, down], true)?;
//! assert!(sim.stance()[0] && sim.clock_s() > 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! `SIMULATOR.md` beside this crate describes the model, what is checked and its limits.
//!
//! # Layout
//!
//! - [`sim`] has [`LeggedSim`]: standing up, queries.
//! - `leg_move.rs`, `body_move.rs`: [`LeggedSim::leg_move`], [`LeggedSim::body_move`].
//! - [`params`] has [`StartPose`], [`SimParams`].
//! - [`report`] has [`MoveReport`], [`FootEvent`], [`Counters`].
//! - [`error`] has [`SimError`], [`MoveError`] and the bus exception it raises.
//! - [`sag`] has [`SagParams`]: the robot sagging under load when a leg lifts (an option).
//! - [`pose`] has conversions to and from the bus's poses and points.
//! - [`collide`]: shapes and foot spheres against the height field; [`collide::rest_height`],
//!   [`collide::touch_point`] and [`collide::foot_clearance`] of a foot sphere are public
//!   for planners that place feet as the simulator does.

mod body_move;
pub mod collide;
pub mod error;
mod leg_move;
pub mod params;
pub mod pose;
pub mod report;
pub mod sag;
pub mod sim;

pub use error::{MoveCommand, MoveError, MoveException, SimError};
pub use params::{SimParams, StartPose};
pub use pose::{isometry_to_pose, pose_to_isometry, world_point};
pub use report::{Counters, FootEvent, MoveReport};
pub use sag::SagParams;
pub use sim::LeggedSim;
