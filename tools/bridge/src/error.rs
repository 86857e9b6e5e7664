//! What can go wrong starting, running or reading a bridge.

use std::path::PathBuf;

/// A bridge's errors; each says what was wrong and what to do.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BridgeError {
    /// The bridge file cannot be read.
    #[error("cannot read the bridge file {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The bridge file or the settings are wrong.
    #[error("{0}")]
    Config(String),
    /// A central could not be joined (not running, refused the bridge, or keeps a simulated
    /// clock).
    #[error("{0}")]
    Connect(String),
    /// Messages the bridge must forward are not registered on the side that handles them.
    #[error("{0}")]
    Missing(String),
    /// The bridge's log cannot be written or read.
    #[error(transparent)]
    Log(#[from] tca_logs::LogError),
    /// A recorded session cannot be played back.
    #[error("{0}")]
    Playback(String),
}

/// Results of this crate.
pub type Result<T, E = BridgeError> = std::result::Result<T, E>;
