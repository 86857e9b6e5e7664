//! The Ambler walks its courses with an ideal executor on the true terrain.

use crate::common;

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
    println!("{}", w.describe(&format!("ambler {name}")));
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
