//! TCA central control: the process every message flows through (§3 of the report).
//!
//! Central forwards each message by name to the module that registered it, decides *when* to
//! forward goals and commands (task-tree constraints and module capacity), holds messages for
//! modules that are down, answers errors to senders and logs all traffic.
//!
//! # Layout
//!
//! - [`core`]: the sans-I/O state machine, `handle(event) -> actions`; all of central's logic.
//! - [`config`]: limits and defaults ([`CentralConfig`]), including per-module resource limits.
//! - [`policy`]: the registration policy file: identities, secrets, who may register and send
//!   what ([`Policy`]).
//! - [`runtime`]: the async driver that owns the core, feeds it events from every link and
//!   carries out its actions; [`CentralHandle`] to connect in-process modules and inspect it.
//! - `inbox`: each link's bounded inbox of frames not yet handled, served round robin so a
//!   flooding module delays only itself.
//! - [`outbox`]: each link's bounded outbox of frames sent and not yet taken; a module that
//!   does not keep up gets no new work, and one that stops reading is disconnected.
//! - [`inproc`]: the in-process transport (tokio channels), the embedded default.
//! - [`zenoh_transport`]: the zenoh transport: central as a zenoh router, modules as clients;
//!   key-expression conventions shared with the module library.

pub mod config;
pub mod core;
mod inbox;
pub mod inproc;
pub mod outbox;
pub mod policy;
pub mod runtime;
pub mod zenoh_transport;

pub use config::CentralConfig;
pub use core::{Action, Central, Event, LinkId};
pub use inproc::InProcLink;
pub use outbox::FrameReceiver;
pub use policy::{Policy, PolicyError};
pub use runtime::{CentralHandle, HighWater, RunningCentral, StartOptions, Stats, start};

/// Errors of central's runtime.
#[derive(Debug, thiserror::Error)]
pub enum CentralError {
    /// The traffic log could not be written.
    #[error("traffic log: {0}")]
    Log(#[from] tca_logs::LogError),
    /// zenoh could not start or listen.
    #[error("zenoh: {0}; check the endpoint (e.g. tcp/127.0.0.1:7447) and that the port is free")]
    Zenoh(String),
    /// Central has stopped.
    #[error("central has stopped")]
    Stopped,
    /// Central refused a frame (an over-limit inbox).
    #[error(transparent)]
    Refused(tca_messages::RouteError),
    /// The policy file could not be loaded.
    #[error(transparent)]
    Policy(#[from] PolicyError),
}

/// Result alias of this crate.
pub type Result<T, E = CentralError> = std::result::Result<T, E>;
