//! FootFall's operator loop across the telemetry bridge, on one machine: the rover (sagging)
//! with FootFall's executor behind the robot-side central, FootFall's planner and the
//! telemetry monitor behind the ground-side central, the bridge between them with a delay
//! each way. Every step is picked from the leg's maps, planned, carried out and lands near
//! where it was aimed; every delay is the setting or a little more; the bridge's log played back
//! gives the same telemetry.

use std::time::Duration;

use crate::{DemoOptions, FootfallSessionOptions, Operator, demo};
use tca_testkit::within_for;

/// A delay a little late is the machine's load; the figures are in BENCHMARKS.md.
const SLACK_MS: f64 = 250.0;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn footfall_steps_across_a_delayed_bridge() {
    let dir = tempfile::tempdir().unwrap();
    let delay = Duration::from_millis(300);
    let options = DemoOptions {
        robot: "athlete".into(),
        course: "rock-field".into(),
        up_delay: delay,
        down_delay: delay,
        telemetry_hz: 10.0,
        speed: 4.0,
        operator: Operator::Footfall(FootfallSessionOptions {
            steps: 3,
            ..FootfallSessionOptions::default()
        }),
        out: dir.path().to_owned(),
        playback_speed: Some(4.0),
    };
    let report = within_for(
        Duration::from_secs(240),
        "three FootFall steps",
        demo(&options, |s, f| eprintln!("{s:?}\n  {f:?}")),
    )
    .await
    .expect("the session runs");
    assert_eq!(report.session.achieved, 3, "{:?}", report.session);
    assert_eq!(report.footfall.len(), 3);
    let legs: std::collections::HashSet<_> =
        report.session.steps.iter().map(|s| s.leg.clone()).collect();
    assert_eq!(legs.len(), 3, "the legs take turns: {legs:?}");
    for f in &report.footfall {
        assert!(f.green_cells > 0 && f.swing_waypoints <= 5, "{f:?}");
        let error = f
            .landed_error_m
            .expect("a touch-down came down as telemetry");
        assert!(error < 0.05, "landed {error} m from the target: {f:?}");
    }
    for way in report.bridge_delays.iter().chain(&report.central_delays) {
        assert!(way.crossings > 0, "{way:?}");
        assert!(way.min_error_ms >= 0.0, "a crossing came early: {way:?}");
        assert!(way.max_error_ms < SLACK_MS, "a crossing came late: {way:?}");
    }
    let replay = report.replay.expect("played back");
    assert!(replay.live > 10, "{replay:?}");
    assert!(replay.same_telemetry, "{replay:?}");
}
