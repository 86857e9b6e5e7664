//! Central killed with `kill -9` in the middle of a walk: the walking modules are separate
//! processes, over zenoh and over the local link. The log of the crashed central is
//! readable; the walk command fails with a message saying how to resume; a new central on
//! the same endpoint keeps the crashed one's log (as `traffic.1.mcap`) and every module
//! registers with it by itself; the same `tca walk --connect` then walks on from where the
//! leg stands to the goal, with no collision.

use std::process::{Command, Stdio};
use std::time::Duration;

use crate::common::*;

const WALKING: [&str; 6] = ["controller", "ism", "ltm", "pdm", "lrp", "gait"];

fn spawn_central(endpoint: &str, log: &std::path::Path) -> ChildProcess {
    spawn_tca(&[
        "central",
        "--listen",
        endpoint,
        "--log",
        log.to_str().unwrap(),
    ])
}

fn spawn_module(name: &str, endpoint: &str, state: &std::path::Path) -> ChildProcess {
    let mut args = vec!["module", name, "--connect", endpoint, "--course", "3"];
    let state = state.to_str().unwrap();
    if name == "controller" {
        // Slow enough that the walk is still going when central is killed (a few seconds).
        args.extend(["--speed", "40", "--state", state]);
    }
    if name == "ltm" {
        args.extend(["--state", state]);
    }
    spawn_tca(&args)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_walk_interrupted_by_a_central_crash_resumes_where_the_leg_stands() {
    walk_through_a_central_crash(&free_endpoint()).await;
}

/// The same over the local link, where the modules rejoin the new central within a fraction
/// of a second: the Controller settles the move whose command the crash abandoned, so the
/// resumed walk plans from where the leg really stands, not from a move still playing out.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn over_the_local_link_too() {
    walk_through_a_central_crash(&unique_local_endpoint()).await;
}

/// The walk, central killed during it and started again on `endpoint`, and the walk resumed.
async fn walk_through_a_central_crash(endpoint: &str) {
    let endpoint = endpoint.to_owned();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("traffic.mcap");
    let state = dir.path().join("state");
    let mut central = spawn_central(&endpoint, &log);
    wait_for_modules(&endpoint, &[]).await;
    let _modules: Vec<ChildProcess> = WALKING
        .iter()
        .map(|m| spawn_module(m, &endpoint, &state))
        .collect();
    wait_for_modules(&endpoint, &WALKING).await;

    // Walk, and kill central once the carriage has moved twice.
    let mut walk = Command::new(env!("CARGO_BIN_EXE_tca"))
        .args(["walk", "--connect", &endpoint, "--course", "3", "--json"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    within("two body moves", async {
        while body_moves(&log) < 2 {
            assert!(
                walk.try_wait().unwrap().is_none(),
                "the walk ended before central was killed"
            );
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    })
    .await;
    central.kill();

    // The walk command says what happened and how to go on.
    let out = within("the walk command ends", async {
        tokio::task::spawn_blocking(move || walk.wait_with_output())
            .await
            .unwrap()
            .unwrap()
    })
    .await;
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "the interrupted walk failed");
    assert!(
        stderr.contains("central went away during the walk") && stderr.contains("walks on"),
        "{stderr}"
    );

    // The crashed central's log is readable, up to its last moments.
    let crashed = tca_logs::LogFile::open(&log).expect("the crash log reads");
    let moves_logged = body_moves(&log);
    assert!(moves_logged >= 2, "{moves_logged} body moves logged");
    assert!(!crashed.records.is_empty());

    // A new central on the same endpoint keeps that log and the modules rejoin it by themselves.
    let _central = spawn_central(&endpoint, &log);
    wait_for_modules(&endpoint, &WALKING).await;
    let kept = dir.path().join("traffic.1.mcap");
    assert_eq!(
        body_moves(&kept),
        moves_logged,
        "the crash log was kept as traffic.1.mcap"
    );

    // The same walk command walks on from where the leg stands.
    let (status, stdout, stderr) = run_tca(
        "the resumed walk",
        &["walk", "--connect", &endpoint, "--course", "3", "--json"],
        Duration::from_secs(120),
    )
    .await;
    let report = walk_report(&stdout, &stderr);
    assert!(status.success(), "{report}\n{stderr}");
    assert_eq!(report["reached"], true, "{report}");
    assert_eq!(report["collisions"], 0, "{report}");
    let resumed_from = report["start_y_m"].as_f64().unwrap();
    assert!(
        resumed_from > tca_walk::START_Y_M + 0.3,
        "resumed from y = {resumed_from} m, not from where the leg stood"
    );
}
