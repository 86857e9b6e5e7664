//! `tca log replay`, whole system through the built binary: a recorded walk replayed with the
//! Controller and ISM played from the log reproduces every message of the live planners; the
//! same replay with other Gait Planner weights reports a divergence naming a message and a
//! field; logs that cannot be replayed are refused with a clear error and exit status 2.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// Each replayed goal gives up after this many wall-clock seconds, so no test hangs.
const GOAL_TIMEOUT_S: &str = "120";

fn tca(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tca"))
        .args(args)
        .env("TCA_LOG", "error")
        .stdin(Stdio::null())
        .output()
        .expect("tca runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Records `tca walk --course 4 --seed 1` (sequential) into `dir`; returns the log's path.
fn record(dir: &Path) -> PathBuf {
    record_with(dir, &[])
}

/// Records `tca walk --course 4 --seed 1 EXTRA` into `dir`; returns the log's path.
fn record_with(dir: &Path, extra: &[&str]) -> PathBuf {
    let mut args = vec![
        "walk",
        "--course",
        "4",
        "--seed",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = tca(&args);
    assert!(
        out.status.success(),
        "the walk to record failed:\n{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let log = dir.join("traffic.mcap");
    assert!(log.exists(), "no log at {}", log.display());
    log
}

fn replay(log: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "log",
        "replay",
        log.to_str().unwrap(),
        "--as",
        "controller,ism",
        "--timeout",
        GOAL_TIMEOUT_S,
    ];
    args.extend_from_slice(extra);
    tca(&args)
}

fn last_json(out: &Output) -> serde_json::Value {
    let stdout = text(&out.stdout);
    let line = stdout.trim().lines().last().unwrap_or_default().to_owned();
    serde_json::from_str(&line)
        .unwrap_or_else(|e| panic!("no JSON on the last line ({e}):\n{stdout}"))
}

#[test]
fn a_recorded_walk_replays_with_every_planner_message_matching() {
    let dir = tempfile::tempdir().unwrap();
    let log = record(dir.path());
    let out = replay(&log, &["--json"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("messages compared, all match"), "{stdout}");
    assert!(
        stdout.contains("controller, ism played from the log; ltm, pdm, lrp, gait live"),
        "{stdout}"
    );
    let report = last_json(&out);
    assert_eq!(report["all_match"], true, "{report}");
    let compared = report["compared"].as_u64().unwrap();
    assert!(compared > 50, "only {compared} messages compared: {report}");
    assert_eq!(report["divergences"], 0);
    assert_eq!(report["goals"][0]["name"], "walk");
    assert_eq!(report["goals"][0]["recorded"], "achieved");
    assert_eq!(report["goals"][0]["live"], "achieved");
    // Nothing the live modules asked for was missing from the record, nor left over.
    for (module, n) in report["unscripted"].as_object().unwrap() {
        assert_eq!(
            n, 0,
            "{module} had deliveries with no recorded answer: {report}"
        );
    }
    for (module, n) in report["unplayed"].as_object().unwrap() {
        assert_eq!(
            n, 0,
            "{module} had recorded deliveries never asked for: {report}"
        );
    }
    // The replay wrote nothing next to the record.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.starts_with("tca-replay")),
        "{names:?}"
    );
}

#[test]
fn other_gait_weights_diverge_and_the_divergence_names_message_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let log = record(dir.path());
    // The shipped parameters with the footfall weight lowered from 4 to 0.5.
    let shipped = include_str!("../../modules/gait-planner/params/gait.toml");
    assert!(
        shipped.contains("\nfootfall = 4.0\n"),
        "gait.toml changed: update this test"
    );
    let changed = shipped.replace("\nfootfall = 4.0\n", "\nfootfall = 0.5\n");
    let params = dir.path().join("gait.toml");
    std::fs::write(&params, changed).unwrap();
    let out = replay(&log, &["--gait-params", params.to_str().unwrap(), "--json"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}{}", text(&out.stderr));
    let first = stdout
        .lines()
        .find_map(|l| l.strip_prefix("first divergence: "))
        .unwrap_or_else(|| panic!("no divergence reported:\n{stdout}"));
    // e.g. "gait -> recoverLeg #1, field footfall.x_m: recorded 1.55, live 1.75"
    assert!(first.starts_with("gait -> "), "{first}");
    assert!(first.contains(", field "), "{first}");
    assert!(
        first.contains(": recorded ") && first.contains(", live "),
        "{first}"
    );
    let report = last_json(&out);
    assert_eq!(report["all_match"], false);
    assert!(report["divergences"].as_u64().unwrap() >= 1);
    assert_eq!(report["listed"][0]["sender"], "gait");
    assert_eq!(report["listed"][0]["difference"]["kind"], "field");
    // The same parameters as shipped, loaded from a file, change nothing.
    std::fs::write(&params, shipped).unwrap();
    let out = replay(&log, &["--gait-params", params.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
}

#[test]
fn a_recorded_concurrent_walk_replays_exactly_and_diverges_with_other_weights() {
    let dir = tempfile::tempdir().unwrap();
    let log = record_with(dir.path(), &["--concurrent"]);
    let out = replay(&log, &["--json"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    let report = last_json(&out);
    assert_eq!(report["all_match"], true, "{report}");
    assert!(report["compared"].as_u64().unwrap() > 50, "{report}");
    assert_eq!(report["goals"][0]["live"], "achieved", "{report}");
    assert_eq!(
        report["goals"][0]["recorded_sim_s"], report["goals"][0]["live_sim_s"],
        "the replayed walk ends at the recorded simulated time: {report}"
    );
    let shipped = include_str!("../../modules/gait-planner/params/gait.toml");
    let params = dir.path().join("gait.toml");
    std::fs::write(
        &params,
        shipped.replace("\nfootfall = 4.0\n", "\nfootfall = 0.5\n"),
    )
    .unwrap();
    let out = replay(&log, &["--gait-params", params.to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("first divergence: gait -> "), "{stdout}");
}

fn assert_refused(out: &Output, expected: &str) {
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{}{stderr}", text(&out.stdout));
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("cannot replay"), "{stderr}");
    assert!(
        stderr.contains(expected),
        "expected {expected:?} in:\n{stderr}"
    );
}

#[test]
fn logs_that_cannot_be_replayed_are_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let log = record(dir.path());
    let bytes = std::fs::read(&log).unwrap();
    // Cut in the middle of the walk (central killed): the record is incomplete.
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert_refused(&replay(&cut, &[]), "the record is incomplete");
    // Cut right after the header: no walk at all.
    let stub = dir.path().join("stub.mcap");
    std::fs::write(&stub, &bytes[..40.min(bytes.len())]).unwrap();
    assert_refused(&replay(&stub, &[]), "holds no `walk` goal");
    // Not a log.
    let junk = dir.path().join("junk.mcap");
    std::fs::write(&junk, b"this is not a traffic log").unwrap();
    assert_refused(&replay(&junk, &[]), "not a readable tca traffic log");
    // Damaged right after the magic bytes: nothing readable.
    let mut damaged = bytes.clone();
    for b in &mut damaged[8..8 + 4096] {
        *b = 0xA5;
    }
    let broken = dir.path().join("broken.mcap");
    std::fs::write(&broken, damaged).unwrap();
    assert_refused(&replay(&broken, &[]), "holds no `walk` goal");
    // A module the log does not hold, and a live module without its terrain.
    let out = tca(&["log", "replay", log.to_str().unwrap(), "--as", "controler"]);
    assert_refused(&out, "no module controler");
    let out = tca(&["log", "replay", log.to_str().unwrap(), "--as", "ism"]);
    assert_refused(&out, "--course");
    // A missing file.
    let out = replay(&dir.path().join("missing.mcap"), &[]);
    assert_refused(&out, "missing.mcap");
}
