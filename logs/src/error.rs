//! Errors of the traffic log.

use std::path::PathBuf;

use thiserror::Error;

/// What can go wrong writing or reading a log.
#[derive(Debug, Error)]
pub enum LogError {
    /// The file could not be created, opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The MCAP container is damaged.
    #[error("{path}: not a readable tca traffic log: {reason}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
    /// The writer failed.
    #[error("writing the traffic log: {0}")]
    Write(String),
    /// The writer thread stopped.
    #[error("the log writer stopped unexpectedly: {0}")]
    WriterGone(String),
}

/// Result alias of this crate.
pub type Result<T, E = LogError> = std::result::Result<T, E>;
