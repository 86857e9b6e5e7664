//! Errors of the Imaging Sensor Manager.

use std::path::PathBuf;

use tca_single_leg_messages::SensorKind;

/// What can go wrong acquiring, reading, checking or calibrating images.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IsmError {
    /// An image's width or height is not its sensor's.
    #[error(
        "a {sensor:?} image must be {expected_width} x {expected_height} pixels (columns x rows) \
         but this one is {width} x {height}; check that the image was made for this sensor"
    )]
    ImageSize {
        /// The sensor the image claims to come from.
        sensor: SensorKind,
        /// The sensor's columns.
        expected_width: u32,
        /// The sensor's rows.
        expected_height: u32,
        /// The image's columns.
        width: u32,
        /// The image's rows.
        height: u32,
    },
    /// One of an image's pixel arrays has the wrong length.
    #[error(
        "the {channel} channel of a {width} x {height} image must hold {expected} pixels but holds \
         {got}; the image is truncated or corrupt"
    )]
    ImageData {
        /// `"range"` or `"reflectance"`.
        channel: &'static str,
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
        /// `width * height`.
        expected: usize,
        /// Pixels present.
        got: usize,
    },
    /// An image's sensor parameter differs from its sensor's.
    #[error(
        "the image's {parameter} is {got} but a {sensor:?}'s is {expected}; the image does not \
         match its sensor"
    )]
    ImageParameter {
        /// The sensor.
        sensor: SensorKind,
        /// Which parameter.
        parameter: &'static str,
        /// The sensor's value.
        expected: f64,
        /// The image's value.
        got: f64,
    },
    /// A pixel count is beyond what the sensor digitises.
    #[error(
        "pixel {index} of the {channel} channel is {value}, above the sensor's largest count \
         {max}; the image is corrupt"
    )]
    CountOutOfRange {
        /// `"range"` or `"reflectance"`.
        channel: &'static str,
        /// Row-major pixel index.
        index: usize,
        /// The count.
        value: u16,
        /// The largest count the sensor produces.
        max: u16,
    },
    /// A transform is not a rigid motion (rotation and translation).
    #[error("the {which} transform is not a rigid transform: {reason}")]
    BadTransform {
        /// Which transform.
        which: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A configuration value is out of range.
    #[error("invalid ISM configuration: {0}")]
    Config(String),
    /// No sensor of this kind is configured.
    #[error("no {0:?} sensor is configured in this ISM; configure one or ask for another sensor")]
    NoSuchSensor(SensorKind),
    /// A stored image sequence could not be used.
    #[error("stored image sequence {dir}: {reason}")]
    Sequence {
        /// The directory.
        dir: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A stored image file is not valid.
    #[error("stored image {path}: {reason}")]
    ImageFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The calibration target could not be found in an image.
    #[error(
        "the calibration target was not found in image {sequence}: {reason}; check that the \
         target is in the sensor's field of view and not hidden"
    )]
    TargetNotFound {
        /// The image's sequence number.
        sequence: u64,
        /// Why not.
        reason: String,
    },
    /// The calibration data cannot determine the transform.
    #[error("calibration is not possible: {0}")]
    Calibration(String),
}

/// Result alias of this crate.
pub type Result<T, E = IsmError> = std::result::Result<T, E>;
