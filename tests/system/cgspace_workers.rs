//! CG-space workers as processes over zenoh on loopback: `tca module cgspace-worker` answers
//! the roadmap's joins for a planner in this process, and the route is the one planned
//! locally; a worker process that is killed is started again.

use std::sync::Arc;
use std::time::Duration;

use crate::common::*;
use tca_cg_space::{
    BatchParams, CgCell, CgParams, CgRobot, CgSpace, LocalJoiner, RouteParams, plan_route_batched,
};
use tca_cg_space_bus::{DistributedJoiner, JoinerOptions, ProcessWorkers, worker_name};
use tca_legged_courses::Course;
use tca_legged_model::RobotModel;
use tca_module::{Connector, Module};

fn cliff() -> (CgSpace, CgCell, CgCell) {
    let course = Course::builtin("cliff", 1).expect("the cliff course");
    let model = RobotModel::builtin("ambler").expect("the Ambler");
    let robot = CgRobot::new(
        &model,
        course.terrain.grid().resolution_m(),
        CgParams::default(),
    )
    .expect("tables");
    let space = CgSpace::new(Arc::new(robot), &course.terrain).expect("a space");
    let grid = *space.grid();
    let s = grid
        .cell_of(
            tca_rrt::nalgebra::Point2::new(course.start.x_m, course.start.y_m),
            0.0,
        )
        .expect("start");
    let g = grid.cell_of(course.goal, 0.0).expect("goal");
    (space, s, g)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn worker_processes_over_zenoh_answer_the_joins() {
    let endpoint = free_endpoint();
    let _central = spawn_tca(&["central", "--listen", &endpoint]);
    let connector = Connector::endpoint(endpoint.clone());
    let planner = retry("the planner joins central", || async {
        Module::builder("cgspace-planner")
            .connect(&connector)
            .await
            .map_err(|e| e.to_string())
    })
    .await;
    let args: Vec<String> = [
        "module",
        "cgspace-worker",
        "--connect",
        &endpoint,
        "--robot",
        "ambler",
        "--terrain",
        "cliff",
        "--seed",
        "1",
        "--region-cap",
        "24",
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .collect();
    let workers = ProcessWorkers::new(env!("CARGO_BIN_EXE_tca"), args);
    let joiner = within(
        "two worker processes join central",
        DistributedJoiner::start(
            planner.clone(),
            2,
            workers.clone(),
            JoinerOptions::default(),
        ),
    )
    .await
    .expect("two worker processes");
    let registry = planner.registry().await.expect("the registry");
    for k in 0..2 {
        assert!(
            registry
                .modules
                .iter()
                .any(|m| m.as_str() == worker_name(k)),
            "{registry:?}"
        );
    }

    let (space, s, g) = cliff();
    let mut local_space = space.clone();
    let local = plan_route_batched(
        &mut local_space,
        &mut LocalJoiner,
        s,
        g,
        &RouteParams::default(),
        &BatchParams::default(),
    )
    .expect("a local route");

    // Plan once; then kill worker 1's process and plan again with the same joiner.
    let plan_with = |mut joiner: DistributedJoiner, mut space: CgSpace| {
        tokio::task::spawn_blocking(move || {
            let r = plan_route_batched(
                &mut space,
                &mut joiner,
                s,
                g,
                &RouteParams::default(),
                &BatchParams::default(),
            );
            (r, joiner)
        })
    };
    let (route, joiner) = within_for(
        Duration::from_secs(60),
        "the route over two worker processes",
        plan_with(joiner, space.clone()),
    )
    .await
    .expect("the planning thread");
    assert_eq!(route.expect("a route"), local);
    let stats = joiner.stats();
    assert_eq!(stats.replacements, 0, "{stats:?}");
    assert!(stats.queries_per_worker.iter().all(|&q| q > 0), "{stats:?}");
    assert!(
        stats.workers.iter().all(|w| w.regions_held <= 24),
        "{stats:?}"
    );

    let pid = workers.pid(1).expect("worker 1's pid");
    let _ = std::process::Command::new("kill")
        .args(["-KILL", &pid.to_string()])
        .status();
    let (route, joiner) = within_for(
        Duration::from_secs(60),
        "the route after a worker process was killed",
        plan_with(joiner, space),
    )
    .await
    .expect("the planning thread");
    assert_eq!(route.expect("a route after the kill"), local);
    let stats = joiner.shutdown().await;
    assert_eq!(stats.replacements, 1, "{stats:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tca_plan_cgspace_with_workers_plans_the_route_on_worker_processes() {
    let (space, s, g) = cliff();
    // The route alone: the batched roadmap's, whoever runs its joins.
    let (status, stdout, stderr) = run_tca(
        "tca plan cgspace --workers 2 --route-only",
        &[
            "plan",
            "cgspace",
            "--robot",
            "ambler",
            "--terrain",
            "cliff",
            "--workers",
            "2",
            "--route-only",
            "--json",
        ],
        Duration::from_secs(60),
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).expect("one JSON line");
    assert_eq!(v["planned"], true, "{v}");
    assert_eq!(v["workers"], 2);
    assert_eq!(v["replacements"], 0);
    let mut local_space = space.clone();
    let local = plan_route_batched(
        &mut local_space,
        &mut LocalJoiner,
        s,
        g,
        &RouteParams::default(),
        &BatchParams::default(),
    )
    .expect("a local route");
    assert_eq!(
        v["route_cells"].as_u64(),
        Some(local.cells.len() as u64),
        "{v}"
    );
    let per_worker = v["joins_per_worker"].as_array().expect("joins per worker");
    assert!(per_worker.iter().all(|j| j.as_u64() > Some(0)), "{v}");

    // The route and its footfalls: the same plan as one made here with the joins run
    // locally, the cells the foot-level search marked sent to the workers with each batch.
    let dir = tempfile::tempdir().expect("a temporary directory");
    let png_dir = dir.path().to_str().expect("a UTF-8 path");
    let (status, stdout, stderr) = run_tca(
        "tca plan cgspace --workers 2",
        &[
            "plan",
            "cgspace",
            "--robot",
            "ambler",
            "--terrain",
            "cliff",
            "--workers",
            "2",
            "--png",
            png_dir,
            "--json",
        ],
        Duration::from_secs(120),
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let line = stdout.lines().last().unwrap_or_default();
    let v: serde_json::Value = serde_json::from_str(line).expect("one JSON line");
    assert_eq!(v["planned"], true, "{v}");
    let course = Course::builtin("cliff", 1).expect("the cliff course");
    let mut local_space = space.clone();
    let plan = tokio::task::spawn_blocking(move || {
        tca_cg_space::plan_with(
            &mut local_space,
            (
                tca_rrt::nalgebra::Point2::new(course.start.x_m, course.start.y_m),
                course.start.yaw_rad,
            ),
            (course.goal, course.start.yaw_rad),
            None,
            &tca_cg_space::PlanParams::default(),
            None,
            &mut tca_cg_space::JoinedRoutes {
                joiner: LocalJoiner,
                batch: BatchParams::default(),
            },
        )
    })
    .await
    .expect("the planning thread")
    .expect("a local plan");
    assert_eq!(
        v["route_cells"].as_u64(),
        Some(plan.feet.route.len() as u64),
        "{v}"
    );
    assert_eq!(v["cells_marked"].as_u64(), Some(plan.marked.len() as u64));
    assert_eq!(v["routes_planned"].as_u64(), Some(plan.routes as u64));
    let footfalls = v["footfalls"].as_array().expect("footfalls");
    assert!(!footfalls.is_empty(), "{v}");
    assert!(v["joins"].as_u64() > Some(0), "{v}");
    assert!(dir.path().join("cgspace-1.png").exists());

    // Refused with the reason: more workers than strips, a central that is not there.
    let (status, _, stderr) = run_tca(
        "too many workers",
        &[
            "plan",
            "cgspace",
            "--robot",
            "ambler",
            "--terrain",
            "cliff",
            "--workers",
            "200",
        ],
        Duration::from_secs(30),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("--workers 200"), "{stderr}");
    let (status, _, stderr) = run_tca(
        "no central",
        &[
            "plan",
            "cgspace",
            "--robot",
            "ambler",
            "--terrain",
            "cliff",
            "--workers",
            "2",
            "--connect",
            &format!("tcp/127.0.0.1:{}", free_port()),
        ],
        Duration::from_secs(30),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("cannot join central"), "{stderr}");
    let (status, _, stderr) = run_tca(
        "a worker without its index",
        &[
            "module",
            "cgspace-worker",
            "--robot",
            "ambler",
            "--terrain",
            "cliff",
        ],
        Duration::from_secs(30),
    )
    .await;
    assert!(!status.success());
    assert!(stderr.contains("--index"), "{stderr}");
}
