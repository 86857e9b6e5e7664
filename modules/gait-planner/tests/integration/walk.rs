//! Both planners walking the simulated leg down the obstacle courses, step after step, with
//! a perfect terrain map: the Gait Planner's footfalls are reachable by the Leg Recovery
//! Planner, its body moves are within the leg's extension, and nothing is ever struck.

use crate::common;

use common::*;
use nalgebra::Point2;
use tca_controller_sim::sim::{LegSimulator, StartPose};
use tca_gait_planner::GaitMaps;
use tca_lrp::{LegRecoveryPlanner, LrpParams, TerrainGrid};
use tca_robot::{Course, ElbowBranch, LegParams};

/// Walks from the carriage at `start_y` (foot planted at `foot`) to `goal_y`; returns the
/// number of steps.
fn walk(course: u32, start_y: f64, foot: Point2<f64>, goal_y: f64) -> usize {
    let terrain = Course::builtin(course).unwrap().height_field().unwrap();
    let mut sim = LegSimulator::new(
        LegParams::default(),
        terrain.clone(),
        StartPose::PlantedAt {
            carriage_y_m: start_y,
            foot_xy: foot,
            branch: ElbowBranch::Positive,
            force_n: 2224.1,
        },
    )
    .unwrap();
    let lrp = LegRecoveryPlanner::new(LegParams::default(), LrpParams::default()).unwrap();
    let gait = planner();
    for step in 1..=20 {
        let body_y = sim.body_position().y_m;
        if (goal_y - body_y).abs() <= 0.02 {
            return step - 1;
        }
        let (footfall, elevation) = maps_for(&terrain, body_y, goal_y);
        let lrp_map = TerrainGrid::elevation_from_height_field(
            &terrain,
            Point2::new(0.0, body_y - 2.9),
            Point2::new(6.0, body_y + 2.9),
            0.05,
        )
        .unwrap();
        let cs = lrp.cspace(&lrp_map, body_y).unwrap();
        let joints = sim.joint_leg_position();
        let reach = lrp.reachability(&cs, &joints).unwrap();
        let plan = gait
            .plan(
                body_y,
                goal_y,
                &GaitMaps {
                    footfall: &footfall,
                    elevation: &elevation,
                    reachable: &|p| reach.reaches(p),
                },
            )
            .unwrap_or_else(|e| panic!("course {course} step {step} at y = {body_y:.2}: {e}"));
        let leg = lrp
            .plan_in(&cs, &joints, &plan.footfall)
            .unwrap_or_else(|e| panic!("course {course} step {step}: {e}"));
        sim.leg_move(&leg.waypoints, true).unwrap_or_else(|e| {
            panic!(
                "course {course} step {step}: leg move to {} failed: {e}",
                plan.footfall
            )
        });
        eprintln!(
            "course {course} step {step}: body {body_y:.2} -> {:.2}, footfall ({:.2}, {:.2}, {:.2}), leg {:.0} s {} turns, clock {:.0} s",
            plan.body_target_y_m,
            plan.footfall.x,
            plan.footfall.y,
            plan.footfall.z,
            leg.motion.time_s,
            leg.turns,
            sim.clock().as_secs_f64()
        );
        sim.body_move(plan.body_target_y_m).unwrap_or_else(|e| {
            panic!(
                "course {course} step {step}: body move to {:.2} failed: {e}",
                plan.body_target_y_m
            )
        });
    }
    panic!("course {course}: not at the goal after 20 steps");
}

#[test]
fn course_3_forward_around_the_sun_box() {
    let steps = walk(3, 1.0, Point2::new(3.8, 0.6), 9.5);
    assert!(steps <= 9, "{steps} steps");
}

#[test]
fn course_2_forward_through_the_steeplechase() {
    let steps = walk(2, 1.0, Point2::new(2.4, 1.2), 9.5);
    assert!(steps <= 9, "{steps} steps");
}

#[test]
fn course_4_backward() {
    let steps = walk(4, 9.5, Point2::new(3.6, 10.0), 1.0);
    assert!(steps <= 10, "{steps} steps");
}
