//! Navigation across processes: `tca up nav.toml` starts central and the four navigation
//! modules each as its own process, and `tca navigate --connect` runs the goal on them. On
//! simulated time it is the run the same seed gives with every module in one process.

use std::time::Duration;

use crate::common::*;

const LIMIT: Duration = Duration::from_secs(300);

fn report(stdout: &str, stderr: &str) -> serde_json::Value {
    let line = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {stdout}\n{stderr}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_wheeled_base_navigates_with_every_module_its_own_process() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let endpoint = free_endpoint();
    let launch = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/nav.toml"))
        .expect("the shipped launch file")
        .replace("tcp/127.0.0.1:7448", &endpoint)
        .replace("out/up-nav", dir.path().to_str().expect("a UTF-8 path"));
    let file = dir.path().join("nav.toml");
    std::fs::write(&file, launch).expect("the launch file written");
    let mut up = spawn_tca(&["up", file.to_str().expect("a UTF-8 path")]);
    wait_for_modules(&endpoint, &["controller", "ism", "ltm", "navigator"]).await;

    let run = ["navigate", "--terrain", "hill", "--seed", "1", "--json"];
    let mut connected = run.to_vec();
    connected.extend(["--connect", &endpoint]);
    let (status, stdout, stderr) = run_tca("the connected navigation", &connected, LIMIT).await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let mut across = report(&stdout, &stderr);
    assert_eq!(across["reached"], true, "{across}");
    assert_eq!(across["collisions"], 0, "{across}");
    assert_eq!(across["falls"], 0, "{across}");
    up.interrupt_and_wait("tca up stops").await;

    // Central's log holds the frames as the modules exchanged them.
    let log = tca_logs::LogFile::open(&dir.path().join("traffic.mcap")).expect("central's log");
    let stats = tca_logs::stats(&log, tca_logs::TimeBase::Envelope);
    let frames = across["frames"].as_u64().unwrap() as usize;
    assert!(
        stats.by_name.get("nav.acquireDepth").copied().unwrap_or(0) >= frames,
        "{:?}",
        stats.by_name
    );

    // The same seed in one process: the same run, apart from the loop rate.
    let (status, stdout, stderr) = run_tca("the in-process navigation", &run, LIMIT).await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let mut here = report(&stdout, &stderr);
    across["loop_hz"] = 0.into();
    here["loop_hz"] = 0.into();
    assert_eq!(across, here);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_navigation_module_without_its_terrain_is_refused_with_what_to_give() {
    let out = tca_output(&["module", "nav-ltm", "--connect", "tcp/127.0.0.1:1"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--course ramps|hill"), "{err}");
    let out = tca_output(&[
        "module",
        "nav-planner",
        "--course",
        "hill",
        "--connect",
        "tcp/127.0.0.1:1",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no navigation module named"), "{err}");
}
