//! A central for one test, over any of the transports.

use std::sync::atomic::{AtomicU32, Ordering};

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
    /// Central listening on a Unix socket of its own ([`unique_local_endpoint`]); modules
    /// connect over the local link.
    Local,
}

/// In-process and zenoh, for tests that must hold over each (and that need zenoh, or are
/// not about the link).
pub const BOTH: [TransportKind; 2] = [TransportKind::InProcess, TransportKind::Zenoh];

/// Every transport: in-process, zenoh and the local link.
pub const ALL: [TransportKind; 3] = [
    TransportKind::InProcess,
    TransportKind::Zenoh,
    TransportKind::Local,
];

/// A local endpoint (`local/test-PID-N`) that no other central of this run or of another
/// test process uses, in the default socket directory (a test must not set `TCA_LOCAL_DIR`:
/// changing the environment of a multi-threaded process is not sound).
pub fn unique_local_endpoint() -> String {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    format!(
        "local/test-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    )
}

/// Removes the socket file a central killed on the local `endpoint` left behind (a central that
/// stops cleanly removes its own); does nothing for other endpoints or a missing file.
pub fn remove_local_socket(endpoint: &str) {
    if !tca_link::LocalEndpoint::is_local(endpoint) {
        return;
    }
    if let Ok(path) = tca_link::LocalEndpoint::parse(endpoint).and_then(|e| e.socket_path()) {
        let _ = std::fs::remove_file(path);
    }
}

/// A central for one test; its runtime task ends with the test.
pub struct TestCentral {
    /// The running central (`None` once stopped).
    pub central: Option<RunningCentral>,
    /// How the test's modules reach it.
    pub connector: Connector,
    /// The endpoint it listens on (a zenoh one, or a local one over the local link); `None`
    /// in-process.
    pub endpoint: Option<String>,
}

impl TestCentral {
    /// A central with the default options.
    pub async fn start(transport: TransportKind) -> Self {
        Self::start_with(transport, StartOptions::default()).await
    }

    /// A central with `options` (over zenoh it listens on a free loopback port, over the local
    /// link on a [`unique_local_endpoint`], instead of `options.listen`).
    pub async fn start_with(transport: TransportKind, mut options: StartOptions) -> Self {
        let endpoint = match transport {
            TransportKind::InProcess => None,
            TransportKind::Zenoh => Some(free_endpoint()),
            TransportKind::Local => Some(unique_local_endpoint()),
        };
        if let Some(e) = &endpoint {
            options.listen = vec![e.clone()];
        }
        let central = within("central starts", tca_central::start(options))
            .await
            .expect("central starts");
        let connector = match &endpoint {
            Some(e) => Connector::endpoint(e.clone()),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_endpoints_are_unique_and_valid() {
        let (a, b) = (unique_local_endpoint(), unique_local_endpoint());
        assert_ne!(a, b);
        for e in [a, b] {
            tca_link::local::LocalEndpoint::parse(&e).expect("a valid local endpoint");
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_local_central_is_reached_over_its_socket() {
        let central = TestCentral::start(TransportKind::Local).await;
        let endpoint = central.endpoint.clone().expect("an endpoint");
        assert!(endpoint.starts_with("local/test-"), "{endpoint}");
        let module = within(
            "a module connects",
            tca_module::Module::builder("probe").connect(&central.connector),
        )
        .await
        .expect("the module connects over the local link");
        let registry = within("registry", module.registry()).await.unwrap();
        assert!(
            registry.modules.iter().any(|m| m.as_str() == "probe"),
            "{registry:?}"
        );
        central.stop().await;
    }

    #[test]
    fn a_left_socket_is_removed() {
        let endpoint = unique_local_endpoint();
        let path = tca_link::LocalEndpoint::parse(&endpoint)
            .and_then(|e| e.prepare())
            .unwrap();
        std::fs::write(&path, b"").unwrap();
        remove_local_socket(&endpoint);
        assert!(!path.exists(), "{} is still there", path.display());
        remove_local_socket(&endpoint);
        remove_local_socket("tcp/127.0.0.1:1");
    }
}
