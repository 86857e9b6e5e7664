//! Multi-legged walks on the bus, whole: the simulated Controller, the body-mounted scanner,
//! the LTM Manager's map and the free gait in one process, driven by one `legged.walk`.
//! Every report's states are checked against the terrain from the report's numbers alone.

use tca_legged_walk::{
    LeggedPlanner, LeggedTerrain, LeggedWalkOptions, LeggedWalkReport, check_states,
};
use tca_logs::LogFile;
use tca_robot::HeightField;
use tokio::sync::mpsc;

fn course_terrain(name: &str, seed: u64) -> HeightField {
    tca_legged_courses::Course::builtin(name, seed)
        .expect("a built-in course")
        .terrain
}

async fn walk(options: LeggedWalkOptions) -> LeggedWalkReport {
    let (tx, _rx) = mpsc::unbounded_channel();
    tca_legged_walk::walk(&options, tx)
        .await
        .expect("the walk runs")
}

/// Asserts a walk reached its goal safely and that every recorded state is consistent.
fn assert_safe_arrival(report: &LeggedWalkReport, terrain: &HeightField) {
    print!("{}", report.summary());
    assert!(report.reached, "{:?}", report.reason);
    assert_safe(report, terrain);
}

fn assert_safe(report: &LeggedWalkReport, terrain: &HeightField) {
    assert_eq!(report.falls, 0, "{}", report.summary());
    assert_eq!(report.collisions, 0, "{}", report.summary());
    assert_eq!(report.self_collisions, 0, "{}", report.summary());
    let least = report.min_stability_margin_m.expect("states were recorded");
    assert!(least > 0.0, "least margin {least}");
    assert!(
        report.states.len() > report.steps,
        "a state per support change"
    );
    let problems = check_states(&report.states, terrain);
    assert!(problems.is_empty(), "{problems:?}");
    assert!(
        report.state_problems.is_empty(),
        "{:?}",
        report.state_problems
    );
    assert!(report.sim_time_s > 0.0);
}

