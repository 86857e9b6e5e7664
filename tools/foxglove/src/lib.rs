//! Foxglove for tca: a live view of a running system over the Foxglove WebSocket protocol
//! and MCAP files of recorded walks, both through Foxglove's own SDK crate.
//!
//! Every message name is a channel whose JSON schema is derived from its registered format
//! ([`schema`], [`traffic`]); the walking and navigating systems' traffic also becomes
//! Foxglove's well-known messages ([`wellknown`]): terrain and danger maps as
//! `foxglove.Grid`, the robot's frames (and a navigating base's estimated and true poses) as
//! `foxglove.FrameTransforms` (with a legged robot's URDF on a topic for the 3D panel),
//! planned leg paths, footholds, the support polygon and the navigator's path and goal as
//! `foxglove.SceneUpdate`, range and depth images as `foxglove.RawImage`, walk and
//! navigation progress and problems as `foxglove.Log`.
//!
//! # Layout
//!
//! - [`schema`]: JSON schemas from data formats.
//! - [`traffic`]: topics, schemas and JSON of the traffic channels.
//! - [`wellknown`]: [`WellKnownState`], traffic to well-known messages.
//! - [`geometry`]: nalgebra to Foxglove geometry.
//! - [`export`]: [`export_foxglove`], a log to MCAP.
//! - [`live`]: [`LiveView`], the WebSocket server.
//! - [`error`][]: [`FoxgloveError`].

pub mod error;
pub mod export;
pub mod geometry;
pub mod live;
pub mod schema;
pub mod traffic;
pub mod wellknown;

pub use error::{FoxgloveError, Result};
pub use export::{ExportSummary, export_foxglove};
pub use live::LiveView;
pub use wellknown::{WellKnown, WellKnownState};
