//! A multi-legged robot's walking system across processes: `tca up walk-legged.toml` starts
//! central and the four legged modules (the simulated Controller among them) each as its own
//! process, and `tca walk --robot ... --connect` walks it. On simulated time the walk is the
//! one the same robot walks with every module in one process.

use std::time::Duration;

use crate::common::*;

const WALK_LIMIT: Duration = Duration::from_secs(300);

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_hexapod_walks_with_every_legged_module_its_own_process() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let (mut up, endpoint) = start_legged_system(dir.path()).await;

    let out_dir = dir.path().join("walk");
    let walk = [
        "walk",
        "--robot",
        "hexapod",
        "--course",
        "hexapod-rough",
        "--seed",
        "1",
        "--json",
    ];
    let mut connected: Vec<&str> = walk.to_vec();
    let out_text = out_dir.to_string_lossy().into_owned();
    connected.extend(["--connect", &endpoint, "--out", &out_text]);
    let (status, stdout, stderr) = run_tca("the connected walk", &connected, WALK_LIMIT).await;
    let across = walk_report(&stdout, &stderr);
    assert!(status.success(), "{stdout}\n{stderr}");
    assert_eq!(across["reached"], true, "{across}");
    assert_eq!(across["falls"], 0, "{across}");
    assert_eq!(across["collisions"], 0, "{across}");
    assert_eq!(across["state_problems"].as_array().map(Vec::len), Some(0));
    assert!(across["steps"].as_u64().unwrap_or(0) >= 20, "{across}");
    assert!(out_dir.join("report.json").exists() && out_dir.join("map.png").exists());

    up.interrupt_and_wait("tca up stops").await;
    // Central's log holds the walk's moves, as the modules exchanged them.
    let log = tca_logs::LogFile::open(&dir.path().join("traffic.mcap")).expect("central's log");
    assert!(log.truncated.is_none());
    let stats = tca_logs::stats(&log, tca_logs::TimeBase::Envelope);
    let leg_moves = stats.by_name.get("legged.legMove").copied().unwrap_or(0);
    assert!(leg_moves >= 20, "{:?}", stats.by_name);

    // The same walk in one process: on simulated time it is the same walk.
    let in_process_dir = dir.path().join("in-process").to_string_lossy().into_owned();
    let mut alone: Vec<&str> = walk.to_vec();
    alone.extend(["--out", &in_process_dir]);
    let (status, stdout, stderr) = run_tca("the in-process walk", &alone, WALK_LIMIT).await;
    let here = walk_report(&stdout, &stderr);
    assert!(status.success(), "{stdout}\n{stderr}");
    assert_eq!(across["steps"], here["steps"]);
    assert_eq!(across["states"], here["states"]);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_legged_module_without_its_robot_is_refused_with_what_to_give() {
    let (status, _, stderr) = run_tca(
        "a legged module without --robot",
        &["module", "legged-gait", "--connect", "tcp/127.0.0.1:9"],
        Duration::from_secs(30),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("--robot"), "{stderr}");
    let (status, _, stderr) = run_tca(
        "a single-leg module given a robot",
        &[
            "module",
            "pdm",
            "--robot",
            "hexapod",
            "--connect",
            "tcp/127.0.0.1:9",
        ],
        Duration::from_secs(30),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("legged modules"), "{stderr}");
    let (status, _, stderr) = run_tca(
        "a legged module of an unknown robot",
        &[
            "module",
            "legged-controller",
            "--robot",
            "nosuchrobot",
            "--connect",
            "tcp/127.0.0.1:9",
        ],
        Duration::from_secs(30),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("nosuchrobot"), "{stderr}");
}
