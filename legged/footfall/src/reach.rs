//! Placing a foot with a given orientation: the wheel's centre at a point and the axis of
//! the leg's last joint (ATHLETE's steering axis, along the wheel's fork) along a given
//! direction, by damped least squares over every joint but the last.
//!
//! A limb of six joints whose last one turns about its own axis at the foot (the wheel's
//! steering) places the foot's centre and that axis with its first five joints: five
//! equations in five unknowns, so that a given orientation leaves finitely many solutions,
//! as the analytic solution of the real rover's limbs does. The last joint only turns the
//! wheel about the fork; it keeps the value it starts with. A leg of fewer than five joints,
//! or whose last joint is not revolute, is placed by position only.

use nalgebra::{DMatrix, DVector, Point3, Unit, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_legged_model::{JointKind, Leg};

/// How close a placement must come.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReachTolerance {
    /// Distance from the foot's centre to its target, metres.
    pub position_m: f64,
    /// Angle between the foot's axis and its target direction, radians.
    pub axis_rad: f64,
    /// Steps allowed from each start.
    pub max_iterations: usize,
}

impl Default for ReachTolerance {
    fn default() -> Self {
        Self {
            position_m: 1e-3,
            axis_rad: 0.01,
            max_iterations: 60,
        }
    }
}

/// Where the foot should be, in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootGoal {
    /// The foot sphere's centre.
    pub centre: Point3<f64>,
    /// The direction of the last joint's axis, or `None` to place the centre only.
    pub axis: Option<Unit<Vector3<f64>>>,
}

/// Whether a leg has a steering joint whose axis the orientation fixes: at least five
/// joints, the last revolute.
pub fn has_steering_axis(leg: &Leg) -> bool {
    leg.dof() >= 5
        && matches!(
            leg.joints().last().map(|j| j.kind()),
            Some(JointKind::Revolute { .. })
        )
}

/// The axis of the leg's last joint in the body frame for joints `q` (the steering axis of
/// a wheel), or `None` for a leg without one ([`has_steering_axis`]).
pub fn foot_axis(leg: &Leg, q: &[f64]) -> Option<Unit<Vector3<f64>>> {
    if !has_steering_axis(leg) {
        return None;
    }
    let frames = leg.joint_frames(q).ok()?;
    let last = leg.joints().last()?;
    let JointKind::Revolute { axis } = last.kind() else {
        return None;
    };
    let frame = frames.last()?;
    Some(Unit::new_normalize(frame.rotation * axis.into_inner()))
}

/// The vertical the foot's axis keeps when the orientation is "upright": straight up or
/// down in the world (`world_down` is the world's -Z seen in the body frame), on the side
/// the axis points to in the leg's neutral position.
pub fn upright_axis(leg: &Leg, world_down: Unit<Vector3<f64>>) -> Option<Unit<Vector3<f64>>> {
    let neutral = foot_axis(leg, &leg.neutral())?;
    let down = world_down.into_inner();
    Some(if neutral.dot(&down) >= 0.0 {
        Unit::new_unchecked(down)
    } else {
        Unit::new_unchecked(-down)
    })
}

/// Joint positions within the limits that place the foot at `goal`, trying each start in
/// turn (the last joint keeps each start's value); `None` when none reaches.
pub fn place_foot(
    leg: &Leg,
    goal: &FootGoal,
    starts: &[&[f64]],
    tolerance: &ReachTolerance,
) -> Option<Vec<f64>> {
    place_foot_where(leg, goal, starts, tolerance, |_| true)
}

/// As [`place_foot`], taking the first solution `accept` accepts (say, one that keeps the
/// leg clear of the rest of the robot): a foot can often be placed in several ways.
pub fn place_foot_where(
    leg: &Leg,
    goal: &FootGoal,
    starts: &[&[f64]],
    tolerance: &ReachTolerance,
    accept: impl Fn(&[f64]) -> bool,
) -> Option<Vec<f64>> {
    let beyond = (goal.centre - leg.base_position()).norm() - leg.reach_bound();
    if beyond > tolerance.position_m || !goal.centre.coords.iter().all(|v| v.is_finite()) {
        return None;
    }
    starts
        .iter()
        .filter(|s| s.len() == leg.dof())
        .filter_map(|s| descend(leg, goal, leg.clamp(s), tolerance))
        .find(|q| accept(q))
}

