//! The Ambler walks its courses with an ideal executor on the true terrain.

mod common;

use std::sync::Arc;

use common::{Walk, ambler_courses as courses, walk};
use nalgebra::Point2;
use tca_free_gait::GaitError;
use tca_legged_model::RobotModel;
use tca_robot::HeightField;

fn ambler() -> Arc<RobotModel> {
    Arc::new(RobotModel::builtin("ambler").expect("the Ambler loads"))
}

fn go(name: &str, terrain: Arc<HeightField>) -> Walk {
    let goal = Point2::new(courses::GOAL.0, courses::GOAL.1);
    let w = walk(name, ambler(), terrain, courses::START, goal, 600);
    println!(
        "ambler {name}: reached {} in {} steps, {:.2} s ({:.1} ms planning per step), min margin {:.3} m executed / {:.3} m planned, {:.2} m left{}",
        w.reached,
        w.steps,
        w.seconds,
        w.planning_ms_per_step,
        w.min_margin,
        w.min_planned_margin,
        w.final_distance,
        w.error
            .as_ref()
            .map(|e| format!(": {e}"))
            .unwrap_or_default()
    );
    w
}

#[test]
fn ambler_walks_flat_ground_20_m() {
    let w = go("flat", courses::flat());
    assert!(w.reached, "{w:?}");
}

#[test]
fn ambler_walks_rough_ground_20_m() {
    let w = go("rough", courses::rough());
    assert!(w.reached, "{w:?}");
}

#[test]
fn ambler_crosses_the_boulder_field() {
    let w = go("boulders", courses::boulders());
    assert!(w.reached, "{w:?}");
}

#[test]
fn ambler_crosses_the_ditch() {
    let w = go("ditch", courses::ditch());
    assert!(w.reached, "{w:?}");
}

#[test]
fn ambler_climbs_the_25_degree_slope() {
    let w = go("slope", courses::slope());
    assert!(w.reached, "{w:?}");
}

#[test]
fn ambler_stops_at_a_chasm_with_a_reason() {
    let w = go("chasm", courses::chasm());
    assert!(!w.reached);
    let e = w.error.expect("the walk ends with an error");
    assert!(!matches!(e, GaitError::GoalReached { .. }));
    assert!(w.final_distance > 8.0);
}
