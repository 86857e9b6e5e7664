//! The local link across processes: `tca central --listen local/NAME` and modules as their
//! own processes over its Unix socket. Round trips work; a module killed with `kill -9` is
//! noticed; a central killed with `kill -9` and started again on the same endpoint is rejoined
//! by its modules; one central listening on a local socket and on zenoh routes between a local
//! and a zenoh module; a second central on a live socket, a malformed endpoint and a module the
//! policy does not know are refused with errors that say so.

use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use crate::common::*;

/// A local endpoint no other test (or run) uses.
fn unique_local() -> String {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    format!(
        "local/test-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    )
}

/// The modules connected to the central at `endpoint` now, if it answers.
async fn connected(endpoint: &str) -> Result<Vec<String>, String> {
    tca().registered_modules(endpoint).await
}

/// Times `n` pings to the echo module `target` through `endpoint`: the report's `n`.
async fn ping(endpoint: &str, target: &str, n: usize) -> u64 {
    let n = n.to_string();
    let (status, stdout, stderr) = run_tca(
        "tca ping",
        &[
            "ping",
            "--connect",
            endpoint,
            "--target",
            target,
            "-n",
            &n,
            "--json",
        ],
        STEP,
    )
    .await;
    assert!(status.success(), "tca ping failed: {stderr}");
    let report: serde_json::Value = serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("no JSON report ({e}): {stdout}"));
    assert!(report["p50_us"].as_f64().unwrap() > 0.0, "{report}");
    report["n"].as_u64().unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn round_trips_cross_processes_and_a_killed_module_is_noticed() {
    let endpoint = unique_local();
    let _central = spawn_tca(&["central", "--listen", &endpoint]);
    wait_for_modules(&endpoint, &[]).await;
    let mut echo = spawn_tca(&["module", "echo", "--connect", &endpoint]);
    wait_for_modules(&endpoint, &["echo"]).await;
    assert_eq!(ping(&endpoint, "echo", 200).await, 200);

    echo.kill();
    retry("central notices the killed echo", || async {
        let modules = connected(&endpoint).await?;
        if modules.iter().any(|m| m == "echo") {
            Err(format!("echo still connected: {modules:?}"))
        } else {
            Ok(())
        }
    })
    .await;
    // A ping now finds the echo down and says so.
    let (status, _, stderr) = run_tca(
        "tca ping with the echo down",
        &[
            "ping",
            "--connect",
            &endpoint,
            "--target",
            "echo",
            "-n",
            "1",
        ],
        STEP,
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("(down)"), "{stderr}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_central_killed_and_started_again_is_rejoined() {
    let endpoint = unique_local();
    let mut central = spawn_tca(&["central", "--listen", &endpoint]);
    wait_for_modules(&endpoint, &[]).await;
    let _echo = spawn_tca(&["module", "echo", "--connect", &endpoint]);
    wait_for_modules(&endpoint, &["echo"]).await;
    assert_eq!(ping(&endpoint, "echo", 20).await, 20);

    // kill -9 leaves the socket file behind; the next central replaces it.
    central.kill();
    let _central = spawn_tca(&["central", "--listen", &endpoint]);
    wait_for_modules(&endpoint, &["echo"]).await;
    assert_eq!(ping(&endpoint, "echo", 20).await, 20);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn one_central_routes_between_local_and_zenoh_modules() {
    let local = unique_local();
    let zenoh = free_endpoint();
    let _central = spawn_tca(&["central", "--listen", &local, "--listen", &zenoh]);
    wait_for_modules(&local, &[]).await;
    // The echo over zenoh, the pinger over the local socket...
    let mut echo = spawn_tca(&["module", "echo", "--connect", &zenoh]);
    wait_for_modules(&local, &["echo"]).await;
    assert_eq!(ping(&local, "echo", 20).await, 20);
    echo.kill();
    // ...and the other way round, at once: central sees that the killed echo's process is
    // gone and lets the new one take its name even before zenoh reports the old one lost.
    let _echo = spawn_tca(&["module", "echo", "--connect", &local]);
    retry("the local echo registered", || async {
        let modules = connected(&zenoh).await?;
        if modules.iter().any(|m| m == "echo") {
            Ok(())
        } else {
            Err(format!("modules: {modules:?}"))
        }
    })
    .await;
    assert_eq!(ping(&zenoh, "echo", 20).await, 20);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mistakes_and_strangers_are_refused_with_reasons() {
    let endpoint = unique_local();
    let dir = tempfile::tempdir().unwrap();
    // A central that admits only the controller identity (no anonymous modules).
    let policy = dir.path().join("policy.toml");
    std::fs::write(
        &policy,
        "[[identity]]\nname = \"controller\"\nsecret_sha3 = \
         \"deaa4421d5fe4c6f5045983a365c51f610280cb96b23a7721c78f32a011c823b\"\n\
         modules = [\"controller\"]\nregister = [\"bodyMove\"]\nsend = []\n",
    )
    .unwrap();
    let _central = spawn_tca(&[
        "central",
        "--listen",
        &endpoint,
        "--policy",
        policy.to_str().unwrap(),
    ]);
    retry("central listening", || async {
        let path = tca_link::LocalEndpoint::parse(&endpoint)
            .unwrap()
            .socket_path()
            .unwrap();
        std::os::unix::net::UnixStream::connect(&path).map(|_| ())
    })
    .await;

    // A second central on the same live socket.
    let (status, _, stderr) = run_tca(
        "a second central",
        &["central", "--listen", &endpoint],
        STEP,
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("already listening"), "{stderr}");

    // A module without credentials: the policy refuses it at hello, over the local link too.
    let (status, _, stderr) = run_tca(
        "an anonymous echo",
        &["module", "echo", "--connect", &endpoint],
        STEP,
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("refused"), "{stderr}");

    // A malformed endpoint, and one nobody listens on.
    let (status, _, stderr) = run_tca(
        "a bad endpoint",
        &["ping", "--connect", "local/a/b", "-n", "1"],
        Duration::from_secs(60),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("NAME must be"), "{stderr}");
    let nobody = unique_local();
    let (status, _, stderr) = run_tca(
        "nobody there",
        &["ping", "--connect", &nobody, "-n", "1"],
        STEP,
    )
    .await;
    assert!(!status.success());
    assert!(
        stderr.contains("no central at") && stderr.contains("tca central --listen"),
        "{stderr}"
    );
}
