//! Errors of the Perception Display Manager.

/// What can go wrong drawing a map.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PdmError {
    /// The map grid is not consistent.
    #[error("the map grid cannot be drawn: {0}")]
    BadGrid(String),
    /// The picture would be too large.
    #[error(
        "a {nx} x {ny}-cell map is too large to draw (at most {limit} cells a side); ask for a \
         coarser resolution"
    )]
    TooLarge {
        /// Cells along X.
        nx: u32,
        /// Cells along Y.
        ny: u32,
        /// Largest side drawn.
        limit: u32,
    },
    /// The map could not be obtained from the LTM Manager.
    #[error("the LTM Manager did not give the map: {0}")]
    Map(String),
    /// PNG encoding failed.
    #[error("PNG encoding failed: {0}")]
    Encode(String),
    /// The picture could not be encoded or written.
    #[error(transparent)]
    Picture(#[from] tca_canvas::CanvasError),
}

/// Result alias of this crate.
pub type Result<T, E = PdmError> = std::result::Result<T, E>;
