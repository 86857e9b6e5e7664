//! `tca walk --planner cgspace`, whole: the built binary walking the Ambler with CG-space
//! route and footfall planning on the CG-space courses, checked from the walk report alone
//! (`--json`), as an outside checker would. The cliff walk runs its route joins on worker
//! processes; planning in one process is checked by `tca plan cgspace` on the same course.

use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// Runs `tca ARGS` to its end with no input.
fn tca(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tca"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("tca runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The report: the last line of stdout.
fn report(out: &Output) -> Value {
    let stdout = text(&out.stdout);
    let last = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(last).unwrap_or_else(|e| {
        panic!(
            "the last line is the JSON report ({e}):\n{stdout}{}",
            text(&out.stderr)
        )
    })
}

fn num(v: &Value) -> f64 {
    v.as_f64().expect("a number")
}

/// Whether a foot point is on the cliff course's face: at x = 14 m, away from the ramp
/// (y 2.5..12.5 m), neither on the ground below (z 0) nor on the plateau (z 2.5 m), with
/// room for the course's relief.
fn on_the_face(p: [f64; 3]) -> bool {
    (p[0] - 14.0).abs() < 0.3 && !(2.5..=12.5).contains(&p[1]) && (0.15..2.35).contains(&p[2])
}

// One seed of the cliff walk (about 14 s here with two workers; every seed of 1..20 takes
// 9-19 s). The whole campaign over seeds is a `tca walk --seeds` run, not a test.
#[test]
fn the_ambler_walks_up_the_ramp_on_worker_processes_and_every_state_stands() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let out_dir = dir.path().to_str().expect("a UTF-8 path");
    let out = tca(&[
        "walk",
        "--robot",
        "ambler",
        "--planner",
        "cgspace",
        "--course",
        "cliff",
        "--seed",
        "11",
        "--workers",
        "2",
        "--out",
        out_dir,
        "--json",
    ]);
    let r = report(&out);
    let why = format!("{}", r["reason"]);
    assert_eq!(r["planner"], "CG-space");
    assert_eq!(r["reached"], true, "{why}");
    assert_eq!(out.status.code(), Some(0), "{why}");
    assert_eq!(r["falls"], 0);
    assert_eq!(r["collisions"], 0);
    assert_eq!(r["self_collisions"], 0);
    assert!(num(&r["min_stability_margin_m"]) > 0.0);
    assert_eq!(
        r["state_problems"].as_array().map(Vec::len),
        Some(0),
        "{}",
        r["state_problems"]
    );
    let states = r["states"].as_array().expect("states");
    assert!(states.len() > 10, "{} states", states.len());
    let mut crossed_on_the_ramp = false;
    for s in states {
        let body = s["body"].as_array().expect("a body pose");
        let (bx, by, bz) = (num(&body[0]), num(&body[1]), num(&body[2]));
        // The body crosses the cliff's line only over the ramp.
        if (bx - 14.0).abs() < 0.5 {
            assert!(
                by > 2.5,
                "the body at ({bx:.2}, {by:.2}) is over the cliff face"
            );
            crossed_on_the_ramp = true;
        }
        let feet = s["feet"].as_object().expect("feet by leg");
        let standing: Vec<[f64; 3]> = feet
            .values()
            .filter(|f| f["stance"] == true)
            .map(|f| {
                let a = f["at"].as_array().expect("a foot point");
                [num(&a[0]), num(&a[1]), num(&a[2])]
            })
            .collect();
        assert!(standing.len() >= 3, "{} feet stand", standing.len());
        for f in &standing {
            assert!(!on_the_face(*f), "a foot stands on the cliff face at {f:?}");
            // The body is above every standing foot (its underside clears the ground the
            // feet stand on).
            assert!(bz > f[2], "the body at {bz:.2} m is below a foot at {f:?}");
        }
        let com = s["com"].as_array().expect("a centre of mass");
        assert_eq!(com.len(), 3);
        assert!(num(&s["margin_m"]) > 0.0, "the CG outside its feet: {s}");
    }
    assert!(crossed_on_the_ramp, "the walk never crossed x = 14 m");
    let goal = r["goal"].as_array().expect("the goal");
    let last = states.last().expect("a last state");
    assert!((num(&last["body"][0]) - num(&goal[0])).abs() < 1.0);
    // The plan is in the report: its route and footholds.
    let routes = r["routes"].as_array().expect("routes");
    assert!(!routes.is_empty());
    assert_joins_ran_on_the_workers(dir.path());
}

#[test]
fn a_walled_in_goal_is_refused_by_tca_walk_without_a_step() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let out_dir = dir.path().to_str().expect("a UTF-8 path");
    let began = Instant::now();
    let out = tca(&[
        "walk",
        "--robot",
        "ambler",
        "--planner",
        "cgspace",
        "--course",
        "walled-goal",
        "--out",
        out_dir,
        "--json",
    ]);
    let took = began.elapsed();
    let r = report(&out);
    assert_ne!(out.status.code(), Some(0));
    assert_eq!(r["reached"], false);
    let why = r["reason"].as_str().expect("a reason");
    assert!(why.contains("cannot be reached"), "{why}");
    // No step taken: the robot never walked toward the wall.
    assert_eq!(r["steps"], 0, "{why}");
    assert_eq!(r["falls"], 0);
    assert_eq!(r["collisions"], 0);
    assert!(took < Duration::from_secs(120), "took {took:?}");
}

/// The route's joins crossed the bus to both worker processes, asked by the walking module;
/// the log passes the audit and the time check; the workers stop with the walk.
fn assert_joins_ran_on_the_workers(out_dir: &std::path::Path) {
    // The joins crossed the bus to both worker processes, asked by the walking module.
    let log = tca_logs::LogFile::open(&out_dir.join("traffic.mcap")).expect("the log");
    let mut asked = [0usize; 2];
    for rec in &log.records {
        let tca_logs::RecordKind::Frame(f) = &rec.kind else {
            continue;
        };
        let Ok(e) = tca_logs::LogFile::envelope(f) else {
            continue;
        };
        if f.direction == tca_logs::Direction::In && e.class == tca_messages::Class::Query {
            for (k, n) in asked.iter_mut().enumerate() {
                if e.name.as_str() == format!("cgspace.join.{k}") {
                    assert_eq!(e.sender.as_str(), "gait");
                    *n += 1;
                }
            }
        }
    }
    assert!(asked.iter().all(|&n| n > 0), "joins per worker: {asked:?}");
    let audit = tca_logs::audit(&log);
    assert!(audit.lost.is_empty(), "{}", audit.text());
    assert!(tca_logs::time_check(&log).holds());
    // The workers stop with the walk.
    std::thread::sleep(Duration::from_secs(2));
    // (Only a walk's workers are given the planner's layout with --cg-params.)
    let ps = Command::new("pgrep")
        .args(["-af", "module cgspace-worker .*--cg-params"])
        .output()
        .expect("pgrep runs");
    assert!(
        ps.stdout.is_empty(),
        "workers left running: {}",
        text(&ps.stdout)
    );
}
