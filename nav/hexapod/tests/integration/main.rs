//! The shipped hexapod walks the hill course (Figure 9's) to its goal with every acceptance
//! limit met: the seed that once stopped on the hill's edge with no step to take.

use std::sync::Arc;

use tca_legged_model::RobotModel;
use tca_nav_hexapod::{HexapodBase, StepperParams, hexapod_params};
use tca_nav_navigator::{RunOptions, hill_course, run};

#[test]
fn the_hexapod_walks_around_the_hill_within_every_limit() {
    let course = hill_course().unwrap();
    let model = Arc::new(RobotModel::builtin("hexapod").unwrap());
    let terrain = Arc::new(course.terrain.clone());
    let params = hexapod_params(&model).unwrap();
    let mut base = HexapodBase::new(
        model.clone(),
        terrain,
        course.start,
        StepperParams::for_model(&model),
    )
    .unwrap();
    let opts = RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed: 7,
        max_frames: 600,
    };
    let (r, _) = run(&course.terrain, &mut base, params, &opts).unwrap();
    let best = r.true_map_path_m.expect("the hill can be walked round");
    eprintln!(
        "hexapod, hill, seed 7: {} ({}), {:.2} m against {best:.2} m, final error {:.3} m, {} frames in untraversable cells",
        r.reached, r.reason, r.distance_m, r.final_error_m, r.untraversable_frames
    );
    assert!(r.reached, "{}", r.reason);
    assert_eq!(r.untraversable_frames, 0, "frames in untraversable cells");
    assert_eq!((r.collisions, r.falls), (0, 0));
    assert!(
        r.final_error_m <= 0.03 * r.distance_m,
        "final error {:.3} m over {:.2} m",
        r.final_error_m,
        r.distance_m
    );
    assert!(
        r.distance_m <= 1.25 * best,
        "walked {:.2} m against {best:.2} m",
        r.distance_m
    );
    assert!(r.meets_acceptance());
}
