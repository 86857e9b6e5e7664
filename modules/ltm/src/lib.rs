//! Local Terrain Map Manager (the report, §5.2.2): builds elevation maps with per-cell
//! uncertainty from range images, merges them by maximum likelihood, keeps a 20 x 20 m window
//! around the vehicle in memory (paging the rest to disk), and answers region queries for
//! elevation, elevation with uncertainty, footfall evaluation and slope maps, with a cache.
//!
//! # Layout
//!
//! - [`builder`]: the LTM Builder: range image -> map patch ([`build_map`]); its method (an
//!   equivalent of the Locus method) and uncertainty model are documented there.
//! - [`cell`]: a map [`Cell`] (unknown, occluded with its greatest elevation, or known with a
//!   standard deviation) and the Merger's maximum-likelihood rule [`fuse`].
//! - [`patch`]: the world-aligned lattice every map of one resolution shares, and dense
//!   rectangles of it ([`Patch`]).
//! - [`scroller`]: the LTM Scroller: the tiled map store with its window around the vehicle
//!   ([`TileStore`]); [`tile_file`]: the tiles' on-disk format.
//! - [`footfall`]: footfall cost and slope over the foot's area.
//! - [`region`]: checked query regions (polygon and resolution) and their grids.
//! - [`query`]: answering region queries, and the query cache.
//! - [`manager`]: [`LocalTerrainMap`], the whole manager's state, and [`LtmConfig`]
//!   ([`LtmConfig::for_robot`] sizes cells, window and foot for a walking robot of any
//!   scale).
//! - [`module`]: the LTM Manager on the bus: [`connect`] answers `mapRegion`, asking the ISM
//!   for `acquireImage` when a refresh is requested or it has no map yet.
//! - [`error`]: [`LtmError`] and the [`Result`] alias.

//! # Legged robots
//!
//! Images from a multi-legged robot's scanner (`tca_ism::IsmConfig::legged_simulated`) carry
//! the same transform chain as the single leg's, with the legged body as the body frame, so
//! they build and merge unchanged: the builder works in world coordinates whatever the
//! scanner's position and orientation, and [`LocalTerrainMap::add_image`] scrolls the window
//! to the image's body origin (the window stays aligned with the world axes at any heading).
//! [`LtmConfig::for_robot`]`(cell_m, half_side_m, foot_radius_m)` gives a map at the robot's
//! scale, e.g. `for_robot(0.1, 10.0, 0.15)` for the Ambler and `for_robot(0.02, 1.0, 0.012)`
//! for the small hexapod.

pub mod builder;
pub mod cell;
pub mod error;
pub mod footfall;
pub mod manager;
pub mod module;
pub mod patch;
pub mod query;
pub mod region;
pub mod scroller;
pub mod tile_file;

pub use builder::{BuilderConfig, build_map};
pub use cell::{Cell, CellState, fuse};
pub use error::{LtmError, Result};
pub use footfall::{FootEvaluator, FootParams, Footing};
pub use manager::{LocalTerrainMap, LtmConfig, MergeReport};
pub use module::{connect, connect_with_map};
pub use patch::Patch;
pub use query::CacheStats;
pub use region::Region;
pub use scroller::{ScrollReport, TileStore};
