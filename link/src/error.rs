//! Errors of links.

use tca_messages::RouteError;
use thiserror::Error;

/// What can go wrong on a link.
#[derive(Debug, Error)]
pub enum LinkError {
    /// Central (or whatever drives the link's queues) has stopped; the link is closed.
    #[error("central has stopped; the link is closed")]
    Stopped,
    /// Central refused the frame: the link's inbox is over its limit
    /// ([`RouteError::OverLimit`]). The link stays open; send again later.
    #[error(transparent)]
    Refused(RouteError),
    /// The link could not be opened (no central at the endpoint, a refused login).
    #[error("{0}")]
    Open(String),
    /// A transport setting is wrong (an endpoint without a protocol, an unreadable zenoh users
    /// file).
    #[error("{0}")]
    Config(String),
}

/// Result alias of this crate.
pub type Result<T, E = LinkError> = std::result::Result<T, E>;
