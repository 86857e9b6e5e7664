//! How a module reaches central: a [`Connector`] wraps one [`Transport`] of `tca-link`.

use std::sync::Arc;

use tca_link::{InProcTransport, Link, Transport, ZenohLogin, ZenohTransport};

use crate::error::{ModuleError, Result};

/// How a module reaches central. The same module code runs on any transport:
///
/// - in-process, for a central in this process: `Connector::from(central.in_process())`;
/// - over zenoh, for a central elsewhere: [`Connector::zenoh`]`("tcp/HOST:7447")`, logging in
///   with `TCA_ZENOH_USER`/`TCA_ZENOH_PASSWORD` when they are set, or
///   [`Connector::zenoh_with_login`];
/// - any other [`Transport`]: [`Connector::new`].
#[derive(Clone, Debug)]
pub struct Connector(Arc<dyn Transport>);

impl Connector {
    /// A connector over `transport`.
    pub fn new(transport: impl Transport) -> Self {
        Connector(Arc::new(transport))
    }

    /// A zenoh connector for one endpoint (e.g. `tcp/127.0.0.1:7447`).
    pub fn zenoh(endpoint: impl Into<String>) -> Self {
        Self::new(ZenohTransport::new(vec![endpoint.into()]))
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

    /// Describes where it connects, for messages.
    pub fn describe(&self) -> String {
        self.0.describe()
    }

    /// Opens a new link to central.
    pub(crate) async fn open(&self) -> Result<Link> {
        self.0.open().await.map_err(ModuleError::from)
    }
}

impl From<InProcTransport> for Connector {
    fn from(transport: InProcTransport) -> Self {
        Connector::new(transport)
    }
}

impl From<ZenohTransport> for Connector {
    fn from(transport: ZenohTransport) -> Self {
        Connector::new(transport)
    }
}
