//! The walking hexapod as the navigation base on the bus: the navigator's speeds walked by
//! the free gait through the legged Controller, the camera on the hexapod's body; the same
//! report as the one-process loop with the hexapod on the simulator directly.

use std::sync::Arc;

use tca_legged_model::{BUILTIN_ROBOTS, RobotModel};
use tca_nav_bus::{LeggedBase, NavBase, NavSetup, run_on_bus};
use tca_nav_hexapod::{HexapodBase, StepperParams, hexapod_params};
use tca_nav_navigator::{RunOptions, RunReport, hill_course, run};

fn without_rate(mut r: RunReport) -> RunReport {
    r.loop_hz = 0.0;
    r
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_hexapod_walks_to_a_near_goal_on_the_bus_as_in_one_process() {
    let course = hill_course().unwrap();
    let model = Arc::new(RobotModel::builtin("hexapod").unwrap());
    let urdf = BUILTIN_ROBOTS
        .iter()
        .find(|r| r.name == "hexapod")
        .unwrap()
        .urdf
        .to_string();
    let params = hexapod_params(&model).unwrap();
    let stepper = StepperParams::for_model(&model);
    let terrain = Arc::new(course.terrain.clone());
    // A short walk over the gravel, ahead and a little to the left, before the hill.
    let opts = RunOptions {
        start: course.start,
        goal_offset: [0.2, 0.1],
        drift: 0.0125,
        seed: 3,
        max_frames: 60,
    };
    let mut base = HexapodBase::new(
        model.clone(),
        terrain.clone(),
        course.start,
        stepper.clone(),
    )
    .unwrap();
    let (direct, _) = run(&course.terrain, &mut base, params.clone(), &opts).unwrap();
    assert!(direct.reached, "{}", direct.reason);
    assert_eq!(direct.robot, "hexapod");
    assert_eq!((direct.falls, direct.collisions), (0, 0));
    assert!(direct.final_error_m <= 0.06, "{direct:?}");
    assert!(base.sim().counters().moves > 10, "the hexapod walked");
    // The camera rode on the body: the body stood at its walking height above the gravel.
    assert!(base.sim().body().translation.z > 0.2);

    let setup = NavSetup {
        terrain,
        base: NavBase::Legged(LeggedBase {
            model,
            urdf,
            stepper,
        }),
        params,
        start: course.start,
        drift: opts.drift,
        seed: opts.seed,
    };
    let bus = run_on_bus(&setup, &opts, None).await.unwrap();
    assert_eq!(without_rate(bus.report), without_rate(direct));
}
