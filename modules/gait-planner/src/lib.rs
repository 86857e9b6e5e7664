//! Gait Planner (the report, §6.2.1 and §8.2): chooses where to plant the foot and how far
//! to move the body, by combining constraint cost maps on a 10 cm grid over the reachable
//! space ahead of the carriage (behind it when walking backward).
//!
//! ```
//! use nalgebra::Point2;
//! use tca_gait_planner::{GaitMaps, GaitParams, GaitPlanner, synthetic};
//! use tca_robot::{Course, LegParams};
//!
//! let terrain = Course::builtin(2)?.height_field()?;
//! let (lo, hi) = (Point2::new(0.0, 1.0), Point2::new(6.0, 6.0));
//! let footfall = synthetic::footfall_map(&terrain, lo, hi, 0.1, 0.15)?;
//! let elevation = synthetic::elevation_map(&terrain, lo, hi, 0.1)?;
//! let planner = GaitPlanner::new(LegParams::default(), GaitParams::default())?;
//! let step = planner.plan(2.5, 9.0, &GaitMaps {
//!     footfall: &footfall,
//!     elevation: &elevation,
//!     reachable: &|_| true,
//! })?;
//! assert!(step.advance_m > 0.0 && step.advance_m <= 1.5);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Layout
//!
//! - [`params`]: [`GaitParams`], the weights and constraints of `params/gait.toml`
//!   (embedded as the default, loadable; errors name the key).
//! - [`region`]: [`StepRegion`], the cost maps' grid for a step, and [`WalkDirection`].
//! - `maps`: one file per cost map: footfall, filtered footfall and the clear region
//!   (`footfall`), body advance (`advance`), scanner visibility (`visibility`), terrain
//!   elevation (`elevation`); [`CostMaps`] holds them all.
//! - [`planner`]: [`GaitPlanner`]: combine the maps, eliminate cells, choose the footfall
//!   and the body move ([`StepPlan`]).
//! - [`synthetic`]: footfall and elevation maps from a height field (tests, benchmarks).
//! - [`picture`]: a PNG mosaic of the cost maps.
//! - `serve.rs`: [`connect`] and [`GaitConfig`]: the module on the bus (the `planStep`
//!   goal: queries, choice, `recoverLeg` then `bodyMove`, `stepPlanned`).
//! - [`walk`]: the `walk` goal: stepping, sequential and concurrent constraints, and the
//!   exception handlers (replan after a failed move, halt after a hardware fault).
//! - [`error`]: the planning failures, [`GaitError`].
//!
//! # Frames and units
//!
//! World frame, metres and radians. The leg's reachability comes from the Leg Recovery
//! Planner (`tca_lrp::Reachability`, or its `legReachability` answer over the bus).

pub mod error;
mod maps;
pub mod params;
pub mod picture;
pub mod planner;
pub mod region;
mod serve;
pub mod synthetic;
pub mod walk;

pub use error::{GaitError, Result};
pub use maps::CostMaps;
pub use params::GaitParams;
pub use planner::{GaitMaps, GaitPlanner, StepPlan};
pub use region::{StepRegion, WalkDirection};
pub use serve::{DEFAULT_MODULE_NAME, GaitConfig, connect};
