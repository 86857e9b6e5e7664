//! The wheeled base finds its way around the hill (the ramps course, longer, is run by
//! `tca navigate`).

use tca_nav_navigator::{
    Course, RunOptions, WheeledBase, WheeledParams, hill_course, run, wheeled_params,
};

fn drive(course: &Course, seed: u64) -> tca_nav_navigator::RunReport {
    let mut base = WheeledBase::new(WheeledParams::PIONEER, &course.terrain, course.start);
    let opts = RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed,
        max_frames: 1500,
    };
    let (report, nav) = run(&course.terrain, &mut base, wheeled_params(), &opts).unwrap();
    if std::env::var_os("NAV_PICTURE").is_some() {
        tca_nav_navigator::write_picture(
            nav.danger(),
            &report,
            format!("/tmp/nav-{}-{seed}.png", course.name),
        )
        .unwrap();
    }
    report
}

fn check(course: &Course, seed: u64) {
    let r = drive(course, seed);
    eprintln!(
        "{} seed {seed}: reached {} ({}), {:.2} m, final error {:.3} m, estimate error {:.3} m, {} replans, {} turns, {} frames, {:.1} Hz, true path {:?}",
        course.name,
        r.reached,
        r.reason,
        r.distance_m,
        r.final_error_m,
        r.estimate_error_m,
        r.replans,
        r.exploration_turns,
        r.frames,
        r.loop_hz,
        r.true_map_path_m
    );
    assert!(r.reached, "{}", r.reason);
    assert!(
        r.final_error_m <= 0.03 * r.distance_m,
        "final error {} over {} m",
        r.final_error_m,
        r.distance_m
    );
    assert_eq!(r.collisions, 0);
    assert_eq!(r.falls, 0);
    assert_eq!(r.untraversable_frames, 0);
    let best = r.true_map_path_m.expect("the course has a path");
    assert!(
        r.distance_m <= 1.25 * best,
        "driven {} m against {} m on the true map",
        r.distance_m,
        best
    );
}

#[test]
fn the_wheeled_base_goes_around_the_hill() {
    check(&hill_course().unwrap(), 1);
}
