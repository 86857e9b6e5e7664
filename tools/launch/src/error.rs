//! Errors of launch files and of starting what they name.

use std::path::PathBuf;

use thiserror::Error;

/// What can go wrong with a launch file.
#[derive(Debug, Error)]
pub enum LaunchError {
    /// The file cannot be read.
    #[error("cannot read launch file {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a valid launch file (TOML syntax, an unknown key, a missing value).
    #[error("launch file {path}: {reason}")]
    Invalid {
        /// The file (`-` for text given directly).
        path: PathBuf,
        /// What is wrong, and where.
        reason: String,
    },
    /// A module cannot be started.
    #[error("cannot start module {module}: {source}")]
    Spawn {
        /// The module.
        module: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The previous traffic log cannot be set aside.
    #[error("cannot keep the previous log: {0}")]
    Log(#[from] tca_logs::LogError),
    /// Central cannot start (or stop cleanly).
    #[error("central: {0}")]
    Central(#[from] tca_central::CentralError),
    /// The policy file cannot be loaded.
    #[error("cannot load the policy: {0}")]
    Policy(#[from] tca_central::PolicyError),
}