/// As [`place_foot_where`], then from `random` random starts drawn with `seed` (the
/// brute-force check's exhaustive search).
pub fn place_foot_thoroughly(
    leg: &Leg,
    goal: &FootGoal,
    starts: &[&[f64]],
    random: usize,
    seed: u64,
    tolerance: &ReachTolerance,
    accept: impl Fn(&[f64]) -> bool,
) -> Option<Vec<f64>> {
    if let Some(q) = place_foot_where(leg, goal, starts, tolerance, &accept) {
        return Some(q);
    }
    let beyond = (goal.centre - leg.base_position()).norm() - leg.reach_bound();
    if beyond > tolerance.position_m {
        return None;
    }
    let steer = starts.first().and_then(|s| s.last().copied());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for _ in 0..random {
        let mut q: Vec<f64> = leg
            .joints()
            .iter()
            .map(|j| {
                let l = j.limits();
                rng.random_range(l.lower..=l.upper)
            })
            .collect();
        if let (Some(s), Some(last)) = (steer, q.last_mut()) {
            *last = s;
        }
        if let Some(q) = descend(leg, goal, q, tolerance).filter(|q| accept(q)) {
            return Some(q);
        }
    }
    None
}

/// The residual of a placement: position error (metres) and axis error (the difference of
/// unit vectors, about the angle in radians).
fn residual(leg: &Leg, goal: &FootGoal, q: &[f64]) -> (Vector3<f64>, Vector3<f64>, f64, f64) {
    let p = leg.foot_position(q).unwrap_or_else(|_| Point3::origin());
    let dp = goal.centre - p;
    let (da, angle) = match (goal.axis, foot_axis(leg, q)) {
        (Some(target), Some(a)) => {
            let d = target.into_inner() - a.into_inner();
            (d, a.dot(&target).clamp(-1.0, 1.0).acos())
        }
        _ => (Vector3::zeros(), 0.0),
    };
    (dp, da, dp.norm(), angle)
}

/// Weight of the axis rows against the position rows: one radian counts as this many metres.
const AXIS_WEIGHT_M: f64 = 0.5;

fn descend(
    leg: &Leg,
    goal: &FootGoal,
    mut q: Vec<f64>,
    tolerance: &ReachTolerance,
) -> Option<Vec<f64>> {
    let oriented = goal.axis.is_some() && has_steering_axis(leg);
    // The joints solved: all of them, or all but the steering joint.
    let n = if oriented { leg.dof() - 1 } else { leg.dof() };
    let rows = if oriented { 6 } else { 3 };
    let scale = leg.reach_bound().max(1e-3);
    let mut damping = 0.01 * scale;
    let (mut dp, mut da, mut dist, mut angle) = residual(leg, goal, &q);
    let cost = |dp: &Vector3<f64>, da: &Vector3<f64>| {
        dp.norm_squared() + (AXIS_WEIGHT_M * AXIS_WEIGHT_M) * da.norm_squared()
    };
    let mut current = cost(&dp, &da);
    // Steps that gain almost nothing mean a local minimum away from the goal.
    let mut stalled = 0;
    for _ in 0..tolerance.max_iterations {
        if dist <= tolerance.position_m && angle <= tolerance.axis_rad {
            return Some(q);
        }
        let frames = leg.joint_frames(&q).ok()?;
        let foot = leg.foot_position(&q).ok()?;
        let axis_now = foot_axis(leg, &q);
        let mut jac = DMatrix::<f64>::zeros(rows, n);
        for (i, (joint, frame)) in leg.joints().iter().zip(&frames).take(n).enumerate() {
            match joint.kind() {
                JointKind::Revolute { axis } => {
                    let w = frame.rotation * axis.into_inner();
                    let o = Point3::from(frame.translation.vector);
                    let c = w.cross(&(foot - o));
                    jac.fixed_view_mut::<3, 1>(0, i).copy_from(&c);
                    if oriented && let Some(a) = axis_now {
                        let ca = w.cross(&a.into_inner()) * AXIS_WEIGHT_M;
                        jac.fixed_view_mut::<3, 1>(3, i).copy_from(&ca);
                    }
                }
                JointKind::Prismatic { axis } => {
                    let w = frame.rotation * axis.into_inner();
                    jac.fixed_view_mut::<3, 1>(0, i).copy_from(&w);
                }
            }
        }
        let mut e = DVector::<f64>::zeros(rows);
        e.fixed_rows_mut::<3>(0).copy_from(&dp);
        if oriented {
            e.fixed_rows_mut::<3>(3).copy_from(&(da * AXIS_WEIGHT_M));
        }
        let step = limited_step(leg, &q, jac, &e, damping)?;
        let mut candidate = q.clone();
        for i in 0..n {
            let s = step[i].clamp(-0.4, 0.4);
            candidate[i] = leg.joints()[i].limits().clamp(q[i] + s);
        }
        let (cdp, cda, cdist, cangle) = residual(leg, goal, &candidate);
        let c = cost(&cdp, &cda);
        if c < current {
            stalled = if current - c < 1e-4 * current {
                stalled + 1
            } else {
                0
            };
            if stalled >= 4 {
                break;
            }
            q = candidate;
            (dp, da, dist, angle, current) = (cdp, cda, cdist, cangle, c);
            damping = (damping * 0.3).max(1e-7 * scale);
        } else {
            damping *= 5.0;
            if damping > 1e3 * scale {
                break;
            }
        }
    }
    (dist <= tolerance.position_m && angle <= tolerance.axis_rad).then_some(q)
}

