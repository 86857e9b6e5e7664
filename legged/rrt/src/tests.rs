//! Whole-planner tests on small terrains.

use std::sync::Arc;

use nalgebra::Point2;
use tca_legged_model::RobotModel;
use tca_robot::HeightField;

use crate::{Planner, RrtParams};

fn field(nx: usize, ny: usize, f: impl Fn(f64, f64) -> f64) -> Arc<HeightField> {
    let r = 0.02;
    let mut h = Vec::new();
    for iy in 0..ny {
        for ix in 0..nx {
            h.push(f(ix as f64 * r, iy as f64 * r - (ny - 1) as f64 * r / 2.0));
        }
    }
    Arc::new(
        HeightField::new(Point2::new(0.0, -((ny - 1) as f64) * r / 2.0), r, nx, ny, h).unwrap(),
    )
}

fn hexapod() -> Arc<RobotModel> {
    Arc::new(RobotModel::builtin("hexapod").unwrap())
}

#[test]
fn neutral_posture_on_flat_ground_is_level_and_stable() {
    let p = Planner::new(hexapod(), field(150, 90, |_, _| 0.0), RrtParams::default()).unwrap();
    let q = p.posture_at(Point2::new(1.0, 0.0), 0.0).unwrap();
    assert!(q.body.roll.abs() < 1e-9 && q.body.pitch.abs() < 1e-9);
    assert!(
        (q.body.z - p.robot().neutral_height()).abs() < 0.01,
        "{}",
        q.body.z
    );
    assert!(q.margin_m > 0.05);
    // Too near the edge for the feet.
    assert!(p.posture_at(Point2::new(0.05, 0.0), 0.0).is_err());
}

#[test]
fn flat_ground_is_planned_straight_and_every_move_is_stable() {
    let p = Planner::new(hexapod(), field(150, 90, |_, _| 0.0), RrtParams::default()).unwrap();
    let plan = p
        .plan(Point2::new(0.6, 0.0), 0.0, Point2::new(1.7, 0.0))
        .unwrap();
    let first = plan.postures.first().unwrap().body.xy();
    let last = plan.postures.last().unwrap().body.xy();
    assert!((first - Point2::new(0.6, 0.0)).norm() < 1e-9);
    assert!((last - Point2::new(1.7, 0.0)).norm() < 1e-9);
    assert_eq!(plan.transitions.len(), plan.postures.len() - 1);
    assert!(plan.length_m() < 1.1 * 1.1, "{}", plan.length_m());
    for t in &plan.transitions {
        assert!(t.min_margin_m >= p.params().stability_margin_m * 0.5);
        assert_eq!(t.phases.len(), 2);
    }
    // Consecutive postures are at most a step apart.
    for w in plan.postures.windows(2) {
        assert!((w[1].body.xy() - w[0].body.xy()).norm() <= p.params().max_step_m + 1e-9);
    }
}

#[test]
fn a_tall_wall_across_the_map_gives_no_path_with_its_reason() {
    let wall = |x: f64, _y: f64| if (1.1..1.2).contains(&x) { 0.4 } else { 0.0 };
    let params = RrtParams {
        max_iterations: 150,
        ..RrtParams::default()
    };
    let p = Planner::new(hexapod(), field(150, 90, wall), params).unwrap();
    let err = p
        .plan(Point2::new(0.6, 0.0), 0.0, Point2::new(1.7, 0.0))
        .unwrap_err();
    let text = err.to_string();
    assert!(text.contains("no path after 150 iterations"), "{text}");
}

#[test]
fn a_goal_off_the_map_is_refused() {
    let p = Planner::new(hexapod(), field(150, 90, |_, _| 0.0), RrtParams::default()).unwrap();
    let err = p
        .plan(Point2::new(0.6, 0.0), 0.0, Point2::new(5.0, 0.0))
        .unwrap_err();
    assert!(err.to_string().contains("goal"), "{err}");
}

#[test]
fn the_walls_course_is_crossed_over_the_low_wall_and_round_the_steep_hill() {
    use tca_legged_courses::{Course, walls};
    let course = Course::builtin("hexapod-walls", 1).unwrap();
    let p = Planner::new(
        hexapod(),
        Arc::new(course.terrain.clone()),
        RrtParams::default(),
    )
    .unwrap();
    let start = Point2::new(course.start.x_m, course.start.y_m);
    let plan = p.plan(start, course.start.yaw_rad, course.goal).unwrap();
    assert!((plan.postures.last().unwrap().body.xy() - course.goal).norm() < 1e-9);
    let (hill, hill_r, _) = walls::STEEP_HILL;
    let hill = Point2::new(hill[0], hill[1]);
    let mut crossed = false;
    for (w, t) in plan.postures.windows(2).zip(&plan.transitions) {
        let (a, b) = (w[0].body.xy(), w[1].body.xy());
        if a.x < walls::WALL_X_M.1 && b.x >= walls::WALL_X_M.0
            || b.x < walls::WALL_X_M.1 && a.x >= walls::WALL_X_M.0
        {
            assert!(
                a.y < walls::WALL_SPLIT_Y_M && b.y < walls::WALL_SPLIT_Y_M,
                "crosses the high wall: {a} {b}"
            );
            crossed = true;
        }
        assert!(t.min_margin_m > 0.0);
        for phase in &t.phases {
            for s in &phase.swings {
                // Every swing starts on the old foothold and ends on the new one.
                assert_eq!(s.path.first(), Some(&w[0].feet[s.leg]));
                assert_eq!(s.path.last(), Some(&w[1].feet[s.leg]));
            }
        }
    }
    assert!(crossed);
    // Over the low wall the body rose to keep its clearance.
    let over = plan
        .postures
        .iter()
        .filter(|q| (walls::WALL_X_M.0..=walls::WALL_X_M.1).contains(&q.body.x))
        .map(|q| q.body.z)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        over >= walls::LOW_WALL_M + p.params().body_clearance_m,
        "{over}"
    );
    for q in &plan.postures {
        assert!(
            (q.body.xy() - hill).norm() > hill_r * 0.75,
            "over the steep hill at {}",
            q.body.xy()
        );
        for f in &q.feet {
            assert!(
                p.terrain()
                    .foothold_quality(Point2::new(f.x, f.y))
                    .is_finite()
            );
        }
    }
}
