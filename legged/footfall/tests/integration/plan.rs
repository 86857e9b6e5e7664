//! Planning one step: over a rock on flat ground, on the rock field with both planners,
//! the plan file, refusals.

use std::sync::Arc;

use nalgebra::{Point2, Vector3};
use tca_footfall::collision::{CheckerParams, LegChecker, Phase};
use tca_footfall::plan::{FootfallPlan, PlanOptions, PlannerKind, StepPlanner};
use tca_footfall::verify::check_plan;
use tca_footfall::{FootfallError, Scene};
use tca_legged_model::RobotModel;
use tca_legged_sim::StartPose;
use tca_robot::HeightField;

/// The athlete standing at the origin of flat ground with a rock of `height` at `rock`.
fn rock_scene(rock: Point2<f64>, radius: f64, height: f64) -> Scene {
    let (nx, ny, res) = (241, 241, 0.05);
    let origin = Point2::new(-6.0, -6.0);
    let mut h = Vec::with_capacity(nx * ny);
    for iy in 0..ny {
        for ix in 0..nx {
            let p = Point2::new(origin.x + ix as f64 * res, origin.y + iy as f64 * res);
            let d = (p - rock).norm() / radius;
            h.push(if d < 1.0 {
                height * (0.5 + 0.5 * (std::f64::consts::PI * d).cos())
            } else {
                0.0
            });
        }
    }
    let terrain = HeightField::new(origin, res, nx, ny, h).unwrap();
    let model = RobotModel::builtin("athlete").unwrap();
    Scene::standing(
        Arc::new(model),
        Arc::new(terrain),
        StartPose {
            x_m: 0.0,
            y_m: 0.0,
            yaw_rad: 0.0,
        },
    )
    .unwrap()
}

fn checker_params() -> CheckerParams {
    CheckerParams::default()
}

#[test]
fn a_step_over_a_rock_clears_it_and_keeps_every_margin() {
    // left_front stands at 30 degrees, 2.75 m out: (2.38, 1.375). The target is 0.9 m to
    // its left, with a rock 30 cm high and 36 cm across half-way.
    let start = Point2::new(
        2.75 * 30f64.to_radians().cos(),
        2.75 * 30f64.to_radians().sin(),
    );
    let target = start + nalgebra::Vector2::new(0.0, 0.9);
    let rock = start + nalgebra::Vector2::new(0.0, 0.45);
    let scene = Arc::new(rock_scene(rock, 0.18, 0.30));
    let leg = scene.leg_index("left_front").unwrap();
    let planner = StepPlanner::new(scene.clone(), PlanOptions::default()).unwrap();
    for kind in [PlannerKind::Sbl, PlannerKind::Astar] {
        let mut o = planner.options().clone();
        o.planner = kind;
        let plan = planner.plan_with(leg, target, &o).unwrap();
        let check = check_plan(&scene, &plan, &checker_params()).unwrap();
        assert!(check.ok(), "{kind:?}: {check:?}");
        assert!(
            plan.swing_waypoints <= 5,
            "{kind:?}: {}",
            plan.swing_waypoints
        );
        // Wherever the wheel passes over the rock, it keeps its margin from the rock raised
        // by the heuristic's 15 cm (sampled every 2 cm, so a centimetre's slack).
        let mut over = 0;
        for p in &plan.foot_path {
            let at = Point2::new(p[0], p[1]);
            if (at - rock).norm() < 0.18 + 0.25 {
                over += 1;
                // The wheel's distance from the rock's surface raised 15 cm.
                let mut gap = f64::INFINITY;
                for i in -20..=20 {
                    for j in -20..=20 {
                        let (x, y) = (p[0] + i as f64 * 0.02, p[1] + j as f64 * 0.02);
                        let z = scene.terrain.height_at(x, y) + 0.15;
                        let d =
                            ((x - p[0]).powi(2) + (y - p[1]).powi(2) + (z - p[2]).powi(2)).sqrt();
                        gap = gap.min(d - 0.25);
                    }
                }
                assert!(
                    gap > 0.04 - 0.01,
                    "{kind:?}: {p:?} only {gap:.3} m from the raised rock"
                );
            }
        }
        assert!(over > 0, "{kind:?}: the foot never passes over the rock");
    }
}

