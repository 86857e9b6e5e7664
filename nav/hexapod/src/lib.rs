//! A walking robot as a base for rough-terrain navigation (the DLR Crawler's role in
//! Chilian and Hirschmüller's tests): the navigator's forward and turn speeds carried out by
//! leg and body moves, so that it drives a walking robot exactly as it drives a wheeled one.
//!
//! - [`Stepper`] turns one drive command into checked free-gait moves (see [`stepper`]).
//! - [`HexapodBase`] carries them out on the quasi-static legged simulator in this process,
//!   as a [`tca_nav_navigator::Base`]; on the bus the same moves go to the legged
//!   Controller as `legged.legMove` and `legged.bodyMove` (`tca-nav-bus`).
//! - [`legged_params`] and [`hexapod_params`]: the navigation parameters of a walking
//!   robot (danger circle, camera on the body, speeds).
//!
//! The stepper plans its footholds on the simulator's terrain, standing in for a walking
//! robot's own sense of the ground under its feet (the Crawler walked blind, with leg
//! reflexes); the navigator that chooses where to go sees only the camera's map.

mod base;
mod presets;
pub mod stepper;

pub use base::{HexapodBase, HexapodError, gait_state, nav_sim_params, split_pose};
pub use presets::{HEXAPOD_DANGER, hexapod_params, legged_params};
pub use stepper::{Next, Stepper, StepperParams, Walk, WalkEnd, footprint_radius_m, planar};
