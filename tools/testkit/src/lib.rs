//! What the workspace's tests share, so that each is written once: bounded waits, free
//! loopback endpoints, a central started for one test (in-process, over zenoh or over the local link), the `tca`
//! binary run as a child process, and the JSON report of a walk. A dev-dependency only.
//!
//! # Layout
//!
//! - this file: [`within`], [`within_for`], [`retry`], [`wait_for_file`] (every await in a
//!   test is bounded).
//! - [`net`]: [`free_port`], [`free_endpoint`].
//! - [`central`]: [`TransportKind`] ([`BOTH`], [`ALL`]), [`TestCentral`],
//!   [`in_process_central`], [`unique_local_endpoint`], [`remove_local_socket`].
//! - [`tca`]: [`Tca`], the `tca` binary of the test's package: run to its end, spawned as a
//!   [`ChildProcess`] killed on drop, asked for the registry; [`walk_report`].
//! - [`tls`]: [`TestCa`], certificates for mutual-TLS tests.

pub mod central;
pub mod net;
pub mod tca;
pub mod tls;

use std::future::Future;
use std::path::Path;
use std::time::Duration;

pub use central::{
    ALL, BOTH, TestCentral, TransportKind, in_process_central, remove_local_socket,
    unique_local_endpoint,
};
pub use net::{free_endpoint, free_port};
pub use tca::{ChildProcess, Tca, walk_report};
pub use tls::TestCa;

/// Every await in a test is bounded by this, unless it says otherwise ([`within_for`]):
/// long enough for a loaded two-core machine, short enough that a hang fails the test.
pub const STEP: Duration = Duration::from_secs(60);

/// Awaits `f`, failing the test if it takes longer than [`STEP`].
pub async fn within<T>(what: &str, f: impl Future<Output = T>) -> T {
    within_for(STEP, what, f).await
}

/// Awaits `f`, failing the test if it takes longer than `limit`.
pub async fn within_for<T>(limit: Duration, what: &str, f: impl Future<Output = T>) -> T {
    match tokio::time::timeout(limit, f).await {
        Ok(v) => v,
        Err(_) => panic!("timed out after {limit:?}: {what}"),
    }
}

/// Retries `f` every 100 ms until it succeeds, at most for [`STEP`] (for connecting to a
/// process that is still starting).
pub async fn retry<T, E: std::fmt::Display, F, Fut>(what: &str, mut f: F) -> T
where
    F: FnMut() -> Fut,
    Fut: Future<Output = Result<T, E>>,
{
    within(what, async {
        loop {
            match f().await {
                Ok(v) => return v,
                Err(e) => {
                    tracing::debug!("{what}: {e}; retrying");
                    tokio::time::sleep(Duration::from_millis(100)).await;
                }
            }
        }
    })
    .await
}

/// Waits (at most [`STEP`]) until `path` exists and is not empty.
pub async fn wait_for_file(path: &Path) {
    within("file appears", async {
        while std::fs::metadata(path)
            .map(|m| m.len() == 0)
            .unwrap_or(true)
        {
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    })
    .await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn within_returns_what_finished_in_time() {
        assert_eq!(within("ready", async { 7 }).await, 7);
    }

    #[tokio::test]
    #[should_panic(expected = "timed out after 10ms: never")]
    async fn within_fails_the_test_when_time_runs_out() {
        within_for(
            Duration::from_millis(10),
            "never",
            std::future::pending::<()>(),
        )
        .await;
    }

    #[tokio::test]
    async fn retry_keeps_trying_until_it_works() {
        let mut attempts = 0;
        let v = retry("third time", || {
            attempts += 1;
            let n = attempts;
            async move { if n < 3 { Err("not yet") } else { Ok(n) } }
        })
        .await;
        assert_eq!(v, 3);
    }
}
