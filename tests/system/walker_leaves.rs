//! A walker that leaves stops its walk: Ctrl-C of `tca walk --connect` says goodbye, and
//! central kills the walk's task tree, so the leg stops and a later walk runs alone (not
//! beside the first). The walking modules are separate processes on a local socket.

use std::time::Duration;

use crate::common::*;

const WALKING: [&str; 6] = ["controller", "ism", "ltm", "pdm", "lrp", "gait"];

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ctrl_c_of_a_walker_kills_its_walk() {
    let endpoint = unique_local_endpoint();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("traffic.mcap");
    let _central = spawn_tca(&[
        "central",
        "--listen",
        &endpoint,
        "--log",
        log.to_str().unwrap(),
    ]);
    wait_for_modules(&endpoint, &[]).await;
    let _modules: Vec<ChildProcess> = WALKING
        .iter()
        .map(|m| {
            let mut args = vec!["module", m, "--connect", &endpoint, "--course", "3"];
            if *m == "controller" {
                // Slow enough that the walk is still going when it is interrupted.
                args.extend(["--speed", "40"]);
            }
            spawn_tca(&args)
        })
        .collect();
    wait_for_modules(&endpoint, &WALKING).await;

    let mut walk = spawn_tca(&["walk", "--connect", &endpoint, "--course", "3"]);
    within("two body moves", async {
        while body_moves(&log) < 2 {
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    })
    .await;
    walk.interrupt_and_wait("the interrupted walker exits")
        .await;

    // Its tree is gone from central at once...
    let (status, stdout, stderr) = run_tca(
        "tca tree",
        &["tree", "--connect", &endpoint],
        Duration::from_secs(30),
    )
    .await;
    assert!(status.success(), "{stderr}");
    assert!(stdout.contains("no live task nodes"), "{stdout}");
    // ...and the leg stops: at most the move under way ends, no new one starts.
    tokio::time::sleep(Duration::from_secs(2)).await;
    let after = body_moves(&log);
    tokio::time::sleep(Duration::from_secs(3)).await;
    assert_eq!(body_moves(&log), after, "the leg kept walking");

    // A new walk walks alone from where the leg stands to the goal.
    let (status, stdout, stderr) = run_tca(
        "the next walk",
        &["walk", "--connect", &endpoint, "--course", "3", "--json"],
        Duration::from_secs(180),
    )
    .await;
    let report = walk_report(&stdout, &stderr);
    assert!(status.success(), "{report}\n{stderr}");
    assert_eq!(report["reached"], true, "{report}");
    assert_eq!(report["collisions"], 0, "{report}");
}
