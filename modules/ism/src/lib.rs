//! Imaging Sensor Manager (the report, §5.2.1): virtual Erim and Perceptron laser
//! rangefinders that cast rays against the simulated terrain, a virtual sensor replaying stored
//! image sequences, the transform chain every image is tagged with, and the scanner-to-body
//! calibration.
//!
//! # Layout
//!
//! - [`spec`]: [`SensorSpec`] of the Erim and the Perceptron (§2.2): image sizes, fields of
//!   view, range digitisation and wrapping, each pixel's ray, and the check that an image fits
//!   its sensor.
//! - [`frames`]: the chain `locus <- scanner <- body <- global` ([`ImageFrames`]) and the
//!   wire [`Transform`](tca_single_leg_messages::Transform) conversions.
//! - [`noise`]: the seeded range/reflectance noise and the reflectance model.
//! - [`sensor`]: the [`RangeSensor`] trait every sensor implements.
//! - [`scanner`]: [`VirtualScanner`], the ray-casting scanner (rows cast in parallel).
//! - [`stored`]: [`StoredSequence`], the sensor replaying images from disk, and the
//!   `.tcarange` file format.
//! - [`calibration`]: least-squares `scanner <- body` calibration from a target on the leg.
//! - [`legged`]: imaging from a multi-legged robot's body: [`PoseSource`], the scanner mast
//!   of a body of any size ([`BodyDimensions`]) and [`IsmConfig::legged_simulated`].
//! - [`module`]: the ISM on the bus: [`connect`] with an [`IsmConfig`] answers
//!   `acquireImage`, asking the Controller for `bodyPosition` (single leg) or
//!   `legged.bodyPose` (legged robots).
//! - [`error`]: [`IsmError`] and the [`Result`] alias.
//!
//! Images travel as the wire type [`RangeImage`](tca_single_leg_messages::RangeImage): range
//! counts wrapped at the ambiguity interval, reflectance counts (0 = no return), and the three
//! transforms of the chain.

pub mod calibration;
pub mod error;
pub mod frames;
pub mod legged;
pub mod module;
pub mod noise;
pub mod scanner;
pub mod sensor;
pub mod spec;
pub mod stored;

pub use calibration::{
    CalibrationFit, CalibrationPose, Correspondence, calibrate, fit_scanner_from_body,
    locate_target,
};
pub use error::{IsmError, Result};
pub use frames::ImageFrames;
pub use legged::{BodyDimensions, PoseSource, world_from_body};
pub use module::{IsmConfig, connect};
pub use noise::{NoiseModel, ReflectanceModel};
pub use scanner::{SphereTarget, VirtualScanner};
pub use sensor::RangeSensor;
pub use spec::{PixelDirections, SensorSpec};
pub use stored::StoredSequence;
