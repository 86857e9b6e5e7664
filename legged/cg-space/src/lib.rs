//! Route and footfall planning for legged robots in CG-space, after Eldershaw and Yim,
//! "Motion planning of legged vehicles in an unstructured environment".
//!
//! The robot is reduced to its centre of gravity's (x, y, heading), roll and pitch zero, on
//! a grid whose cell is the smallest foot's footprint ([`CgGrid`]). A *foot cell* is valid
//! where the ground's slope is within the robot's traction ([`FootMap`]); a *CG cell* is
//! valid where each of the four quadrants about the CG holds a valid foot cell in some
//! leg's range, and where a body height exists at which the under-carriage (an inverse
//! height map of the robot) clears the ground and one such foot per quadrant reaches its
//! ground ([`validity`]). CG cells are evaluated lazily, region by region ([`CgSpace`]).
//!
//! Routes ([`route`]) join cells by A* inside a block about them ([`astar`]), and a
//! tree-building probabilistic roadmap joins each new point only to trees it is not yet
//! part of; a bidirectional flood proves a route impossible in bounded time. The
//! foot-level search ([`footplan`]) is depth first, moves tried in the paper's order of
//! priority, footholds ranked by how many route cells ahead they stay usable. Where it gets
//! stuck, the cell is marked invalid and the route replanned ([`planner`]).
//!
//! Frames: world X east, Y north, Z up; headings counter-clockwise from +X; the body frame
//! x forward, y left, z up. Metres and radians.
//!
//! ```
//! use nalgebra::Point2;
//! use tca_cg_space::{CgParams, CgSpace, PlanParams, plan};
//! use tca_legged_model::RobotModel;
//! use tca_robot::HeightField;
//!
//! let model = RobotModel::builtin("ambler")?;
//! let terrain = HeightField::flat(Point2::new(0.0, -6.0), Point2::new(20.0, 6.0), 0.1, 0.0)?;
//! let mut space = CgSpace::for_model(&model, &terrain, CgParams::default())?;
//! let p = plan(&mut space, (Point2::new(5.0, 0.0), 0.0), (Point2::new(9.0, 0.0), 0.0), None, &PlanParams::default())?;
//! assert!(p.feet.route.len() > 10);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod astar;
pub mod distribute;
pub mod error;
pub mod footcheck;
pub mod footmap;
pub mod footmoves;
pub mod footplan;
pub mod grid;
pub mod legs;
pub mod picture;
pub mod planner;
pub mod robot;
pub mod route;
pub mod space;
pub mod validity;

pub use astar::{AStarResult, Block, astar};
pub use distribute::{
    BatchParams, BatchedRouteError, JoinError, JoinQuery, Joiner, Joins, LocalJoiner, Partition,
    fingerprint, plan_route_batched, roadmap_batched,
};
pub use error::CgError;
pub use footmap::FootMap;
pub use footplan::{
    FootCell, FootPlan, FootSearch, FootStep, Held, MoveCheck, SearchCounts, SearchParams, Stance,
    apply as apply_step, millimetres,
};
pub use grid::{CgCell, CgGrid};
pub use legs::{BodyPose, LegPose, Legs};
pub use picture::{
    Layout, PictureError, PictureOptions, draw_cg_space, footfalls, stances, start_stance,
    write_cg_space_png,
};
pub use planner::{
    JoinedRoutes, LocalRoutes, Plan, PlanParams, RoutePlanner, Standing, plan, plan_checked,
    plan_with,
};
pub use robot::{CgParams, CgRobot};
pub use route::{Flood, Route, RouteParams, flood, plan_route, roadmap};
pub use space::{CgSpace, REGION_CELLS};
pub use validity::{Verdict, assess};
