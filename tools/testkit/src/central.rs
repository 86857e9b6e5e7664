//! A central for one test, over either transport.

use tca_central::{RunningCentral, StartOptions, Stats};
use tca_module::Connector;

use crate::{free_endpoint, within};

/// Which transport a test runs over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportKind {
    /// Central in the test's process, over tokio channels.
    InProcess,
    /// Central listening on a free loopback port; modules are zenoh clients.
    Zenoh,
}

/// Both transports, for tests that must hold over each.
pub const BOTH: [TransportKind; 2] = [TransportKind::InProcess, TransportKind::Zenoh];

/// A central for one test; its runtime task ends with the test.
pub struct TestCentral {
    /// The running central (`None` once stopped).
    pub central: Option<RunningCentral>,
    /// How the test's modules reach it.
    pub connector: Connector,
    /// The zenoh endpoint it listens on, over zenoh.
    pub endpoint: Option<String>,
}

impl TestCentral {
    /// A central with the default options.
    pub async fn start(transport: TransportKind) -> Self {
        Self::start_with(transport, StartOptions::default()).await
    }

    /// A central with `options` (over zenoh it listens on a free loopback port instead of
    /// `options.listen`).
    pub async fn start_with(transport: TransportKind, mut options: StartOptions) -> Self {
        let endpoint = (transport == TransportKind::Zenoh).then(free_endpoint);
        if let Some(e) = &endpoint {
            options.listen = vec![e.clone()];
        }
        let central = within("central starts", tca_central::start(options))
            .await
            .expect("central starts");
        let connector = match &endpoint {
            Some(e) => Connector::zenoh(e.clone()),
            None => Connector::from(central.in_process()),
        };
        TestCentral {
            central: Some(central),
            connector,
            endpoint,
        }
    }

    /// Stops central cleanly; its final statistics.
    pub async fn stop(mut self) -> Stats {
        let central = self.central.take().expect("running");
        within("central stops", central.shutdown())
            .await
            .expect("clean shutdown")
    }
}

/// A central in this process with the default options, and the connector to it.
pub async fn in_process_central() -> (RunningCentral, Connector) {
    let central = within(
        "central starts",
        tca_central::start(StartOptions::default()),
    )
    .await
    .expect("central starts");
    let connector = Connector::from(central.in_process());
    (central, connector)
}
