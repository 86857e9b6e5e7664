//! Every built-in course walked by the robot it is made for, with the ideal executor on
//! the course's true terrain.

use crate::common;

use std::sync::Arc;

use common::walk;
use tca_legged_courses::Course;
use tca_legged_model::RobotModel;

fn course(name: &str) {
    let c = Course::builtin(name, 1).expect("the course builds");
    let model = Arc::new(RobotModel::builtin(c.robot_hint).expect("the robot loads"));
    let w = walk(
        name,
        model,
        Arc::new(c.terrain),
        (c.start.x_m, c.start.y_m, c.start.yaw_rad),
        c.goal,
        600,
    );
    println!(
        "{}",
        w.describe(&format!("course {name} ({})", c.robot_hint))
    );
    assert!(w.reached, "{name}: {w:?}");
}

#[test]
fn course_flat() {
    course("flat");
}

#[test]
fn course_rough() {
    course("rough");
}

#[test]
fn course_boulders() {
    course("boulders");
}

#[test]
fn course_ditch() {
    course("ditch");
}

#[test]
fn course_slope() {
    course("slope");
}

#[test]
fn course_hexapod_flat() {
    course("hexapod-flat");
}

#[test]
fn course_hexapod_rough() {
    course("hexapod-rough");
}
