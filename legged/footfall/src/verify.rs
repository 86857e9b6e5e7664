//! An outside check of a plan: every configuration along it, at most the resolution from
//! the next, keeps every margin (against the terrain it was planned on and the terrain as
//! it is), it passes through the lift and drop way-points above the start and the target,
//! and how many way-points its swing has.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::collision::{CheckerParams, LegChecker, Phase};
use crate::error::FootfallError;
use crate::plan::FootfallPlan;
use crate::scene::Scene;

/// What the check found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanCheck {
    /// Every margin kept, on the planning terrain and on the real one.
    pub margins_kept: bool,
    /// The first margin broken, if any.
    pub broken: Option<String>,
    /// The first way-point is `lift_m` straight above the start's wheel and the
    /// second-to-last `lift_m` straight above the goal's, within a millimetre.
    pub through_waypoints: bool,
    /// The swing's way-points (lift and drop included).
    pub swing_waypoints: usize,
    /// The swing has at most five way-points.
    pub at_most_five: bool,
    /// The plan starts at the scene's joints and ends with the wheel resting on the target.
    pub ends_right: bool,
}

impl PlanCheck {
    /// Everything holds.
    pub fn ok(&self) -> bool {
        self.margins_kept && self.through_waypoints && self.at_most_five && self.ends_right
    }
}

/// Checks `plan` in `scene` with the margins and resolution of `params` (its raise is
/// taken from the plan).
pub fn check_plan(
    scene: &std::sync::Arc<Scene>,
    plan: &FootfallPlan,
    params: &CheckerParams,
) -> Result<PlanCheck, FootfallError> {
    let leg = scene.leg_index(&plan.leg)?;
    let full = plan.full_path();
    if plan.waypoints.len() < 3 {
        return Err(FootfallError::Plan(format!(
            "a step has at least a lift, a drop and a goal way-point; this one has {}",
            plan.waypoints.len()
        )));
    }
    let raise = plan.heuristics.map_or(0.0, |h| h.raise_m);
    let mut broken = None;
    for raise_m in [raise, 0.0] {
        let checker = LegChecker::new(
            scene.clone(),
            leg,
            &CheckerParams {
                raise_m,
                ..params.clone()
            },
        )?;
        let n = full.len();
        let lift = &full[0..2];
        let swing = &full[1..n - 1];
        let drop = &full[n - 2..n];
        let found = checker
            .path_dense(lift, Phase::LiftOrDrop)
            .or_else(|| checker.path_dense(swing, Phase::Free))
            .or_else(|| checker.path_dense(drop, Phase::LiftOrDrop));
        if let Some((_, hit)) = found {
            broken = Some(format!("terrain raised {raise_m:.2} m: {hit}"));
            break;
        }
        if raise == 0.0 {
            break;
        }
    }
    let foot = |q: &[f64]| scene.foot_centre(leg, q);
    let n = full.len();
    let up = Vector3::z() * plan.lift_m;
    let lifted = (foot(&full[1]) - (foot(&full[0]) + up)).norm() <= 1e-3;
    let dropped = (foot(&full[n - 2]) - (foot(&full[n - 1]) + up)).norm() <= 1e-3;
    let l = &scene.model.legs()[leg];
    let goal = foot(&full[n - 1]);
    let rest = tca_legged_sim::collide::rest_height(
        &scene.terrain,
        nalgebra::Point2::new(goal.x, goal.y),
        l.foot_radius(),
    );
    let on_target = (goal.x - plan.target[0]).hypot(goal.y - plan.target[1]) <= 1e-3
        && (goal.z - rest).abs() <= 1e-3;
    let starts_here = full[0]
        .iter()
        .zip(&scene.posture[leg])
        .all(|(a, b)| (a - b).abs() <= 1e-9);
    let swing_waypoints = n - 2;
    Ok(PlanCheck {
        margins_kept: broken.is_none(),
        broken,
        through_waypoints: lifted && dropped,
        swing_waypoints,
        at_most_five: swing_waypoints <= 5,
        ends_right: on_target && starts_here,
    })
}
