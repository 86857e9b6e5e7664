//! Leg Recovery Planner (the report, §6.2.2 and §6.3): moves the foot from where it is to a
//! footfall without striking terrain, with time- and power-efficient trajectories found by
//! the Envelope Trajectory Finding Algorithm, and tells the Gait Planner which footfalls the
//! foot can reach.
//!
//! ```
//! use nalgebra::{Point2, Point3};
//! use tca_lrp::{LegRecoveryPlanner, LrpParams, TerrainGrid};
//! use tca_robot::{Course, ElbowBranch, CarriagePose, LegKinematics, LegParams};
//!
//! let terrain = Course::builtin(3)?.height_field()?;
//! let map = TerrainGrid::elevation_from_height_field(
//!     &terrain, Point2::new(0.0, 0.0), Point2::new(6.0, 5.0), 0.05)?;
//! let planner = LegRecoveryPlanner::new(LegParams::default(), LrpParams::default())?;
//! // The foot stands on the sand behind and left of the carriage at y = 2 m ...
//! let kin = LegKinematics::new(&LegParams::default());
//! let pose = CarriagePose::level(2.0);
//! let start = kin.inverse_world(&pose, &Point3::new(2.0, 1.2, 0.0), ElbowBranch::Positive)?;
//! // ... and goes to a footfall beyond the 1.2 m "sun" box, around it.
//! let plan = planner.plan(&map, 2.0, &start, &Point3::new(3.3, 3.6, 0.0))?;
//! assert!(plan.to_leg_move().transition);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Layout
//!
//! - [`params`]: [`LrpParams`], the planner's own parameters (cell size, margins, cost).
//! - [`cost`]: [`CostModel`] (time, energy and their ratio, turn penalty) and
//!   [`JointSpeeds`].
//! - [`terrain_grid`]: [`TerrainGrid`] (the LTM Manager's maps with unknown and occluded
//!   cells, converted from and to the wire) and [`ObstacleHeights`] (conservative heights).
//! - [`cspace`]: [`CSpace`], the shoulder x elbow grid of lowest foot heights.
//! - [`envelope`]: [`ReachEnvelope`], the heights reachable at one moment.
//! - [`etfa`]: the Envelope Trajectory Finding Algorithm (A*).
//! - [`trajectory`]: way-point extraction (lifts first, lowers last) and an independent
//!   clearance check.
//! - [`planner`]: [`LegRecoveryPlanner`], input checks and the whole pipeline;
//!   [`LegPlan`]; [`Reachability`].
//! - [`exact`]: an exact search over (shoulder, elbow, foot height) used to measure the
//!   ETFA (tests, benchmarks).
//! - [`picture`]: PNG pictures of the configuration space and the search.
//! - [`polygon`]: map regions as polygons (validation, bounding grid, inclusion).
//! - `serve.rs`: [`connect`] and [`LrpConfig`]: the module on the bus (`recoverLeg` goal,
//!   `legReachability` query), failures raised as `moveFailed`.
//! - [`error`]: the planning failures, [`PlanError`].
//!
//! # Frames and units
//!
//! World frame for footfalls and maps, joint space for way-points (§8.2); metres, radians,
//! seconds, joules. Heights are the world Z of the foot's sole; the carriage is taken as
//! level (the `recoverLeg` goal gives only its position on the rails).

pub mod cost;
pub mod cspace;
pub mod envelope;
pub mod error;
pub mod etfa;
pub mod exact;
pub mod params;
pub mod picture;
pub mod planner;
pub mod polygon;
mod serve;
pub mod terrain_grid;
pub mod trajectory;

pub use cost::{CostModel, JointSpeeds, MotionCost};
pub use cspace::{CCell, CSpace};
pub use envelope::ReachEnvelope;
pub use error::{PlanError, Result};
pub use params::LrpParams;
pub use planner::{LegPlan, LegRecoveryPlanner, Reachability};
pub use serve::{DEFAULT_MODULE_NAME, LrpConfig, connect, reachability_map};
pub use terrain_grid::{MapValue, ObstacleHeights, TerrainGrid};
