//! One canvas for every picture the system draws: the PDM's map pictures, the Leg Recovery
//! Planner's configuration-space searches, the Gait Planner's cost maps and the timeline of a
//! traffic log.
//!
//! # Layout
//!
//! - [`canvas`]: [`Canvas`], an RGB image with rectangles, lines, circles, markers, text and
//!   copies of other canvases, clipped to its edges; its PNG encoding.
//! - [`font`]: the 5 x 7 bitmap font of labels.
//! - [`error`](mod@error): [`CanvasError`].

pub mod canvas;
pub mod error;
pub mod font;

pub use canvas::{Canvas, Rgb, grey};
pub use error::CanvasError;
