//! Crash-proof walking: `tca chaos` walks course 3 with the walking modules as
//! separate processes over zenoh while random modules are killed with SIGKILL and started
//! again. Every walk reaches its goal without a collision, and the audit of central's log finds
//! no message lost and none handled twice (`tca log audit` agrees). The stateful modules (the
//! Controller, whose leg must not jump back to the start, and the LTM Manager, whose map must
//! not vanish) are killed on purpose in the first run.

use std::time::Duration;

use crate::common::*;

async fn chaos(args: &[&str]) -> (serde_json::Value, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap().to_owned();
    let mut all = vec!["chaos", "--json", "--out", &out];
    all.extend_from_slice(args);
    let (status, stdout, stderr) = run_tca("tca chaos", &all, Duration::from_secs(240)).await;
    let report = walk_report(&stdout, &stderr);
    assert!(status.success(), "{stdout}\n{stderr}");
    // The log can be audited on its own too.
    let log = report["log"].as_str().unwrap().to_owned();
    let (audit_status, audit_out, _) = run_tca(
        "tca log audit",
        &["log", "audit", &log],
        Duration::from_secs(60),
    )
    .await;
    assert!(audit_status.success(), "{audit_out}");
    assert!(
        audit_out.contains("no message lost, none handled twice"),
        "{audit_out}"
    );
    assert!(audit_out.contains("time kept"), "{audit_out}");
    (report, stderr)
}

fn check(report: &serde_json::Value, walks: usize, kills: usize) {
    assert_eq!(report["passed"], true, "{report}");
    let w = report["walks"].as_array().unwrap();
    assert!(w.len() >= walks, "{report}");
    for walk in w {
        assert_eq!(walk["reached"], true, "{walk}");
        assert_eq!(walk["collisions"], 0, "{walk}");
    }
    assert!(
        report["kills"].as_array().unwrap().len() >= kills,
        "{report}"
    );
    assert!(report["audit"]["lost"].as_array().unwrap().is_empty());
    assert!(
        report["audit"]["handled_twice"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    assert!(report["audit"]["tasks"].as_u64().unwrap() > 0);
    assert!(
        report["time"]["violations"].as_array().unwrap().is_empty(),
        "{report}"
    );
    assert!(report["time"]["constraints"].as_u64().unwrap() > 0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn walks_survive_the_stateful_modules_being_killed() {
    let (report, stderr) = chaos(&[
        "--walks",
        "2",
        "--kills",
        "4",
        "--seed",
        "5",
        "--victims",
        "controller,ltm",
    ])
    .await;
    check(&report, 2, 4);
    assert!(stderr.contains("killed"), "{stderr}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn walks_survive_any_module_being_killed() {
    let (report, _) = chaos(&["--walks", "3", "--kills", "3", "--seed", "11"]).await;
    check(&report, 3, 3);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_that_is_not_a_walking_module_cannot_be_a_victim() {
    let (status, _, stderr) = run_tca(
        "tca chaos --victims central",
        &["chaos", "--walks", "1", "--victims", "central"],
        Duration::from_secs(30),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("not a walking module"), "{stderr}");
}

/// Central itself killed with SIGKILL twice during a walk, started again at once on its
/// journal: the walk goes on by itself to its goal (the walker sends it once), and the logs of
/// the three centrals, audited together, show no message lost, none handled twice, time kept.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_walk_goes_on_through_kills_of_central_on_its_journal() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap().to_owned();
    let (status, stdout, stderr) = run_tca(
        "tca chaos --kill-central",
        &[
            "chaos",
            "--json",
            "--out",
            &out,
            "--kill-central",
            "--walks",
            "1",
            "--kills",
            "2",
            "--seed",
            "2",
        ],
        Duration::from_secs(240),
    )
    .await;
    let report = walk_report(&stdout, &stderr);
    assert!(status.success(), "{stdout}\n{stderr}");
    check(&report, 1, 2);
    for kill in report["kills"].as_array().unwrap() {
        assert_eq!(kill["module"], "central", "{kill}");
    }
    let walks = report["walks"].as_array().unwrap().len() as u64;
    assert_eq!(report["walk_goals"].as_u64(), Some(walks), "{report}");
    // Each restart kept the crashed central's log: three logs, audited as one history.
    let logs: Vec<String> = report["logs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap().to_owned())
        .collect();
    assert_eq!(logs.len(), 3, "{report}");
    let mut args = vec!["log", "audit"];
    args.extend(logs.iter().map(String::as_str));
    let (audit_status, audit_out, _) =
        run_tca("tca log audit", &args, Duration::from_secs(60)).await;
    assert!(audit_status.success(), "{audit_out}");
    assert!(
        audit_out.contains("no message lost, none handled twice"),
        "{audit_out}"
    );
    assert!(audit_out.contains("time kept"), "{audit_out}");
}
