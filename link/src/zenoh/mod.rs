//! The zenoh transport's shared half: what runs across processes and machines.
//!
//! Central opens a zenoh session in *router* mode listening on its endpoints
//! ([`DEFAULT_ENDPOINT`] by default); each module opens a *client* session connected to it.
//! A module's link is named by its identity and its zenoh session id (see [`keys`] for the key
//! expressions and liveliness tokens).
//!
//! Publications are reliable with blocking congestion control (no frame is silently dropped)
//! and express (sent at once, not batched), and multicast scouting is off: modules find central
//! by its endpoint only.
//!
//! Central's router can authenticate clients ([`RouterSecurity`]): with a zenoh users file
//! (zenoh's `transport/auth/usrpwd`) a client without a valid login cannot open a session;
//! with mutual TLS ([`TlsFiles`], `tls/HOST:PORT` endpoints) a client without a certificate
//! signed by central's CA cannot either. Either way the router's access control ([`acl`])
//! confines each identity (zenoh user, certificate common name) to its own keys. Modules log
//! in with a [`ZenohLogin`] and present their certificate with [`TlsFiles`].
//!
//! - [`keys`]: the key scheme and liveliness tokens, and how clients retry.
//! - [`acl`]: the access control that confines each identity to its keys.
//! - [`tls`]: the certificate files of a mutual-TLS link.
//! - [`exposure`]: whether an endpoint is reachable from other machines.
//! - [`config`]: router and client configuration, the zenoh login, the users file.
//! - [`client`]: [`ZenohTransport`], a module's side.

pub mod acl;
pub mod client;
pub mod config;
pub mod exposure;
pub mod keys;
pub mod tls;

pub use acl::{Authenticators, access_control};
pub use client::ZenohTransport;
pub use config::{
    RouterSecurity, ZenohLogin, client_config, client_config_secured, client_config_with_login,
    router_config, router_config_secured,
};
pub use exposure::{Exposure, exposure};
pub use keys::{
    ALIVE_KEY_PATTERN, CENTRAL_ALIVE_KEY, DEFAULT_ENDPOINT, NO_IDENTITY, RETRY_PERIOD_INIT_MS,
    RETRY_PERIOD_MAX_MS, UP_KEY_PATTERN, alive_key, check_identity_name, down_key, link_of, up_key,
    up_key_pattern,
};
pub use tls::TlsFiles;
