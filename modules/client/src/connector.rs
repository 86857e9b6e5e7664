//! How a module reaches central: a [`Connector`] wraps one [`Transport`] of `tca-link`.

use std::sync::Arc;

use tca_link::{
    InProcTransport, Link, LinkError, LocalEndpoint, LocalTransport, TlsFiles, Transport,
    ZenohLogin, ZenohTransport,
};

use crate::error::{ModuleError, Result};

/// How a module reaches central. The same module code runs on any transport:
///
/// - in-process, for a central in this process: `Connector::from(central.in_process())`;
/// - over a Unix socket, for a central on this machine: [`Connector::local`]`("local")` (or
///   `local/NAME`);
/// - over zenoh, for a central elsewhere: [`Connector::zenoh`]`("tcp/HOST:7447")`, logging in
///   with `TCA_ZENOH_USER`/`TCA_ZENOH_PASSWORD` when they are set, or
///   [`Connector::zenoh_with_login`]; with mutual TLS (`tls/HOST:7448`), presenting the
///   certificate of `TCA_ZENOH_TLS_CERT`/`TCA_ZENOH_TLS_KEY`/`TCA_ZENOH_TLS_CA` when they are
///   set, or [`Connector::zenoh_with_tls`];
/// - by endpoint, whichever of the two it names: [`Connector::endpoint`];
/// - any other [`Transport`]: [`Connector::new`].
#[derive(Clone, Debug)]
pub struct Connector(Arc<dyn Transport>);

impl Connector {
    /// A connector over `transport`.
    pub fn new(transport: impl Transport) -> Self {
        Connector(Arc::new(transport))
    }

    /// A connector for one endpoint: a local one (`local`, `local/NAME`) goes over central's
    /// Unix socket, any other (e.g. `tcp/127.0.0.1:7447`) over zenoh. A malformed local
    /// endpoint makes every connection fail with an error saying what is wrong.
    pub fn endpoint(endpoint: impl Into<String>) -> Self {
        let endpoint = endpoint.into();
        if LocalEndpoint::is_local(&endpoint) {
            Self::local(endpoint)
        } else {
            Self::new(ZenohTransport::new(vec![endpoint]))
        }
    }

    /// A connector to central's local socket `endpoint` (`local` or `local/NAME`).
    pub fn local(endpoint: impl Into<String>) -> Self {
        let endpoint = endpoint.into();
        match LocalTransport::new(&endpoint) {
            Ok(t) => Self::new(t),
            Err(e) => Self::new(Unusable {
                endpoint,
                reason: e.to_string(),
            }),
        }
    }

    /// A connector for one endpoint (e.g. `tcp/127.0.0.1:7447`), over zenoh; a local endpoint
    /// (`local`, `local/NAME`) is served by the local link instead, as [`Connector::endpoint`].
    pub fn zenoh(endpoint: impl Into<String>) -> Self {
        Self::endpoint(endpoint)
    }

    /// A zenoh connector for one endpoint that logs in with a zenoh user and password
    /// (central's router requires it when its policy names a zenoh users file).
    pub fn zenoh_with_login(
        endpoint: impl Into<String>,
        user: impl Into<String>,
        password: impl Into<String>,
    ) -> Self {
        Self::new(ZenohTransport::with_login(
            vec![endpoint.into()],
            ZenohLogin::new(user, password),
        ))
    }

    /// A zenoh connector for one endpoint (`tls/HOST:PORT`) that presents the certificate of
    /// `tls` and checks central's against its CA (central requires it when its policy has
    /// `[transport.tls]`); the certificate's common name is the module's identity.
    pub fn zenoh_with_tls(endpoint: impl Into<String>, tls: TlsFiles) -> Self {
        Self::new(ZenohTransport::new(vec![endpoint.into()]).tls(tls))
    }

    /// Describes where it connects, for messages.
    pub fn describe(&self) -> String {
        self.0.describe()
    }

    /// Opens a new link to central.
    pub(crate) async fn open(&self) -> Result<Link> {
        self.0.open().await.map_err(ModuleError::from)
    }
}

/// A transport for an endpoint that cannot be used: every connection fails, saying why.
#[derive(Debug)]
struct Unusable {
    endpoint: String,
    reason: String,
}

impl Transport for Unusable {
    fn open(
        &self,
    ) -> std::pin::Pin<Box<dyn std::future::Future<Output = tca_link::Result<Link>> + Send + '_>>
    {
        let reason = self.reason.clone();
        Box::pin(async move { Err(LinkError::Config(reason)) })
    }

    fn describe(&self) -> String {
        format!("central at {} (unusable endpoint)", self.endpoint)
    }
}

impl From<InProcTransport> for Connector {
    fn from(transport: InProcTransport) -> Self {
        Connector::new(transport)
    }
}

impl From<LocalTransport> for Connector {
    fn from(transport: LocalTransport) -> Self {
        Connector::new(transport)
    }
}

impl From<ZenohTransport> for Connector {
    fn from(transport: ZenohTransport) -> Self {
        Connector::new(transport)
    }
}
