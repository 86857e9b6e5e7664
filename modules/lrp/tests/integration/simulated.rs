//! Trajectories executed by the simulated Controller on the true terrain: the leg never
//! strikes anything and the transition move ends with the foot planted on the footfall.

use crate::common;

use common::*;
use nalgebra::Point2;
use tca_controller_sim::sim::{LegSimulator, StartPose};
use tca_robot::{Course, ElbowBranch, HeightField, LegParams};

/// Plans from a planted foot at `from` to `to` and runs the `legMove` in the simulator.
fn walk_leg(
    terrain: &HeightField,
    body_y: f64,
    from: Point2<f64>,
    to: Point2<f64>,
    branch: ElbowBranch,
) {
    let branch = ElbowBranch::of(&planted(terrain, body_y, from, branch));
    let mut sim = LegSimulator::new(
        LegParams::default(),
        terrain.clone(),
        StartPose::PlantedAt {
            carriage_y_m: body_y,
            foot_xy: from,
            branch,
            force_n: 2224.1,
        },
    )
    .unwrap();
    let map = map_around(terrain, body_y);
    let start = sim.joint_leg_position();
    let plan = planner()
        .plan(&map, body_y, &start, &footfall(terrain, to))
        .unwrap_or_else(|e| panic!("{from} -> {to}: {e}"));
    let mv = plan.to_leg_move();
    assert!(mv.transition);
    let report = sim
        .leg_move(&plan.waypoints, true)
        .unwrap_or_else(|e| panic!("{from} -> {to}: the simulator refused or struck: {e}"));
    let contact = report.contact.expect("planted at the end");
    let off = (Point2::new(contact.foot_world.x, contact.foot_world.y) - to).norm();
    assert!(off < 0.02, "{from} -> {to}: landed {off} m off");
    // The planner's time estimate is close to the simulated one (blends add a little).
    let simulated = report.duration.as_secs_f64();
    assert!(
        simulated >= plan.motion.time_s * 0.9 && simulated <= plan.motion.time_s * 1.5 + 10.0,
        "{from} -> {to}: simulated {simulated} s, planned {} s",
        plan.motion.time_s
    );
}

#[test]
fn around_the_sun_box_on_course_3() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    walk_leg(
        &terrain,
        2.0,
        Point2::new(3.3, 1.0),
        Point2::new(3.3, 3.4),
        ElbowBranch::Positive,
    );
    walk_leg(
        &terrain,
        2.0,
        Point2::new(2.0, 1.2),
        Point2::new(4.4, 3.5),
        ElbowBranch::Negative,
    );
}

#[test]
fn over_the_steeplechase_pylons_on_course_2() {
    let terrain = Course::builtin(2).unwrap().height_field().unwrap();
    // Rows of pylons at y = 3.2 and 4.8: from one side of a pylon to the other.
    walk_leg(
        &terrain,
        3.2,
        Point2::new(3.7, 2.4),
        Point2::new(3.7, 4.0),
        ElbowBranch::Positive,
    );
    walk_leg(
        &terrain,
        4.8,
        Point2::new(4.4, 4.0),
        Point2::new(4.4, 5.6),
        ElbowBranch::Positive,
    );
}

#[test]
fn random_scenes_never_strike_terrain() {
    let mut planned = 0;
    for seed in 0..16 {
        let (terrain, a, b) = random_scene(seed);
        let map = map_around(&terrain, 4.0);
        let start = planted(&terrain, 4.0, a, ElbowBranch::Positive);
        // Scenes whose footfall is walled in are skipped (their failure is tested elsewhere).
        if planner()
            .plan(&map, 4.0, &start, &footfall(&terrain, b))
            .is_err()
        {
            continue;
        }
        walk_leg(&terrain, 4.0, a, b, ElbowBranch::Positive);
        planned += 1;
    }
    assert!(planned >= 10, "only {planned} scenes planned");
}
