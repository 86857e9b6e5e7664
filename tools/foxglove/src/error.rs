//! Errors.

use std::path::PathBuf;

/// What can go wrong exporting or serving.
#[derive(Debug, thiserror::Error)]
pub enum FoxgloveError {
    /// A file could not be created or written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The MCAP writer failed.
    #[error("cannot write the MCAP file: {0}")]
    Write(String),
    /// The WebSocket server could not start.
    #[error(
        "cannot start the Foxglove WebSocket server: {0}; check that the address is free (another `tca foxglove`?) or choose another with --port"
    )]
    Server(String),
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, FoxgloveError>;
