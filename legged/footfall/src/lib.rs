//! FootFall: single-step planning for one limb of an ATHLETE-like rover, after SunSpiral
//! et al.'s ground tools for ATHLETE. A pure algorithm crate: no bus, no clock.
//!
//! ```no_run
//! use std::sync::Arc;
//! use tca_footfall::Scene;
//! use tca_footfall::maps::{MapParams, leg_maps};
//! use tca_footfall::plan::{PlanOptions, StepPlanner};
//!
//! let scene = Arc::new(Scene::rock_field(1)?);
//! let leg = scene.leg_index("left_front")?;
//! let maps = leg_maps(&scene, leg, &MapParams::default())?;
//! println!("{} green cells", maps.counts.green);
//! let planner = StepPlanner::new(scene.clone(), PlanOptions::default())?;
//! let plan = planner.plan(leg, nalgebra::Point2::new(9.2, 0.8))?;
//! println!("{} way-points, {:.1} ms", plan.waypoints.len(), plan.times.total_ms);
//! # Ok::<(), tca_footfall::FootfallError>(())
//! ```
//!
//! # Layout
//!
//! - [`scene`]: [`Scene`], the robot and its terrain as telemetry reports them.
//! - [`reach`]: a foot placed with its steering axis upright.
//! - [`ground`]: slope and evenness under a wheel.
//! - [`maps`]: one leg's green / red / orange / blue maps, the polygons and margins, and the
//!   brute-force check of the same rules.
//! - [`margins`], [`terrain`], [`collision`]: the margin table, the terrain mesh, the
//!   one-leg collision checker with bisection.
//! - [`sbl`], [`smooth`], [`astar`], [`reference`]: the planners and smoothing.
//! - [`plan`]: [`plan::StepPlanner`] and [`plan::FootfallPlan`]; [`verify`]: a plan checked
//!   from outside.
//! - [`picture`]: the maps and a plan's ghost as PNG.
//! - [`campaign`]: the acceptance campaign.
//!
//! `README.md` beside this crate says what each rule and planner does.

pub mod astar;
pub mod campaign;
pub mod collision;
pub mod error;
pub mod ground;
pub mod maps;
pub mod margins;
pub mod picture;
pub mod plan;
pub mod reach;
pub mod reference;
pub mod sbl;
pub mod scene;
pub mod smooth;
pub mod terrain;
pub mod verify;

pub use error::{FootfallError, Result};
pub use nalgebra;
pub use scene::Scene;