/// A damped least-squares step with the joints that sit on a limit and would be pushed past
/// it frozen.
fn limited_step(
    leg: &Leg,
    q: &[f64],
    mut jac: DMatrix<f64>,
    e: &DVector<f64>,
    damping: f64,
) -> Option<DVector<f64>> {
    let n = jac.ncols();
    let mut frozen = vec![false; n];
    loop {
        let a = &jac * jac.transpose()
            + DMatrix::<f64>::identity(jac.nrows(), jac.nrows()) * (damping * damping);
        let y = a.cholesky()?.solve(e);
        let step = jac.transpose() * y;
        let mut changed = false;
        for i in 0..n {
            let l = leg.joints()[i].limits();
            let out = (q[i] <= l.lower && step[i] < 0.0) || (q[i] >= l.upper && step[i] > 0.0);
            if out && !frozen[i] {
                frozen[i] = true;
                jac.column_mut(i).fill(0.0);
                changed = true;
            }
        }
        if !changed {
            return Some(step);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_legged_model::RobotModel;

    fn athlete() -> RobotModel {
        RobotModel::builtin("athlete").unwrap()
    }

    #[test]
    fn the_neutral_wheel_is_upright_and_placed_back_exactly() {
        let robot = athlete();
        for leg in robot.legs() {
            assert!(has_steering_axis(leg));
            let q0 = leg.neutral();
            let axis = foot_axis(leg, &q0).unwrap();
            assert!(axis.z.abs() > 0.999, "{}: {axis:?}", leg.name());
            let up = upright_axis(leg, -Vector3::z_axis()).unwrap();
            assert!((up.into_inner() - axis.into_inner()).norm() < 1e-4);
            let goal = FootGoal {
                centre: leg.foot_position(&q0).unwrap(),
                axis: Some(up),
            };
            let q = place_foot(leg, &goal, &[&q0], &ReachTolerance::default()).unwrap();
            assert!(q.iter().zip(&q0).all(|(a, b)| (a - b).abs() < 1e-9));
        }
    }

    #[test]
    fn moved_targets_keep_the_axis_upright_and_the_steering_joint() {
        let robot = athlete();
        let leg = robot.leg("left_front").unwrap();
        let q0 = leg.neutral();
        let up = upright_axis(leg, -Vector3::z_axis()).unwrap();
        let base = leg.foot_position(&q0).unwrap();
        let tol = ReachTolerance::default();
        let mut reached = 0;
        for (dx, dy, dz) in [
            (0.3, 0.0, 0.0),
            (-0.4, 0.2, 0.1),
            (0.0, 0.5, 0.2),
            (0.2, -0.3, -0.1),
            (-0.6, 0.0, 0.3),
        ] {
            let centre = base + Vector3::new(dx, dy, dz);
            let goal = FootGoal {
                centre,
                axis: Some(up),
            };
            if let Some(q) = place_foot(leg, &goal, &[&q0], &tol) {
                reached += 1;
                assert!(leg.within_limits(&q));
                assert!((leg.foot_position(&q).unwrap() - centre).norm() <= tol.position_m);
                let a = foot_axis(leg, &q).unwrap();
                assert!(a.dot(&up) >= tol.axis_rad.cos());
                assert_eq!(q[5], q0[5]);
            }
        }
        assert!(reached >= 4, "reached {reached} of 5");
    }

    #[test]
    fn a_target_beyond_reach_is_refused_at_once() {
        let robot = athlete();
        let leg = robot.leg("right_rear").unwrap();
        let q0 = leg.neutral();
        let goal = FootGoal {
            centre: leg.base_position() + Vector3::new(10.0, 0.0, 0.0),
            axis: upright_axis(leg, -Vector3::z_axis()),
        };
        assert!(place_foot(leg, &goal, &[&q0], &ReachTolerance::default()).is_none());
        assert!(
            place_foot_thoroughly(
                leg,
                &goal,
                &[&q0],
                16,
                1,
                &ReachTolerance::default(),
                |_| true
            )
            .is_none()
        );
    }

    #[test]
    fn a_three_joint_leg_is_placed_by_position() {
        let robot = RobotModel::builtin("hexapod").unwrap();
        let leg = robot.leg("left_front").unwrap();
        assert!(!has_steering_axis(leg));
        let q0 = leg.neutral();
        let target = leg.foot_position(&q0).unwrap() + Vector3::new(0.02, 0.01, 0.03);
        let goal = FootGoal {
            centre: target,
            axis: None,
        };
        let q = place_foot(leg, &goal, &[&q0], &ReachTolerance::default()).unwrap();
        assert!((leg.foot_position(&q).unwrap() - target).norm() < 1e-3);
    }
}
