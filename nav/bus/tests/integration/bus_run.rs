//! The navigation modules on the bus take the one-process loop's steps: same seeds, same
//! report; bad frames and goals are refused with a reason.

use std::sync::Arc;

use tca_nav_bus::{NavBase, NavSetup, run_on_bus};
use tca_nav_navigator::{
    RunOptions, RunReport, WheeledBase, WheeledParams, hill_course, run, wheeled_params,
};

fn without_rate(mut r: RunReport) -> RunReport {
    r.loop_hz = 0.0;
    r
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_run_on_the_bus_gives_the_one_process_report() {
    let course = hill_course().unwrap();
    let opts = RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed: 4,
        max_frames: 1500,
    };
    let mut base = WheeledBase::new(WheeledParams::PIONEER, &course.terrain, course.start);
    let (direct, nav) = run(&course.terrain, &mut base, wheeled_params(), &opts).unwrap();
    assert!(direct.reached, "{}", direct.reason);
    let setup = NavSetup {
        terrain: Arc::new(course.terrain.clone()),
        base: NavBase::Wheeled(WheeledParams::PIONEER),
        params: wheeled_params(),
        start: course.start,
        drift: opts.drift,
        seed: opts.seed,
    };
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("nav.mcap");
    let bus = run_on_bus(&setup, &opts, Some(log.clone())).await.unwrap();
    assert!(bus.report.loop_hz > 0.0);
    assert_eq!(without_rate(bus.report.clone()), without_rate(direct));
    // The LTM Manager's map is the one the navigator planned on.
    let mine = nav.danger();

    assert_eq!(bus.danger.nx(), mine.nx());
    for (a, b) in bus.danger.cells().iter().zip(mine.cells()) {
        assert_eq!(a.danger.is_finite(), b.danger.is_finite());
        if a.danger.is_finite() {
            assert!((a.danger - b.danger).abs() < 1e-6, "{a:?} {b:?}");
        }
        assert!((a.certainty - b.certainty).abs() < 1e-6, "{a:?} {b:?}");
    }
    assert!(std::fs::metadata(&log).unwrap().len() > 0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_impossible_goal_is_refused_with_a_reason() {
    let course = hill_course().unwrap();
    let setup = NavSetup {
        terrain: Arc::new(course.terrain.clone()),
        base: NavBase::Wheeled(WheeledParams::PIONEER),
        params: wheeled_params(),
        start: course.start,
        drift: 0.0,
        seed: 1,
    };
    let opts = RunOptions {
        start: course.start,
        goal_offset: [500.0, 0.0],
        drift: 0.0,
        seed: 1,
        max_frames: 10,
    };
    let r = run_on_bus(&setup, &opts, None).await.unwrap().report;
    assert!(!r.reached);
    assert!(r.reason.contains("outside the map"), "{}", r.reason);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_the_ltm_matcher_the_bus_run_is_the_one_process_run_too() {
    let course = hill_course().unwrap();
    let opts = RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed: 2,
        max_frames: 1500,
    };
    let mut params = wheeled_params();
    params.matcher = Some(tca_nav_navigator::MatchParams::default());
    let mut base = WheeledBase::new(WheeledParams::PIONEER, &course.terrain, course.start);
    let (direct, _) = run(&course.terrain, &mut base, params.clone(), &opts).unwrap();
    assert!(direct.registrations > 0, "{direct:?}");
    let setup = NavSetup {
        terrain: Arc::new(course.terrain.clone()),
        base: NavBase::Wheeled(WheeledParams::PIONEER),
        params,
        start: course.start,
        drift: opts.drift,
        seed: opts.seed,
    };
    let bus = run_on_bus(&setup, &opts, None).await.unwrap();
    assert_eq!(without_rate(bus.report), without_rate(direct));
}
