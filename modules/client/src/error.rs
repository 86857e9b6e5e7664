//! Errors a module sees.

use std::time::Duration;

use tca_messages::{CodecError, FormatError, RouteError};
use thiserror::Error;

/// What can go wrong talking to central.
#[derive(Debug, Error)]
pub enum ModuleError {
    /// The connection to central could not be made.
    #[error("cannot connect to central: {0}")]
    Connect(String),
    /// Central refused this module (name taken, bad hello, policy).
    #[error("central refused module {module}: {reason}")]
    Refused {
        /// The module.
        module: String,
        /// Why.
        reason: String,
    },
    /// Central refused some registrations.
    #[error("central refused registrations: {}", .0.join("; "))]
    Registration(Vec<String>),
    /// A message type's data format could not be derived.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// Data could not be encoded or decoded.
    #[error(transparent)]
    Codec(#[from] CodecError),
    /// Central answered with a routing error.
    #[error(transparent)]
    Route(#[from] RouteError),
    /// The handler of a query failed.
    #[error("{name} failed in its handler: {reason}")]
    HandlerFailed {
        /// The message name.
        name: String,
        /// The handler's reason.
        reason: String,
    },
    /// No answer within the timeout.
    #[error(
        "no answer to {name} within {timeout:?}; its handler may be slow or stuck (raise the timeout or check the handler)"
    )]
    Timeout {
        /// The message name.
        name: String,
        /// The timeout.
        timeout: Duration,
    },
    /// The link to central is closed.
    #[error("the link to central is closed (central stopped or the network failed)")]
    Disconnected,
    /// Central went away (its process died or the network dropped) while this module was
    /// connected over zenoh. What was in flight is lost; the module rejoins central by itself
    /// when it is back (see [`crate::Module::wait_online`]).
    #[error(
        "central went away (its process stopped or the network dropped); what was in flight is lost. \
         The module reconnects and registers again by itself when central is back: restart central \
         (same endpoint) and send again"
    )]
    CentralLost,
    /// The module was used wrongly.
    #[error("{0}")]
    Usage(String),
}

/// Result alias of this crate.
pub type Result<T, E = ModuleError> = std::result::Result<T, E>;

/// A handler's failure: a reason sent back to central (and to the sender of a query).
///
/// Any error converts into it (`?` works in handlers); so does a string via [`HandlerError::new`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HandlerError {
    /// What went wrong.
    pub reason: String,
}

impl HandlerError {
    /// A failure with the given reason.
    pub fn new(reason: impl Into<String>) -> Self {
        HandlerError {
            reason: reason.into(),
        }
    }
}

impl std::fmt::Display for HandlerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.reason)
    }
}

impl<E: std::error::Error> From<E> for HandlerError {
    fn from(e: E) -> Self {
        HandlerError::new(e.to_string())
    }
}
