//! What a multi-legged robot description says, for people: [`RobotSummary`] (its legs, joints,
//! limits, mass, standing pose, stability and each foot's reachable workspace) printed as
//! text or serialised as JSON, and [`draw`]: the robot standing, seen from above and from the
//! side, as a PNG.
//!
//! `tca robot show NAME|FILE.urdf` is the command-line face of this crate.

pub mod draw;
pub mod error;
pub mod summary;

pub use draw::draw;
pub use error::ViewError;
pub use summary::{JointSummary, LegSummary, RobotSummary};
