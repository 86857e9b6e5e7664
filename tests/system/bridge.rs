//! The telemetry bridge across processes, at the Earth-Moon light time: a robot-side central
//! with the ATHLETE-like walker's Controller publishing telemetry, a ground-side central with
//! the telemetry monitor, `tca bridge run bridge.toml` (the shipped file) between them with
//! 1.3 s each way, and an operator on the ground sending ten leg moves. Every move is
//! achieved, every delay (measured by the bridge and from the two centrals' logs) is the
//! setting or a little more, never less, and the bridge's log played back to a fresh ground
//! side gives the same telemetry.

use std::path::Path;
use std::time::Duration;

use crate::common::*;
use tca_legged_ground::{SessionOptions, run_session};
use tca_module::{Connector, Module};

/// A delay a little late is the machine's load; the figures are in BENCHMARKS.md.
const SLACK_MS: f64 = 250.0;

/// The `legged.telemetry` lines of a monitor's record: (arrival, data).
fn telemetry(record: &Path) -> Vec<(u64, serde_json::Value)> {
    std::fs::read_to_string(record)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["name"] == "legged.telemetry")
        .map(|v| (v["received_ns"].as_u64().unwrap_or(0), v["data"].clone()))
        .collect()
}

fn check_delays(what: &str, figures: &serde_json::Value) {
    for way in figures.as_array().expect("both ways") {
        let n = way["crossings"].as_u64().unwrap_or(0);
        assert!(n > 0, "{what}: nothing crossed {}", way["direction"]);
        let min = way["min_error_ms"].as_f64().unwrap();
        let max = way["max_error_ms"].as_f64().unwrap();
        assert!(min >= 0.0, "{what}: a crossing came early: {way}");
        assert!(
            max < SLACK_MS,
            "{what}: a crossing came {max} ms late: {way}"
        );
        eprintln!("{what}: {way}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ten_leg_moves_across_the_bridge_at_the_moons_distance() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let d = |f: &str| dir.path().join(f).to_string_lossy().into_owned();
    let (robot, ground) = (free_endpoint(), free_endpoint());
    let _robot_central = spawn_tca(&["central", "--listen", &robot, "--log", &d("robot.mcap")]);
    let _ground_central = spawn_tca(&["central", "--listen", &ground, "--log", &d("ground.mcap")]);
    // Both centrals answer before their modules start.
    wait_for_modules(&robot, &[]).await;
    wait_for_modules(&ground, &[]).await;
    let controller_args = [
        "module",
        "legged-controller",
        "--robot",
        "athlete",
        "--course",
        "flat",
        "--telemetry",
        "10",
        "--speed",
        "4",
        "--connect",
        &robot,
    ];
    let mut controller = spawn_tca(&controller_args);
    let record = d("telemetry.jsonl");
    let _monitor = spawn_tca(&[
        "module",
        "legged-telemetry",
        "--record",
        &record,
        "--connect",
        &ground,
    ]);
    wait_for_modules(&robot, &["controller"]).await;
    wait_for_modules(&ground, &["telemetry"]).await;

    // The shipped bridge file, on this test's endpoints and directory.
    let file = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/bridge.toml"))
        .expect("the shipped bridge file")
        .replace("tcp/127.0.0.1:7447", &robot)
        .replace("tcp/127.0.0.1:7448", &ground)
        .replace("out/bridge", dir.path().to_str().expect("a UTF-8 path"));
    let bridge_file = d("bridge.toml");
    std::fs::write(&bridge_file, file).expect("the bridge file written");
    let mut bridge = spawn_tca(&["bridge", "run", &bridge_file]);
    wait_for_modules(&ground, &["bridge"]).await;
    wait_for_modules(&robot, &["bridge"]).await;

    // The operator: ten leg moves, each waited for.
    let to_ground = Connector::endpoint(ground.clone());
    let operator = retry("the operator connects", || {
        Module::builder("operator").connect(&to_ground)
    })
    .await;
    let options = SessionOptions {
        query_timeout: Duration::from_secs(35),
        ..SessionOptions::default()
    };
    let session = within_for(Duration::from_secs(150), "ten leg moves", async {
        run_session(&operator, &options, |s| {
            eprintln!(
                "step {}: {} {} in {:.3} s",
                s.step,
                s.leg,
                s.outcome,
                s.round_trip_s()
            )
        })
        .await
    })
    .await
    .expect("the session runs");
    assert_eq!(session.robot, "athlete");
    assert_eq!(session.achieved, 10, "{session:?}");
    for s in &session.steps {
        // Up, the move (under a second at this speed), down.
        assert!(
            s.round_trip_s() >= 2.6 && s.round_trip_s() < 2.6 + 1.0 + SLACK_MS / 1e3,
            "{s:?}"
        );
    }
    operator.close().await;
    // No more telemetry; what is on its way down arrives, then the bridge stops (Ctrl-C).
    controller.kill();
    tokio::time::sleep(Duration::from_millis(1600)).await;
    bridge.interrupt_and_wait("the bridge stops").await;

    // Every delay is the setting or a little more: measured by the bridge, and between the
    // centrals from their own logs.
    let (status, stdout, stderr) = run_tca(
        "the delays",
        &[
            "bridge",
            "delays",
            &d("bridge.mcap"),
            "--robot-log",
            &d("robot.mcap"),
            "--ground-log",
            &d("ground.mcap"),
            "--worst",
            "3",
            "--json",
        ],
        STEP,
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    eprintln!("{stdout}");
    let figures: serde_json::Value =
        serde_json::from_str(stdout.lines().last().expect("a JSON line")).expect("JSON");
    check_delays("the bridge", &figures["bridge"]);
    check_delays("between the centrals", &figures["centrals"]);
    // The worst crossings each way: three, worst first, the first the largest maximum.
    for (worst, ways) in [("bridge_worst", "bridge"), ("centrals_worst", "centrals")] {
        let list = figures[worst].as_array().expect(worst);
        assert_eq!(list.len(), 3, "{worst}: {list:?}");
        let errors: Vec<f64> = list
            .iter()
            .map(|l| l["error_ms"].as_f64().unwrap())
            .collect();
        assert!(
            errors.windows(2).all(|w| w[0] >= w[1]),
            "{worst}: {errors:?}"
        );
        let max = figures[ways]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w["max_error_ms"].as_f64().unwrap())
            .fold(f64::MIN, f64::max);
        assert!(
            (errors[0] - max).abs() < 1e-6,
            "{worst}: {errors:?} against {max}"
        );
        assert!(
            list.iter()
                .all(|l| l["name"].as_str().is_some_and(|n| !n.is_empty()))
        );
    }
    for way in figures["bridge"].as_array().unwrap() {
        assert_eq!(way["setting_s"], 1.3, "{way}");
    }
    // Up: the model, six leg states, ten moves; down: their answers and the telemetry.
    assert!(
        figures["bridge"][0]["crossings"].as_u64().unwrap() >= 17,
        "{figures}"
    );
    let live = telemetry(Path::new(&record));
    assert!(live.len() > 50, "{} telemetry samples came", live.len());

    // Played back to a fresh ground side (four times as fast): the same telemetry.
    let replay_ground = free_endpoint();
    let _replay_central = spawn_tca(&["central", "--listen", &replay_ground]);
    wait_for_modules(&replay_ground, &[]).await;
    let replay_record = d("replay.jsonl");
    let _replay_monitor = spawn_tca(&[
        "module",
        "legged-telemetry",
        "--record",
        &replay_record,
        "--connect",
        &replay_ground,
    ]);
    wait_for_modules(&replay_ground, &["telemetry"]).await;
    let (status, stdout, stderr) = run_tca(
        "the playback",
        &[
            "bridge",
            "play",
            &d("bridge.mcap"),
            "--ground",
            &replay_ground,
            "--speed",
            "4",
            "--linger",
            "0",
            "--json",
        ],
        STEP,
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let played: serde_json::Value =
        serde_json::from_str(stdout.lines().last().expect("a JSON line")).expect("JSON");
    within("the played-back telemetry is recorded", async {
        while telemetry(Path::new(&replay_record)).len() < live.len() {
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    })
    .await;
    let again = telemetry(Path::new(&replay_record));
    assert_eq!(again.len(), live.len(), "{played}");
    for (k, ((lt, l), (rt, r))) in live.iter().zip(&again).enumerate() {
        assert_eq!(l, r, "sample {k}");
        // The recorded timing, four times as fast.
        let live_s = (lt - live[0].0) as f64 / 1e9;
        let again_s = (rt - again[0].0) as f64 / 1e9 * 4.0;
        assert!(
            (live_s - again_s).abs() < 4.0 * SLACK_MS / 1e3,
            "sample {k}: {live_s:.3} s live, {again_s:.3} s played back"
        );
    }
}
