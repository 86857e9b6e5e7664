//! Map pictures from the command line (`tca map`; the PDM of §5.2.3): a picture of any map
//! kind of any region, from a running walking system or from a traffic log.
//!
//! # Layout
//!
//!
//! - [`request`]: what to draw: kind, area (rectangle, polygon or the whole mapped area) and
//!   resolution, parsed from command-line text and checked before any work.
//! - [`from_log`]: the LTM Manager's map rebuilt from the range images a log recorded (up to a
//!   time), and the footfalls the Gait Planner chose.
//! - [`live`]: asking a running system's LTM Manager (`mapRegion`), or its PDM (`renderMap`).
//! - [`picture`]: drawing a grid to PNG with the PDM's renderer, and what was drawn
//!   ([`MapPicture`]).

pub mod from_log;
pub mod live;
pub mod picture;
pub mod request;

pub use from_log::{LogMapOptions, RecordedWalk, map_from_log, read_walk, rebuild};
pub use live::{LiveMapOptions, map_from_system};
pub use picture::{MapPicture, draw};
pub use request::{
    DEFAULT_RESOLUTION_M, MapArea, MapRequest, parse_kind, parse_polygon, parse_rectangle,
};
