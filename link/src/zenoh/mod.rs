//! The zenoh transport's shared half: what runs across processes and machines.
//!
//! Central opens a zenoh session in *router* mode listening on its endpoints
//! ([`DEFAULT_ENDPOINT`] by default); each module opens a *client* session connected to it.
//! A module's link is named by its zenoh session id `<zid>` (see [`keys`] for the key
//! expressions and liveliness tokens).
//!
//! Publications are reliable with blocking congestion control (no frame is silently dropped)
//! and express (sent at once, not batched), and multicast scouting is off: modules find central
//! by its endpoint only.
//!
//! With a zenoh users file ([`router_config_with_users`]) the router requires zenoh
//! user/password authentication (`transport/auth/usrpwd`): a client without a valid login
//! cannot open a session at all. Modules log in with a [`ZenohLogin`].
//!
//! - [`keys`]: the key scheme and liveliness tokens, and how clients retry.
//! - [`exposure`]: whether an endpoint is reachable from other machines.
//! - [`config`]: router and client configuration, the zenoh login, the users file.
//! - [`client`]: [`ZenohTransport`], a module's side.

pub mod client;
pub mod config;
pub mod exposure;
pub mod keys;

pub use client::ZenohTransport;
pub use config::{
    ZenohLogin, client_config, client_config_with_login, router_config, router_config_with_users,
};
pub use exposure::{Exposure, exposure};
pub use keys::{
    ALIVE_KEY_PATTERN, CENTRAL_ALIVE_KEY, DEFAULT_ENDPOINT, RETRY_PERIOD_INIT_MS,
    RETRY_PERIOD_MAX_MS, UP_KEY_PATTERN, alive_key, down_key, up_key, zid_of,
};
