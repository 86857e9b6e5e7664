//! Properties of single steps planned from random standing states.

use std::sync::Arc;

use nalgebra::Point2;
use proptest::prelude::*;
use tca_free_gait::{Action, FreeGait, GaitError, GaitParams, GridView, stand};
use tca_legged_model::RobotModel;
use tca_robot::HeightField;

fn terrain(seed: f64, amplitude: f64) -> GridView {
    let (nx, ny) = (281, 141);
    let mut h = Vec::with_capacity(nx * ny);
    for iy in 0..ny {
        for ix in 0..nx {
            let (x, y) = (ix as f64 * 0.1, iy as f64 * 0.1 - 7.0);
            let d = (x - 5.0).hypot(y);
            let w = ((d - 3.5) / 1.5).clamp(0.0, 1.0);
            h.push(w * amplitude * ((x * 1.3 + seed).sin() * (y * 0.9 - seed).cos()));
        }
    }
    GridView::new(Arc::new(
        HeightField::new(Point2::new(0.0, -7.0), 0.1, nx, ny, h).expect("terrain"),
    ))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Every planned step keeps the margin, names real legs, and swings end below their
    /// foothold; the goal within tolerance is reported as reached.
    #[test]
    fn planned_steps_keep_the_margin(
        seed in 0.0f64..10.0,
        amplitude in 0.0f64..0.25,
        goal_x in -10.0f64..10.0,
        goal_y in -5.0f64..5.0,
        yaw in -0.5f64..0.5,
    ) {
        let model = Arc::new(RobotModel::builtin("ambler").unwrap());
        let params = GaitParams::for_model(&model);
        let gait = FreeGait::new(model.clone(), params.clone());
        let view = terrain(seed, amplitude);
        let state = stand(&model, &view, 5.0, 0.0, yaw).unwrap();
        let goal = Point2::new(5.0 + goal_x, goal_y);
        let mut state = state;
        for _ in 0..4 {
            match gait.plan_step(&state, &view, goal) {
                Ok(plan) => {
                    prop_assert!(plan.min_margin_m >= params.min_margin_m - 1e-9);
                    prop_assert!(!plan.actions.is_empty());
                    for a in &plan.actions {
                        if let Action::Swing { leg, waypoints, foothold } = a {
                            prop_assert!(*leg < model.legs().len());
                            prop_assert!(!waypoints.is_empty());
                            let l = &model.legs()[*leg];
                            let last = waypoints.last().unwrap();
                            prop_assert!(l.within_limits(last));
                            let centre = plan.end.body * l.foot_position(last).unwrap();
                            prop_assert!(centre.z - l.foot_radius() < foothold.z);
                        }
                    }
                    let (_, m) = gait.stability(&plan.end).unwrap();
                    prop_assert!(m >= params.min_margin_m - 1e-6);
                    state = plan.end;
                }
                Err(GaitError::GoalReached { distance_m }) => {
                    prop_assert!(distance_m <= params.goal_tolerance_m);
                    break;
                }
                Err(e) => {
                    // A refusal must say why.
                    prop_assert!(!e.to_string().is_empty());
                    break;
                }
            }
        }
    }
}

#[test]
fn bad_states_are_refused_with_a_reason() {
    let model = Arc::new(RobotModel::builtin("ambler").unwrap());
    let gait = FreeGait::new(model.clone(), GaitParams::for_model(&model));
    let view = terrain(1.0, 0.0);
    let mut state = stand(&model, &view, 5.0, 0.0, 0.0).unwrap();
    state.legs.pop();
    let e = gait
        .plan_step(&state, &view, Point2::new(10.0, 0.0))
        .unwrap_err();
    assert!(matches!(e, GaitError::BadState { .. }), "{e}");
    let mut state = stand(&model, &view, 5.0, 0.0, 0.0).unwrap();
    for l in state.legs.iter_mut().take(4) {
        l.stance = false;
    }
    let e = gait
        .plan_step(&state, &view, Point2::new(10.0, 0.0))
        .unwrap_err();
    assert!(matches!(e, GaitError::Unstable { .. }), "{e}");
    let state = stand(&model, &view, 5.0, 0.0, 0.0).unwrap();
    let e = gait
        .plan_step(&state, &view, Point2::new(5.1, 0.0))
        .unwrap_err();
    assert!(matches!(e, GaitError::GoalReached { .. }), "{e}");
    assert!(gait.reached(&state, Point2::new(5.1, 0.0), 0.2));
}

#[test]
fn unknown_ground_is_never_stepped_on() {
    // A view that knows only the ground behind x = 6.
    struct Behind(GridView);
    impl tca_free_gait::TerrainView for Behind {
        fn height_at(&self, p: Point2<f64>) -> Option<f64> {
            (p.x < 6.0).then(|| self.0.height_at(p)).flatten()
        }
        fn max_height_in_disc(&self, c: Point2<f64>, r: f64) -> Option<f64> {
            (c.x + r < 6.0)
                .then(|| self.0.max_height_in_disc(c, r))
                .flatten()
        }
        fn foothold_cost(&self, p: Point2<f64>, r: f64) -> Option<f64> {
            (p.x + r < 6.0)
                .then(|| self.0.foothold_cost(p, r))
                .flatten()
        }
    }
    let model = Arc::new(RobotModel::builtin("ambler").unwrap());
    let gait = FreeGait::new(model.clone(), GaitParams::for_model(&model));
    let view = Behind(terrain(1.0, 0.0));
    let mut state = stand(&model, &view, 4.0, 0.0, 0.0).unwrap();
    for _ in 0..30 {
        match gait.plan_step(&state, &view, Point2::new(15.0, 0.0)) {
            Ok(plan) => {
                for a in &plan.actions {
                    if let Action::Swing { foothold, .. } = a {
                        assert!(
                            foothold.x < 6.0,
                            "stepped on unknown ground at {foothold:?}"
                        );
                    }
                }
                state = plan.end;
            }
            Err(e) => {
                assert!(!matches!(e, GaitError::GoalReached { .. }));
                return;
            }
        }
    }
}
