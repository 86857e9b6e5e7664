//! Why danger parameters or a danger map could not be made.

use thiserror::Error;

/// Why danger parameters could not be read or a danger map could not be made.
#[derive(Debug, Error)]
pub enum DangerError {
    /// A parameter is out of its range.
    #[error("danger parameter `{name}` = {value} is not valid: {expected}")]
    BadParam {
        /// The parameter's name, as in the file.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// The parameter file could not be read.
    #[error("cannot read the danger parameters {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The parameter file is not valid TOML of the expected fields.
    #[error(
        "the danger parameters {path} are not valid: {source}; see nav/danger-map/robots/ for examples"
    )]
    Parse {
        /// The file.
        path: String,
        /// Why.
        source: Box<toml::de::Error>,
    },
    /// The map's grid could not be made.
    #[error("the danger map's grid is not valid: {0}")]
    Grid(#[from] tca_robot::GridError),
}
