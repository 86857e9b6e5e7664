//! TCA links: what central and a module share to talk to each other.
//!
//! A *link* joins one module to central. Frames (encoded [envelopes](tca_messages::Envelope))
//! travel up it into the link's bounded [`Inbox`] in central, and down it through the link's
//! bounded outbox to the module's [`FrameReceiver`]. This crate holds both ends and the
//! transports that carry them, so that the module library never links central itself and
//! central never links the module library.
//!
//! A module opens a link through a [`Transport`]: [`InProcTransport`] (central in the same
//! process, over tokio channels; central hands one out), [`LocalTransport`] (central on this
//! machine, over a Unix socket) or [`ZenohTransport`] (central elsewhere, over zenoh). Another
//! transport slots in by implementing the trait. [`transport_for`] picks one by endpoint.
//!
//! # Layout
//!
//! - [`transport`]: the [`Transport`] interface and the [`Link`] a module gets from it:
//!   [`FrameSender`], [`FrameReceiver`], central's [`Presence`].
//! - [`inbox`]: [`Inbox`], a link's bounded queue of frames central has not handled yet.
//! - [`outbox`]: [`Gauge`] and [`FrameReceiver`], a link's bounded queue of frames the module
//!   has not taken yet.
//! - [`hub`]: [`Hub`], how the queues wake whoever drives them (central's driver).
//! - [`inproc`]: the in-process transport: [`InProcTransport`], [`InProcLink`],
//!   [`InProcSender`].
//! - [`local`]: the same-machine transport over a Unix socket: [`LocalTransport`] (a
//!   module's side), [`LocalListener`] (central's side), [`LocalEndpoint`], [`PeerPolicy`].
//! - [`net`]: free loopback ports and endpoints.
//! - [`zenoh`](mod@zenoh): the zenoh key scheme and liveliness tokens, router and client
//!   configuration, the zenoh login, mutual TLS ([`TlsFiles`]), the router's access control
//!   that confines each identity to its own keys, and [`ZenohTransport`], a module's client
//!   side.
//! - [`error`](mod@error): [`LinkError`].

pub mod error;
pub mod hub;
pub mod inbox;
pub mod inproc;
pub mod local;
pub mod net;
pub mod outbox;
pub mod transport;
pub mod zenoh;

pub use error::{LinkError, Result};
pub use hub::{Hub, LinkSignal};
pub use inbox::{Inbox, InboxUse, MAX_REFUSALS, Taken};
pub use inproc::{InProcLink, InProcSender, InProcTransport};
pub use local::{LocalEndpoint, LocalListener, LocalTransport, PeerPolicy};
pub use outbox::{FrameReceiver, Gauge, OutboxLimits, OutboxUse};
pub use transport::{FrameSender, Link, Presence, SendFrame, Transport};
pub use zenoh::{TlsFiles, ZenohLogin, ZenohTransport};

/// A link's number, given by central when the link opens. It is also the high half of every
/// message id the module on it sends.
pub type LinkId = u32;

/// The transport that reaches central at `endpoint`: [`LocalTransport`] for `local` and
/// `local/NAME`, [`ZenohTransport`] for anything else (`tcp/HOST:PORT`, `unixsock-stream/PATH`).
pub fn transport_for(endpoint: &str) -> Result<std::sync::Arc<dyn Transport>> {
    if LocalEndpoint::is_local(endpoint) {
        Ok(std::sync::Arc::new(LocalTransport::new(endpoint)?))
    } else {
        Ok(std::sync::Arc::new(ZenohTransport::new(vec![
            endpoint.to_owned(),
        ])))
    }
}

#[cfg(test)]
mod access_control_tests;
