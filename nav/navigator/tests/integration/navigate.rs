//! The wheeled base finds its way around the hill, and over the ramps on a seed whose cut
//! corner once crossed ground never seen onto a ramp's raised side and on one that, seeing
//! only 1.6 m ahead, wandered north along the platform (every ramps seed is run by
//! `tca navigate --terrain ramps --seeds 8`).

use tca_nav_navigator::{
    Course, RunOptions, WheeledBase, WheeledParams, hill_course, ramps_course, run, wheeled_params,
};

fn drive(course: &Course, seed: u64) -> tca_nav_navigator::RunReport {
    let mut base = WheeledBase::new(WheeledParams::PIONEER, &course.terrain, course.start);
    let opts = RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed,
        max_frames: 3000,
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

#[test]
fn the_wheeled_base_crosses_the_platform_by_its_ramps() {
    check(&ramps_course().unwrap(), 2);
}

#[test]
fn the_wheeled_base_sees_far_enough_not_to_wander_along_the_platform() {
    check(&ramps_course().unwrap(), 1);
}

/// A base that is told to move and never does (stuck on something it cannot cross).
struct Stuck {
    pose: tca_nav_navigator::Pose2,
}

impl tca_nav_navigator::Base for Stuck {
    fn name(&self) -> &str {
        "stuck"
    }
    fn true_pose(&self) -> tca_nav_navigator::Pose2 {
        self.pose
    }
    fn attitude(&self) -> tca_nav_navigator::Attitude {
        tca_nav_navigator::Attitude::default()
    }
    fn drive(
        &mut self,
        _forward_mps: f64,
        _turn_rps: f64,
        _dt_s: f64,
    ) -> tca_nav_navigator::Motion {
        tca_nav_navigator::Motion {
            pose: self.pose,
            collided: true,
            fell: false,
        }
    }
}

#[test]
fn a_base_that_never_moves_ends_the_run_with_a_reason_after_the_stall_frames() {
    let course = hill_course().unwrap();
    let mut base = Stuck { pose: course.start };
    let opts = RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed: 1,
        max_frames: 3000,
    };
    let params = wheeled_params();
    let stall = params.stall_frames;
    assert!(stall > 0);
    let (r, _) = run(&course.terrain, &mut base, params, &opts).unwrap();
    assert!(!r.reached);
    assert!(r.reason.contains("no progress"), "{}", r.reason);
    assert!(
        r.reason.contains(&format!("{stall} frames")),
        "{}",
        r.reason
    );
    // It gave up once the estimate had stood still for the stall frames, not at the limit.
    assert_eq!(r.frames, stall, "{}", r.reason);
    assert_eq!(r.distance_m, 0.0);
}