fn options(robot: &str, course: &str, seed: u64) -> LeggedWalkOptions {
    LeggedWalkOptions {
        terrain: Some(LeggedTerrain::Course {
            name: course.into(),
            seed,
        }),
        seed,
        ..LeggedWalkOptions::new(robot)
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ambler_crosses_the_boulder_field_on_its_own_map() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let report = walk(LeggedWalkOptions {
        out: Some(dir.path().to_path_buf()),
        ..options("ambler", "boulders", 1)
    })
    .await;
    assert_safe_arrival(&report, &course_terrain("boulders", 1));
    assert!(report.steps >= 30, "20 m in steps of at most 0.6 m");
    for file in ["traffic.mcap", "map.png", "report.json"] {
        assert!(dir.path().join(file).is_file(), "{file} written");
    }
    let written: LeggedWalkReport = serde_json::from_slice(
        &std::fs::read(dir.path().join("report.json")).expect("report.json"),
    )
    .expect("report.json is a report");
    assert_eq!(written.states, report.states);
    // The log holds the robot's description, so its Foxglove export shows the robot.
    let log = LogFile::open(&dir.path().join("traffic.mcap")).expect("the walk's log");
    let exported = dir.path().join("foxglove.mcap");
    let summary = tca_foxglove::export_foxglove(&log, &exported).expect("an export");
    assert_eq!(
        summary.well_known.get("/robot_description"),
        Some(&1),
        "{summary:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ambler_plans_each_step_while_the_last_executes() {
    let report = walk(LeggedWalkOptions {
        concurrent: true,
        ..options("ambler", "flat", 1)
    })
    .await;
    assert_eq!(report.mode, "concurrent");
    assert_safe_arrival(&report, &course_terrain("flat", 1));
    // Time runs forward through the overlapping steps.
    assert!(report.states.windows(2).all(|w| w[0].t_s <= w[1].t_s));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ambler_climbs_the_slope_on_its_own_map() {
    let report = walk(options("ambler", "slope", 3)).await;
    assert_safe_arrival(&report, &course_terrain("slope", 3));
    let top = report
        .states
        .iter()
        .map(|s| s.body[2])
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        top > 2.0,
        "the body climbed onto the 2 m plateau (top {top:.2} m)"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ambler_crosses_the_ditch_on_its_own_map() {
    let report = walk(options("ambler", "ditch", 2)).await;
    assert_safe_arrival(&report, &course_terrain("ditch", 2));
    let farthest_foot = report
        .states
        .iter()
        .flat_map(|s| s.feet.values().map(|f| f.at[0]))
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(farthest_foot > 12.5, "feet got past the ditch");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_hexapod_walks_its_rough_course_on_its_own_map() {
    let report = walk(options("hexapod", "hexapod-rough", 2)).await;
    assert_safe_arrival(&report, &course_terrain("hexapod-rough", 2));
    assert!(!report.mode.contains("true terrain"), "{}", report.mode);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_hexapod_walks_its_rough_course_planning_on_the_true_terrain() {
    let report = walk(LeggedWalkOptions {
        ground_truth: true,
        ..options("hexapod", "hexapod-rough", 1)
    })
    .await;
    assert_safe_arrival(&report, &course_terrain("hexapod-rough", 1));
    assert!(report.mode.contains("true terrain"), "{}", report.mode);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_athlete_stands_and_takes_steps_on_rough_ground() {
    let report = walk(LeggedWalkOptions {
        goal: Some([9.0, 0.0]),
        ..options("athlete", "rough", 1)
    })
    .await;
    print!("{}", report.summary());
    assert!(report.steps >= 12, "{}", report.summary());
    assert_safe(&report, &course_terrain("rough", 1));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_impossible_goal_ends_with_the_reason_and_no_fall() {
    // A chasm 5 m wide and 3 m deep across the whole terrain at x = 12..17 m.
    let flat = course_terrain("flat", 1);
    let (lo, _) = flat.extent();
    let grid = flat.grid();
    let (nx, ny, cell) = (grid.nx(), grid.ny(), grid.resolution_m());
    let heights = (0..ny)
        .flat_map(|_| (0..nx).map(move |ix| lo.x + ix as f64 * cell))
        .map(|x| if (12.0..17.0).contains(&x) { -3.0 } else { 0.0 })
        .collect();
    let chasm = HeightField::new(lo, cell, nx, ny, heights).expect("a terrain");
    let dir = tempfile::tempdir().expect("a temporary directory");
    let file = dir.path().join("chasm.asc");
    tca_robot::terrain::asc::write_height_field(&file, &chasm).expect("written");
    let report = walk(LeggedWalkOptions {
        terrain: Some(LeggedTerrain::File(file)),
        start: Some([3.0, 0.0, 0.0]),
        goal: Some([23.0, 0.0]),
        ..LeggedWalkOptions::new("ambler")
    })
    .await;
    print!("{}", report.summary());
    assert!(!report.reached);
    let reason = report.reason.clone().expect("a reason");
    assert!(
        reason.contains("step") || reason.contains("goal"),
        "{reason}"
    );
    assert_safe(&report, &chasm);
    assert!(report.states.iter().all(|s| s.body[0] < 12.0));
}

/// The integrated RRT-Connect planner walks the hexapod across the walls course: over the
/// 15 cm wall, never over the 35 cm one, round the steep hill, safely, with its plan in the
/// report and its trees in a picture.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rrt_connect_walks_the_hexapod_over_the_low_wall_and_round_the_hill() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let report = walk(LeggedWalkOptions {
        planner: LeggedPlanner::Rrt(tca_rrt::Gait::Tripod),
        out: Some(dir.path().to_path_buf()),
        ..options("hexapod", "hexapod-walls", 2)
    })
    .await;
    assert_safe_arrival(&report, &course_terrain("hexapod-walls", 2));
    assert_eq!(
        report.self_collisions, 0,
        "no two parts of the robot touched"
    );
    let walls = report.walls.expect("the walls course is checked");
    assert!(walls.as_intended(), "{}", walls.describe());
    assert!(report.planner.contains("RRT-Connect"), "{}", report.planner);
    let first = report.routes.first().expect("a plan in the report");
    assert!(first.postures > 10 && first.nodes > 0, "{first:?}");
    assert!(dir.path().join("rrt.png").is_file());
}

/// A goal behind a wall too high to climb, across the whole terrain: the planner says there
/// is no way, and the robot is left standing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rrt_connect_ends_a_walk_to_an_unreachable_goal_with_the_reason() {
    // The walls course's extent, level, with a 35 cm wall across it.
    let course = course_terrain("hexapod-walls", 1);
    let (lo, _) = course.extent();
    let grid = course.grid();
    let (nx, ny, cell) = (grid.nx(), grid.ny(), grid.resolution_m());
    let heights = (0..ny)
        .flat_map(|_| (0..nx).map(move |ix| lo.x + ix as f64 * cell))
        .map(|x| if (2.5..2.6).contains(&x) { 0.35 } else { 0.0 })
        .collect();
    let walled = HeightField::new(lo, cell, nx, ny, heights).expect("a terrain");
    let dir = tempfile::tempdir().expect("a temporary directory");
    let file = dir.path().join("wall.asc");
    tca_robot::terrain::asc::write_height_field(&file, &walled).expect("written");
    let report = walk(LeggedWalkOptions {
        terrain: Some(LeggedTerrain::File(file)),
        start: Some([0.5, 0.0, 0.0]),
        goal: Some([4.5, 0.0]),
        planner: LeggedPlanner::Rrt(tca_rrt::Gait::Tripod),
        ..LeggedWalkOptions::new("hexapod")
    })
    .await;
    print!("{}", report.summary());
    assert!(!report.reached);
    let reason = report.reason.clone().expect("a reason");
    assert!(reason.contains("no path"), "{reason}");
    assert_eq!(report.falls, 0);
    assert_eq!(report.collisions, 0);
    assert!(report.states.iter().all(|s| s.body[0] < 2.5));
}

/// A leg whose drives die mid-walk: the Controller refuses the next command that would move
/// it and raises `legged.hardwareFault`; the walk halts standing with the leg in the reason,
/// and nothing moved after the fault.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hardware_fault_halts_the_walk_standing_with_the_leg_named() {
    let fault: tca_legged_walk::InjectedFault = "left_middle@6".parse().expect("a fault");
    let report = walk(LeggedWalkOptions {
        faults: vec![fault],
        ..options("hexapod", "hexapod-flat", 1)
    })
    .await;
    print!("{}", report.summary());
    assert!(!report.reached);
    let reason = report.reason.clone().expect("a reason");
    assert!(reason.contains("hardware fault on left_middle"), "{reason}");
    assert_safe(&report, &course_terrain("hexapod-flat", 1));
    let last = report.states.last().expect("states");
    assert!(last.t_s >= 6.0, "the robot moved until the fault");
    // Every state after the fault is the state the robot stood in when it struck.
    let before = report
        .states
        .iter()
        .rev()
        .find(|s| s.t_s < 6.0)
        .expect("a state before the fault");
    let moved_after: Vec<_> = report
        .states
        .iter()
        .filter(|s| s.t_s > before.t_s)
        .collect();
    assert!(
        moved_after.len() <= 2,
        "at most the move under way when the fault started ended: {} states after it",
        moved_after.len()
    );
}

use crate::common::tca_output as tca;

/// `tca course write`, then `tca walk --robot FILE.urdf --terrain FILE.asc --json`: an
/// eight-legged description written for this test walks with no change to the code, and
/// the JSON summary has the fields other tools check walks by.
#[test]
fn an_eight_legged_description_walks_flat_and_rough_ground_from_the_command_line() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let robot = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/robots/octopod.urdf");
    for course in ["hexapod-flat", "hexapod-rough"] {
        let asc = dir.path().join(format!("{course}.asc"));
        let asc_text = asc.to_string_lossy().into_owned();
        let out = tca(&["course", "write", course, &asc_text, "--seed", "2"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let out_dir = dir.path().join(course).to_string_lossy().into_owned();
        let out = tca(&[
            "walk",
            "--robot",
            robot,
            "--terrain",
            &asc_text,
            "--start",
            "0.6,0",
            "--goal",
            "2.9,0",
            "--out",
            &out_dir,
            "--json",
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value =
            serde_json::from_str(stdout.lines().last().expect("a JSON line")).expect("JSON");
        for field in [
            "reached",
            "reason",
            "steps",
            "falls",
            "collisions",
            "min_stability_margin_m",
            "sim_time_s",
            "wall_time_s",
            "planning_ms_per_step",
            "states",
        ] {
            assert!(json.get(field).is_some(), "{field} in the summary");
        }
        assert_eq!(json["reached"], true);
        let state = &json["states"][0];
        assert_eq!(state["body"].as_array().map(Vec::len), Some(6));
        assert_eq!(state["com"].as_array().map(Vec::len), Some(3));
        assert!(state["t_s"].is_number());
        let feet = state["feet"].as_object().expect("feet by leg name");
        assert_eq!(feet.len(), 8);
        for name in ["left_1", "right_4"] {
            assert_eq!(feet[name]["at"].as_array().map(Vec::len), Some(3));
            assert!(feet[name]["stance"].is_boolean());
        }
        let report: LeggedWalkReport = serde_json::from_value(json).expect("a report");
        let terrain = course_terrain(course, 2);
        assert_safe(&report, &terrain);
    }
}

#[test]
fn bad_robots_terrains_starts_and_goals_are_refused_with_what_to_do() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let not_urdf = dir.path().join("robot.urdf");
    std::fs::write(&not_urdf, "this is not a robot").expect("written");
    let not_urdf = not_urdf.to_string_lossy().into_owned();
    let bad_asc = dir.path().join("bad.asc");
    std::fs::write(&bad_asc, "ncols 3\nnrows two\n").expect("written");
    let bad_asc = bad_asc.to_string_lossy().into_owned();
    let cases: &[(&[&str], &str)] = &[
        (&["walk", "--robot", "centipede"], "ambler"),
        (&["walk", "--robot", &not_urdf], "robot.urdf"),
        (
            &["walk", "--robot", "ambler", "--course", "moon"],
            "boulders",
        ),
        (
            &["walk", "--robot", "ambler", "--terrain", &bad_asc],
            "ESRI ASCII",
        ),
        (
            &["walk", "--robot", "ambler", "--terrain", "/no/such.asc"],
            "/no/such.asc",
        ),
        (
            &["walk", "--robot", "ambler", "--start", "0.5,0"],
            "too near the edge",
        ),
        (
            &["walk", "--robot", "ambler", "--goal", "40,0"],
            "too near the edge",
        ),
        (&["walk", "--robot", "ambler", "--goal", "north"], "X,Y"),
        (
            &["walk", "--robot", "ambler", "--start", "3,0,1,2"],
            "X,Y,YAW",
        ),
        (&["walk", "--robot", "ambler", "--start", "3,nan"], "finite"),
        (&["walk", "--goal", "3,4"], "--robot"),
        (
            &["walk", "--robot", "ambler", "--seeds", "5..1"],
            "FIRST..LAST",
        ),
        (&["course", "write", "moon", "x.asc"], "boulders"),
        (
            &["walk", "--robot", "hexapod", "--fault", "wing@3"],
            "left_front",
        ),
        (
            &["walk", "--robot", "hexapod", "--fault", "left_front"],
            "LEG@SECONDS",
        ),
        (
            &["walk", "--robot", "hexapod", "--fault", "left_front@-2"],
            "zero or more",
        ),
        (
            &["walk", "--fault", "slip@2", "--fault", "slip@3"],
            "one --fault",
        ),
        (
            &["walk", "--robot", "hexapod", "--planner", "astar"],
            "free (the free gait), rrt (RRT-Connect) and cgspace",
        ),
        (
            &[
                "walk",
                "--robot",
                "hexapod",
                "--planner",
                "rrt",
                "--gait",
                "gallop",
            ],
            "gallop",
        ),
        (
            &["walk", "--robot", "hexapod", "--gait", "wave"],
            "--planner rrt",
        ),
    ];
    for (args, needle) in cases {
        let out = tca(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} was accepted");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    let out = tca(&["walk", "--start", "3,0"]);
    assert!(!out.status.success(), "--start without --robot");
}
