//! Errors of the Local Terrain Map Manager.

use std::path::PathBuf;

/// What can go wrong building, merging, scrolling or querying maps.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LtmError {
    /// The range image is not valid for its sensor (size, parameters, transforms).
    #[error("range image refused: {0}")]
    Image(#[from] tca_ism::IsmError),
    /// A region has fewer than three corners.
    #[error(
        "a region needs at least three polygon corners, got {0}; give the corners of the area \
         wanted, in order"
    )]
    TooFewCorners(usize),
    /// A polygon corner is not a finite point.
    #[error("polygon corner {index} is ({x_m}, {y_m}), not a finite point")]
    BadCorner {
        /// Index of the corner.
        index: usize,
        /// Its X, metres.
        x_m: f64,
        /// Its Y, metres.
        y_m: f64,
    },
    /// A polygon corner is so far away that its cell index would overflow.
    #[error(
        "polygon corner ({x_m}, {y_m}) is beyond the map's reach at {resolution_m} m cells; \
         give coordinates within {limit_m} m of the origin"
    )]
    CornerTooFar {
        /// Its X, metres.
        x_m: f64,
        /// Its Y, metres.
        y_m: f64,
        /// The resolution asked for.
        resolution_m: f64,
        /// Largest coordinate accepted at that resolution, metres.
        limit_m: f64,
    },
    /// An image's transforms put the scanner absurdly far away.
    #[error(
        "the image's transforms put the scanner at ({x_m:.1}, {y_m:.1}, {z_m:.1}) m, more than \
         {limit_m} m from the world origin; check the calibration and the body pose"
    )]
    ScannerTooFar {
        /// Scanner X, metres.
        x_m: f64,
        /// Scanner Y, metres.
        y_m: f64,
        /// Scanner Z, metres.
        z_m: f64,
        /// Largest distance accepted, metres.
        limit_m: f64,
    },
    /// A polygon encloses no area.
    #[error(
        "the polygon's corners are all on one line (zero area); give corners that enclose the \
         region"
    )]
    ZeroArea,
    /// A resolution is zero, negative or not a number.
    #[error("{what} resolution {value} m is not valid; give a finite cell size greater than zero")]
    BadResolution {
        /// Which resolution.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// A region would need too many cells.
    #[error(
        "the region needs {nx} x {ny} cells at {resolution_m} m, more than the limit of {limit}; \
         ask for a smaller region or a coarser resolution"
    )]
    RegionTooLarge {
        /// Cells along X.
        nx: u64,
        /// Cells along Y.
        ny: u64,
        /// The resolution asked for.
        resolution_m: f64,
        /// Largest number of cells served.
        limit: usize,
    },
    /// A map patch's resolution differs from the map's.
    #[error(
        "a map patch at {patch_m} m cannot be merged into the map at {map_m} m; build patches at \
         the map's resolution"
    )]
    ResolutionMismatch {
        /// The patch's resolution.
        patch_m: f64,
        /// The map's resolution.
        map_m: f64,
    },
    /// The LTM Manager does not make maps of this kind.
    #[error(
        "the LTM Manager does not make {0:?} maps (it makes elevation, elevation with \
         uncertainty, footfall and slope maps); reachability maps come from the Leg Recovery \
         Planner (legReachability)"
    )]
    UnsupportedKind(tca_single_leg_messages::MapKind),
    /// A configuration value is out of range.
    #[error("invalid LTM configuration: {0}")]
    Config(String),
    /// Reading or writing a map tile failed.
    #[error("map tile store {path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A stored map tile is not valid.
    #[error("map tile {path} is not valid: {reason}; delete it or use another store directory")]
    TileFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// Result alias of this crate.
pub type Result<T, E = LtmError> = std::result::Result<T, E>;

/// Checks a resolution.
pub(crate) fn check_resolution(what: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(LtmError::BadResolution { what, value })
    }
}