#[test]
fn rock_field_steps_plan_fast_and_round_trip_through_json() {
    let scene = Arc::new(Scene::rock_field(1).unwrap());
    let planner = StepPlanner::new(scene.clone(), PlanOptions::default()).unwrap();
    let pairs = tca_footfall::campaign::draw_pairs(&scene, &planner.options().map, 4, 7).unwrap();
    for (leg, target) in pairs {
        let plan = planner.plan(leg, target).unwrap();
        let check = check_plan(&scene, &plan, &checker_params()).unwrap();
        assert!(check.ok(), "{check:?}");
        let back = FootfallPlan::from_json(&plan.to_json()).unwrap();
        assert_eq!(
            (&back.leg, back.target, back.swing_waypoints),
            (&plan.leg, plan.target, plan.swing_waypoints)
        );
        for (a, b) in back.full_path().iter().zip(plan.full_path()) {
            assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-12));
        }
        // The way-points sent end pressed into the ground below the goal.
        let sent = plan.leg_move_waypoints();
        assert_eq!(sent.len(), plan.waypoints.len());
        let l = &scene.model.legs()[leg];
        let goal = l.foot_position(plan.waypoints.last().unwrap()).unwrap();
        let pressed = l.foot_position(sent.last().unwrap()).unwrap();
        assert!(((goal - pressed) - Vector3::new(0.0, 0.0, plan.press_m)).norm() < 2e-3);
    }
}

#[test]
fn bad_targets_and_plans_are_refused_saying_why() {
    let scene = Arc::new(Scene::rock_field(1).unwrap());
    let planner = StepPlanner::new(scene.clone(), PlanOptions::default()).unwrap();
    let leg = scene.leg_index("left_front").unwrap();
    // Far out of reach.
    let e = planner.plan(leg, Point2::new(13.0, 6.0)).unwrap_err();
    assert!(
        matches!(e, FootfallError::BadTarget { .. }) && e.to_string().contains("cannot reach"),
        "{e}"
    );
    // Under the body: reached but not stable, or not reachable.
    let e = planner.plan(leg, Point2::new(7.0, 0.3)).unwrap_err();
    assert!(matches!(e, FootfallError::BadTarget { .. }), "{e}");
    let e = FootfallPlan::from_json("{\"leg\": 3}").unwrap_err();
    assert!(e.to_string().contains("tca footfall plan"), "{e}");
    assert!(
        scene
            .leg_index("tail")
            .unwrap_err()
            .to_string()
            .contains("left_front")
    );
}

#[test]
fn the_checker_finds_a_leg_pushed_into_the_body_and_the_ground() {
    let scene = Arc::new(Scene::rock_field(1).unwrap());
    let leg = scene.leg_index("right_middle").unwrap();
    let c = LegChecker::new(scene.clone(), leg, &checker_params()).unwrap();
    let q0 = scene.posture[leg].clone();
    // Standing: only the wheel touches the ground, which the lift rules allow.
    assert!(c.check(&q0, Phase::LiftOrDrop).is_none());
    let hit = c.check(&q0, Phase::Free).unwrap();
    assert_eq!(hit.other, "terrain");
    // The knee folded up and in hits the chassis.
    let mut q = q0.clone();
    q[1] = 1.3;
    q[2] = -1.5;
    let hit = c.check(&q, Phase::Free).unwrap();
    assert!(hit.other == "body" || hit.other.contains("right_"), "{hit}");
    // The thigh pitched down drives the knee into the ground.
    let mut q = q0.clone();
    q[1] = -1.0;
    assert!(c.check(&q, Phase::Free).is_some());
    // Outside the limits.
    let mut q = q0;
    q[0] = 5.0;
    assert_eq!(c.check(&q, Phase::Free).unwrap().other, "joint limits");
}
