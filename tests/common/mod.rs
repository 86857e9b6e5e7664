//! Shared helpers of the whole-system tests: start central (in-process, or with zenoh on a free
//! loopback port), connect modules over either transport, run `tca` as a child process.

#![allow(dead_code, unreachable_pub)]

use std::future::Future;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use tca_central::{RunningCentral, StartOptions};
use tca_module::Connector;

/// Every await in a test is bounded by this.
pub const STEP: Duration = Duration::from_secs(20);

/// Awaits `f`, failing the test if it takes longer than [`STEP`].
pub async fn within<T>(what: &str, f: impl Future<Output = T>) -> T {
    match tokio::time::timeout(STEP, f).await {
        Ok(v) => v,
        Err(_) => panic!("timed out after {STEP:?}: {what}"),
    }
}

/// Which transport a test runs over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    InProcess,
    Zenoh,
}

pub const BOTH: [Transport; 2] = [Transport::InProcess, Transport::Zenoh];

/// A free TCP port on loopback.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free loopback port")
}

/// A zenoh endpoint on a free loopback port.
pub fn free_endpoint() -> String {
    format!("tcp/127.0.0.1:{}", free_port())
}

/// A central for one test; shut down (or aborted) when dropped.
pub struct TestCentral {
    pub central: Option<RunningCentral>,
    pub connector: Connector,
    pub endpoint: Option<String>,
}

impl TestCentral {
    pub async fn start(transport: Transport) -> Self {
        Self::start_with(transport, StartOptions::default()).await
    }

    pub async fn start_with(transport: Transport, mut options: StartOptions) -> Self {
        let endpoint = (transport == Transport::Zenoh).then(free_endpoint);
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

    pub async fn stop(mut self) -> tca_central::Stats {
        let central = self.central.take().expect("running");
        within("central stops", central.shutdown())
            .await
            .expect("clean shutdown")
    }
}

/// A `tca` child process, killed when dropped.
pub struct ChildProcess(pub Child);

impl ChildProcess {
    pub fn spawn(args: &[&str]) -> Self {
        let child = Command::new(env!("CARGO_BIN_EXE_tca"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("tca starts");
        ChildProcess(child)
    }

    /// SIGKILL, as a crash.
    pub fn kill(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

impl Drop for ChildProcess {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Waits until `path` exists and is non-empty.
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

/// Retries `f` until it succeeds (for connecting to a process that is still starting).
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

/// The modules registered with the central at `endpoint` (`tca registry --json`).
pub async fn registered_modules(endpoint: &str) -> Result<Vec<String>, String> {
    let e = endpoint.to_owned();
    let out = tokio::task::spawn_blocking(move || {
        Command::new(env!("CARGO_BIN_EXE_tca"))
            .args(["registry", "--connect", &e, "--json"])
            .output()
    })
    .await
    .map_err(|e| e.to_string())?
    .map_err(|e| e.to_string())?;
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())?;
    Ok(v["modules"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|m| m.as_str().map(str::to_owned))
                .collect()
        })
        .unwrap_or_default())
}

/// Waits until every module in `names` is registered with the central at `endpoint`.
pub async fn wait_for_modules(endpoint: &str, names: &[&str]) {
    retry("the modules registered", || async {
        let modules = registered_modules(endpoint).await?;
        let missing: Vec<_> = names
            .iter()
            .filter(|n| !modules.iter().any(|m| m == *n))
            .collect();
        if missing.is_empty() {
            Ok(())
        } else {
            Err(format!("still missing {missing:?}"))
        }
    })
    .await
}

/// Runs `tca ARGS` to its end and returns its exit status, stdout and stderr.
pub async fn run_tca(
    what: &str,
    args: &[&str],
    limit: Duration,
) -> (std::process::ExitStatus, String, String) {
    let args: Vec<String> = args.iter().map(|a| (*a).to_owned()).collect();
    let run = tokio::task::spawn_blocking(move || {
        Command::new(env!("CARGO_BIN_EXE_tca"))
            .args(&args)
            .stdin(Stdio::null())
            .output()
    });
    let out = match tokio::time::timeout(limit, run).await {
        Ok(out) => out.expect("joins").expect("tca runs"),
        Err(_) => panic!("timed out after {limit:?}: {what}"),
    };
    (
        out.status,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The JSON report on the last line of `tca walk --json`'s stdout.
pub fn walk_report(stdout: &str, stderr: &str) -> serde_json::Value {
    let last = stdout.trim().lines().last().unwrap_or_default();
    serde_json::from_str(last)
        .unwrap_or_else(|e| panic!("no walk report ({e}): {stdout}\n{stderr}"))
}
