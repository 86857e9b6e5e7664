//! The walking system across processes: `tca up` starts central and each walking module as
//! its own process over zenoh (the Controller simulator among them, swapped in for the real
//! one without any other module knowing), and `tca walk --connect` walks it.

use std::process::{Command, Stdio};

use crate::common::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_walk_runs_with_every_module_its_own_process() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = free_endpoint();
    let launch = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/walk.toml"))
        .unwrap()
        .replace("tcp/127.0.0.1:7447", &endpoint)
        .replace("out/up", dir.path().to_str().unwrap())
        .replace("\"3\"", "\"4\"");
    let file = dir.path().join("walk.toml");
    std::fs::write(&file, launch).unwrap();
    let mut up = spawn_tca(&["up", file.to_str().unwrap()]);
    // Wait until all six modules have registered.
    retry("the walking modules registered", || async {
        let e = endpoint.clone();
        let out = tokio::task::spawn_blocking(move || {
            Command::new(env!("CARGO_BIN_EXE_tca"))
                .args(["registry", "--connect", &e, "--json"])
                .output()
        })
        .await
        .unwrap()
        .map_err(|e| e.to_string())?;
        let v: serde_json::Value =
            serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())?;
        let modules = v["modules"].as_array().map_or(0, Vec::len);
        if modules >= 7 {
            Ok(())
        } else {
            Err(format!("{modules} modules so far"))
        }
    })
    .await;
    let e = endpoint.clone();
    let out = within(
        "the walk",
        tokio::task::spawn_blocking(move || {
            Command::new(env!("CARGO_BIN_EXE_tca"))
                .args(["walk", "--connect", &e, "--course", "4", "--json"])
                .stdin(Stdio::null())
                .output()
        }),
    )
    .await
    .unwrap()
    .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let last = stdout.trim().lines().last().unwrap_or_default();
    let report: serde_json::Value = serde_json::from_str(last)
        .unwrap_or_else(|e| panic!("{e}: {stdout}\n{}", String::from_utf8_lossy(&out.stderr)));
    assert_eq!(report["reached"], true, "{report}");
    assert_eq!(report["collisions"], 0, "{report}");
    assert!(report["steps"].as_u64().unwrap() >= 5, "{report}");
    up.interrupt_and_wait("tca up stops").await;
    // Central's log of the walk is complete and tells the story.
    let log = tca_logs::LogFile::open(&dir.path().join("traffic.mcap")).unwrap();
    assert!(log.truncated.is_none());
    let stats = tca_logs::stats(&log, tca_logs::TimeBase::Envelope);
    assert!(
        stats.by_name.get("legMove").copied().unwrap_or(0) >= 5,
        "{:?}",
        stats.by_name
    );
}
