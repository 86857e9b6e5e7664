//! Perception Display Manager (the report, §5.2.3): draws the LTM Manager's maps of any kind
//! and region as PNG pictures, with requested 3D positions (planned footfalls) and paths (leg
//! paths) drawn over them.
//!
//! # Layout
//!
//! - [`render`](mod@render): a [`MapGrid`](tca_single_leg_messages::MapGrid) and its overlays -> a
//!   [`Canvas`](tca_canvas::Canvas): colour ramp, unknown/occluded patterns, colour scale,
//!   distance scale bar, extent, overlays; [`render_png`] and [`write_png`].
//! - [`module`]: the PDM on the bus: [`connect`] with a [`PdmConfig`] handles `renderMap`,
//!   asking the LTM Manager for `mapRegion`; [`render_map`] does the same for command-line
//!   tools.
//! - [`error`]: [`PdmError`] and the [`Result`] alias.

pub mod error;
pub mod module;
pub mod render;

pub use error::{PdmError, Result};
pub use module::{PdmConfig, connect, render_map};
pub use render::{MapLayout, RenderOptions, render, render_png, write_png};
