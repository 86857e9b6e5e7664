//! Errors of writing pictures.

use std::path::PathBuf;

/// Why a picture could not be encoded or written.
#[derive(Debug, thiserror::Error)]
pub enum CanvasError {
    /// PNG encoding failed.
    #[error("PNG encoding failed: {0}")]
    Encode(#[from] png::EncodingError),
    /// Writing the file failed.
    #[error(
        "cannot write the picture to {}: {source}; check the directory exists and is writable",
        path.display()
    )]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}
