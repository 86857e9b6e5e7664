//! The mission's promise: the leg (compliant, as the report's was, unless rigid) walks down the
//! obstacle courses autonomously, without striking anything; concurrent walking saves time;
//! faults are replanned or halt the walk; an impassable course stops safely.

use crate::common::within;
use tca_controller_sim::sim::ScheduledFault;
use tca_single_leg_messages::WalkMode;
use tca_walk::{ComputeModel, TerrainChoice, WalkOptions, WalkReport};
use tokio::sync::mpsc;

fn options(terrain: TerrainChoice, seed: u64) -> WalkOptions {
    WalkOptions {
        terrain,
        goal_y_m: None,
        backward: false,
        mode: WalkMode::Sequential,
        seed,
        out: None,
        step_pictures: false,
        connect: None,
        compute: ComputeModel::Paper,
        fault: None,
        rigid: false,
        body_move_law: Default::default(),
        attach: None,
    }
}

async fn walk(options: WalkOptions) -> WalkReport {
    let (tx, _rx) = mpsc::unbounded_channel();
    within("walk", tca_walk::walk(&options, tx))
        .await
        .expect("the walk runs")
}

fn assert_clean(report: &WalkReport) {
    assert!(
        report.reached,
        "{}: {:?}\n{report:#?}",
        report.terrain, report.reason
    );
    assert_eq!(report.collisions, 0, "{report:#?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_course_is_walked_forward_without_a_collision() {
    for course in 1..=4 {
        for seed in [1, 2, 3] {
            let report = walk(options(TerrainChoice::Course(course), seed)).await;
            assert_clean(&report);
            assert!(report.distance_m >= 8.0, "{report:#?}");
            assert!(report.steps >= 5, "{report:#?}");
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_course_is_walked_forward_and_back_on_the_maps_of_the_way_out() {
    for course in 1..=4 {
        for seed in [1, 2] {
            let report = walk(WalkOptions {
                backward: true,
                ..options(TerrainChoice::Course(course), seed)
            })
            .await;
            assert_clean(&report);
            assert_eq!(report.legs.len(), 2);
            assert!(
                (report.final_y_m - report.start_y_m).abs() < 0.05,
                "{report:#?}"
            );
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn random_courses_are_walked_without_a_collision() {
    for seed in [11, 12, 13] {
        let report = walk(options(TerrainChoice::Random(seed), seed)).await;
        assert_clean(&report);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn course_3_takes_the_reports_time_sequentially_and_concurrently() {
    // Under the paper's compute model every module is charged its 1990 time, so the walk's
    // simulated duration is the report's experiment (13.5 min sequential, 8.75 min
    // concurrent on course 3): each within 15 %, and the first step, which builds the first
    // terrain map from scratch, the slowest.
    // The step durations come from the log.
    let dir = tempfile::tempdir().unwrap();
    let sequential = walk(WalkOptions {
        out: Some(dir.path().join("sequential")),
        ..options(TerrainChoice::Course(3), 1)
    })
    .await;
    assert_clean(&sequential);
    let concurrent = walk(WalkOptions {
        mode: WalkMode::Concurrent,
        ..options(TerrainChoice::Course(3), 1)
    })
    .await;
    assert_clean(&concurrent);
    for (report, paper_min) in [(&sequential, 13.5), (&concurrent, 8.75)] {
        let minutes = report.sim_time_s / 60.0;
        assert!(
            (minutes - paper_min).abs() <= 0.15 * paper_min,
            "{}: {minutes:.2} min against the report's {paper_min} min",
            report.mode
        );
    }
    let durations: Vec<f64> = std::iter::once(0.0)
        .chain(sequential.step_ends_s.iter().copied())
        .collect::<Vec<_>>()
        .windows(2)
        .map(|w| w[1] - w[0])
        .collect();
    assert_eq!(durations.len(), sequential.steps, "{sequential:#?}");
    let first = durations[0];
    assert!(
        durations[1..].iter().all(|&d| d < first),
        "the first step is not the slowest: {durations:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_impassable_course_stops_safely_and_says_why() {
    // A wall 1.6 m tall across the whole pit at y = 4 m: the leg can neither step over it nor
    // go around it.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("wall.asc");
    let (nx, ny, cell) = (121usize, 221usize, 0.05);
    let mut text = format!(
        "ncols {nx}\nnrows {ny}\nxllcenter 0\nyllcenter 0\ncellsize {cell}\nNODATA_value -9999\n"
    );
    for row in 0..ny {
        let y = (ny - 1 - row) as f64 * cell;
        let h = if (4.0..4.3).contains(&y) { 1.6 } else { 0.0 };
        let line: Vec<String> = (0..nx).map(|_| format!("{h}")).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    std::fs::write(&path, text).unwrap();
    let report = walk(options(TerrainChoice::File(path), 1)).await;
    assert!(!report.reached, "{report:#?}");
    assert_eq!(report.collisions, 0, "{report:#?}");
    assert!(report.reason.is_some());
    assert!(report.final_y_m < 4.0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_slip_is_replanned_from_where_the_leg_is_and_the_walk_goes_on() {
    let clean = walk(options(TerrainChoice::Course(3), 1)).await;
    assert_clean(&clean);
    for mode in [WalkMode::Sequential, WalkMode::Concurrent] {
        let report = walk(WalkOptions {
            mode,
            fault: Some(ScheduledFault::parse("slip@3").unwrap()),
            ..options(TerrainChoice::Course(3), 1)
        })
        .await;
        assert_clean(&report);
        // The slipped step is planned again (concurrently, the step planned ahead of it is
        // planned again too): more steps than the clean walk.
        assert!(report.steps > clean.steps, "{mode:?}: {report:#?}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hardware_fault_halts_the_walk_with_the_reason() {
    for (fault, mode, says) in [
        (
            "force-drop@2",
            WalkMode::Sequential,
            "the foot force dropped",
        ),
        (
            "limit-switch@4",
            WalkMode::Concurrent,
            "limit switch tripped",
        ),
    ] {
        let report = walk(WalkOptions {
            mode,
            fault: Some(ScheduledFault::parse(fault).unwrap()),
            ..options(TerrainChoice::Course(3), 1)
        })
        .await;
        assert!(!report.reached, "{fault}: {report:#?}");
        assert_eq!(report.collisions, 0, "{fault}");
        let reason = report.reason.clone().unwrap_or_default();
        assert!(
            reason.contains(says) && reason.contains("the walk was halted"),
            "{fault}: {reason}"
        );
        // Halted during the faulty step's body move: no further step was taken.
        assert!(report.final_y_m < 9.0, "{fault}: {report:#?}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_rigid_leg_walks_too() {
    // `--rigid`: no deflection simulated and none compensated.
    for mode in [WalkMode::Sequential, WalkMode::Concurrent] {
        let report = walk(WalkOptions {
            mode,
            rigid: true,
            backward: true,
            ..options(TerrainChoice::Course(4), 1)
        })
        .await;
        assert_clean(&report);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_reports_open_loop_body_move_falls_short_and_the_walk_stops_with_the_reason() {
    // `--body-move open-loop`: each body move falls short, so the walk takes more steps, and
    // it ends short of the goal, saying why, without a collision.
    let servo = walk(options(TerrainChoice::Course(3), 1)).await;
    let report = walk(WalkOptions {
        body_move_law: tca_controller_sim::sim::BodyMoveLaw::OpenLoop,
        ..options(TerrainChoice::Course(3), 1)
    })
    .await;
    assert_eq!(report.collisions, 0, "{report:#?}");
    assert!(report.steps > servo.steps + 2, "{report:#?}");
    assert!(report.final_y_m > 9.0, "{report:#?}");
    if !report.reached {
        let reason = report.reason.as_deref().unwrap_or_default();
        assert!(reason.contains("not advancing"), "{reason}");
    }
}
