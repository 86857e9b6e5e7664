//! The local transport: central and modules on one machine, over a Unix-domain socket.
//!
//! Endpoints are `local` and `local/NAME` (several centrals on one machine); each names a
//! socket in a per-user runtime directory ([`endpoint`]). Frames are length-prefixed
//! ([`frame`]). Who may connect is decided twice: by the file system (the directory is 0700 and
//! the socket 0600, so other users cannot reach it) and by the kernel's word on the peer's user
//! id (`SO_PEERCRED`), checked against a [`PeerPolicy`] (central's own user, and any user ids
//! it is told to admit). Central's policy file then checks the module's identity at hello, as
//! over any transport.
//!
//! It keeps what the zenoh transport promises: a module that exits or is killed closes its
//! socket and central closes its link at once; a central that dies closes every socket, its
//! modules hear [`Presence::Down`](crate::Presence::Down) at once and connect again until a
//! central is back ([`client`]); each link has central's bounded inbox and outbox like any
//! other ([`server`]).
//!
//! - [`endpoint`]: [`LocalEndpoint`], the runtime directory and its checks.
//! - [`frame`]: the greeting and the length-prefixed frames.
//! - [`peer`]: who may connect, [`PeerPolicy`].
//! - [`server`]: [`LocalListener`], central's side, and [`Attach`], what it needs of central.
//! - [`client`]: [`LocalTransport`], a module's side.

pub mod client;
pub mod endpoint;
pub mod frame;
pub mod peer;
pub mod server;

pub use client::LocalTransport;
pub use endpoint::{DEFAULT_LOCAL_NAME, LOCAL_PROTOCOL, LocalEndpoint, current_uid, runtime_dir};
pub use peer::PeerPolicy;
pub use server::{Attach, LocalListener};

#[cfg(test)]
mod tests;
