//! Errors a module sees.

use std::sync::Arc;
use std::time::Duration;

use tca_link::LinkError;
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
    /// Central sent something this library cannot read (a different protocol version, or a
    /// corrupt frame).
    #[error("unreadable answer from central: {0}")]
    Protocol(String),
    /// A module's configuration is wrong (a parameter out of range, a transport setting, a
    /// file that cannot be read); the message says what to fix.
    #[error("{0}")]
    Config(String),
    /// A module's files could not be read or written.
    #[error("{what}: {source}")]
    Io {
        /// What was being done, e.g. `cannot write the state file out/state/controller.json`.
        what: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The module library was used wrongly (a name that is not a valid message name, two
    /// handlers for one message, a class a call does not take).
    #[error("{0}")]
    Usage(String),
}

impl From<LinkError> for ModuleError {
    fn from(e: LinkError) -> Self {
        match e {
            LinkError::Stopped => ModuleError::Disconnected,
            // Over its inbox limit in central: the send is refused, the link stays.
            LinkError::Refused(route) => ModuleError::Route(route),
            LinkError::Open(reason) => ModuleError::Connect(reason),
            LinkError::Config(reason) => ModuleError::Config(reason),
        }
    }
}

/// Result alias of this crate.
pub type Result<T, E = ModuleError> = std::result::Result<T, E>;

/// A handler's failure: a reason sent back to central (and to the sender of a query), and the
/// error that caused it, if any, for the module's own diagnostics.
///
/// Any error converts into it (`?` works in handlers), keeping it as the cause; so does a
/// string via [`HandlerError::new`].
#[derive(Debug, Clone)]
pub struct HandlerError {
    /// What went wrong: what central passes on.
    pub reason: String,
    cause: Option<Arc<dyn std::error::Error + Send + Sync + 'static>>,
}

impl HandlerError {
    /// A failure with the given reason.
    pub fn new(reason: impl Into<String>) -> Self {
        HandlerError {
            reason: reason.into(),
            cause: None,
        }
    }

    /// The error the failure came from, when it came from one.
    pub fn cause(&self) -> Option<&(dyn std::error::Error + Send + Sync + 'static)> {
        self.cause.as_deref()
    }
}

impl PartialEq for HandlerError {
    fn eq(&self, other: &Self) -> bool {
        self.reason == other.reason
    }
}

impl Eq for HandlerError {}

impl std::fmt::Display for HandlerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.reason)
    }
}

impl<E: std::error::Error + Send + Sync + 'static> From<E> for HandlerError {
    fn from(e: E) -> Self {
        HandlerError {
            reason: e.to_string(),
            cause: Some(Arc::new(e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_handler_error_keeps_its_cause() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no map tile");
        let e = HandlerError::from(io);
        assert_eq!(e.reason, "no map tile");
        let cause = e.cause().expect("the io error is kept");
        let io = cause.downcast_ref::<std::io::Error>().expect("as itself");
        assert_eq!(io.kind(), std::io::ErrorKind::NotFound);
        assert!(HandlerError::new("plain").cause().is_none());
    }

    #[test]
    fn link_errors_become_the_module_errors_users_know() {
        assert!(matches!(
            ModuleError::from(LinkError::Stopped),
            ModuleError::Disconnected
        ));
        assert!(matches!(
            ModuleError::from(LinkError::Config("x".into())),
            ModuleError::Config(_)
        ));
    }
}
