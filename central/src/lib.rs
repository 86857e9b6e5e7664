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
//! - [`journal`]: the journal that lets a central restarted after a crash come back whole (task
//!   trees, queues, the goals handed to modules), and how nothing is done twice.
//! - [`runtime`]: the async driver that owns the core, feeds it events from every link and
//!   carries out its actions; [`CentralHandle`] to hand in-process modules their transport
//!   ([`CentralHandle::in_process`]) and to inspect central. Each link's bounded inbox (served
//!   round robin, so a flooding module delays only itself) and outbox (a module that does not
//!   keep up gets no new work, one that stops reading is disconnected) are `tca-link`'s.
//! - `zenoh_router`: central as a zenoh router; modules are zenoh clients (the key scheme
//!   and configuration are `tca_link::zenoh`'s).
//! - Local sockets (`local`, `local/NAME` in [`StartOptions::listen`]): `tca_link::local`'s
//!   listener, opening links through the runtime; any mix of local and zenoh endpoints is
//!   served by one central.

pub mod config;
pub mod core;
pub mod journal;
pub mod policy;
pub mod process;
pub mod runtime;
mod zenoh_router;

pub use config::CentralConfig;
pub use core::{Action, Central, Event, LinkId};
pub use policy::{Policy, PolicyError};
pub use runtime::{CentralHandle, HighWater, Restored, RunningCentral, StartOptions, Stats, start};
pub use tca_link::zenoh::DEFAULT_ENDPOINT;

/// Errors of central's runtime.
#[derive(Debug, thiserror::Error)]
pub enum CentralError {
    /// The traffic log could not be written.
    #[error("traffic log: {0}")]
    Log(#[from] tca_logs::LogError),
    /// zenoh could not start or listen.
    #[error("zenoh: {0}; check the endpoint (e.g. tcp/127.0.0.1:7447) and that the port is free")]
    Zenoh(String),
    /// A transport setting is wrong, or a link could not be opened.
    #[error(transparent)]
    Link(#[from] tca_link::LinkError),
    /// Central has stopped.
    #[error("central has stopped")]
    Stopped,
    /// Central was asked to listen where other machines can reach it, with no policy.
    #[error(
        "refusing to listen on {0} (reachable from other machines) with no policy: any process \
         that finds central could join under any name and send anything. Give a policy \
         (--policy FILE: identities with secrets, what each may register and send; see \
         policy.example.toml and the README's security section), listen on a loopback address \
         (tcp/127.0.0.1:7447) or a local socket (local), or, on a network you trust, say \
         --insecure"
    )]
    Insecure(String),
    /// Central was asked to listen where other machines can reach it with a policy that
    /// authenticates no zenoh client, so its router cannot keep the modules apart.
    #[error(
        "refusing to listen on {0} (reachable from other machines) with a policy that \
         authenticates no zenoh client: the router cannot tell clients apart, so any process \
         that reaches it could read every module's frames and publish on their keys. Add \
         `zenoh_users_file` or `[transport.tls]` to the policy's [transport] section (see \
         policy.example.toml and the README's security section), listen on a loopback address \
         (tcp/127.0.0.1:7447) or a local socket (local), or, on a network you trust, say \
         --insecure"
    )]
    Unisolated(String),
    /// The policy file could not be loaded.
    #[error(transparent)]
    Policy(#[from] PolicyError),
    /// The journal could not be opened, restored or started.
    #[error(transparent)]
    Journal(#[from] journal::JournalError),
}

/// Result alias of this crate.
pub type Result<T, E = CentralError> = std::result::Result<T, E>;
