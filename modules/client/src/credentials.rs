//! Logging in: the identity and secret a module presents in its hello, checked by central
//! against its policy file, and the zenoh login of the transport.
//!
//! Both can be given in code ([`ModuleBuilder::identity`](crate::ModuleBuilder::identity),
//! [`Connector::zenoh_with_login`](crate::Connector::zenoh_with_login)) or, for built-in
//! modules and command-line tools, by environment variables: `TCA_IDENTITY` and `TCA_SECRET`
//! for the hello, `TCA_ZENOH_USER` and `TCA_ZENOH_PASSWORD` for zenoh, `TCA_ZENOH_TLS_CERT`,
//! `TCA_ZENOH_TLS_KEY` and `TCA_ZENOH_TLS_CA` for a TLS certificate. Code wins over the
//! environment. A zenoh login or certificate proves the identity it names by itself: such a
//! module's hello needs no secret.

use tca_messages::control::{AuthHello, ControlRequest, Credentials, Hello};

pub use tca_link::{TlsFiles, ZenohLogin};

/// The credentials named by `TCA_IDENTITY` and `TCA_SECRET`, when both are set.
pub fn credentials_from_env() -> Option<Credentials> {
    let identity = std::env::var("TCA_IDENTITY").ok()?;
    let secret = std::env::var("TCA_SECRET").ok()?;
    Some(Credentials { identity, secret })
}

/// The hello: `tca.helloAuth` with credentials, else `tca.hello`.
pub(crate) fn hello_request(hello: Hello, credentials: Option<Credentials>) -> ControlRequest {
    match credentials {
        Some(credentials) => ControlRequest::HelloAuth(AuthHello { hello, credentials }),
        None => ControlRequest::Hello(hello),
    }
}
