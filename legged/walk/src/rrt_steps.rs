//! The integrated RRT-Connect planner (`tca-rrt`) as the walking module's step source.
//!
//! At the first step, and whenever the robot is not where the plan expected it (after a
//! failed move, once any foot left in the air is set down), the whole walk is planned from
//! the posture the robot stands in to the goal. Each planned transition between two
//! postures becomes one step of moves that the simulated Controller carries out one at a
//! time. The planner moves the body while a group of legs swings (tripod or wave); the
//! Controller is quasi-static, so a phase is executed either as the body's move to the
//! phase's end pose on all feet followed by each leg of the group swinging alone, or, where
//! a leg cannot reach its old foothold from the end pose, in steps of at most a centimetre
//! of travel: the swinging feet on along their paths, then the body to the same fraction of
//! its line, as the planner checked them. A swing is sent as joint positions at points at
//! most a centimetre apart along the planned path, the last a little below the foothold so
//! that the move ends at contact. Where a transition cannot be carried out even so, the
//! steps before it are kept and the walk is planned again from where they leave the robot;
//! a plan whose first transition cannot be is tried again with the next seed, a few times.
//!
//! The planner plans on the terrain it is given, as the planner of the paper did on its
//! elevation map of the whole terrain.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use nalgebra::{Isometry3, Point2, Point3, Vector3};
use tca_free_gait::{Action, GaitState, LegGaitState, StepPlan};
use tca_legged_model::RobotModel;
use tca_robot::HeightField;
use tca_rrt::trajectory::{path_length, point_along};
use tca_rrt::{BodyPose, Phase, Plan, Planner, RrtParams, Transition};

/// Swing way-points are at most this far apart along the planned path, metres.
const WAYPOINT_SPACING_M: f64 = 0.01;
/// The robot is where a planned step starts when its body is within this distance and
/// every foot within [`FOOT_MATCH_M`], metres.
const BODY_MATCH_M: f64 = 0.005;
/// See [`BODY_MATCH_M`].
const FOOT_MATCH_M: f64 = 0.01;
/// Plans tried from one place (each with the next seed) before the walk gives up there.
const PLAN_ATTEMPTS: u64 = 5;

/// Steps from the RRT-Connect planner, planned once for the walk and again when the robot
/// is not where they expected it.
pub struct RrtSteps {
    planner: Planner,
    below_foothold_m: f64,
    /// The plan's steps still to come, each with the state it starts from.
    queue: Mutex<VecDeque<(GaitState, StepPlan)>>,
}

/// What [`RrtSteps::next_step`] gives.
pub struct NextStep {
    /// The step.
    pub step: StepPlan,
    /// The whole plan, when this step began a new one.
    pub new_plan: Option<Plan>,
}

impl std::fmt::Debug for RrtSteps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RrtSteps").finish_non_exhaustive()
    }
}

impl RrtSteps {
    /// A step source for `model` on `terrain` with the planner's `params`; a swing ends
    /// `below_foothold_m` under its foothold.
    pub fn new(
        model: Arc<RobotModel>,
        terrain: Arc<HeightField>,
        params: RrtParams,
        below_foothold_m: f64,
    ) -> Result<Self, String> {
        let planner = Planner::new(model, terrain, params).map_err(|e| e.to_string())?;
        Ok(RrtSteps {
            planner,
            below_foothold_m,
            queue: Mutex::new(VecDeque::new()),
        })
    }

    /// The planner.
    pub fn planner(&self) -> &Planner {
        &self.planner
    }

    /// The next step from `state` toward `goal`: the plan's next one if the robot stands
    /// where it starts, otherwise the first of a new plan from where it stands. `Ok(None)`
    /// when the plan has no step left (the body is at the goal's posture).
    pub fn next_step(
        &self,
        state: &GaitState,
        goal: Point2<f64>,
    ) -> Result<Option<NextStep>, String> {
        let mut queue = self.queue.lock().unwrap_or_else(|p| p.into_inner());
        if let Some((start, _)) = queue.front()
            && same_place(start, state)
        {
            return Ok(queue.pop_front().map(|(_, step)| NextStep {
                step,
                new_plan: None,
            }));
        }
        if let Some(step) = self.set_down(state)? {
            queue.clear();
            return Ok(Some(NextStep {
                step,
                new_plan: None,
            }));
        }
        let start = self.posture_of(state)?;
        let mut last_problem = String::new();
        for attempt in 0..PLAN_ATTEMPTS {
            let mut planner = self.planner.clone();
            let seed = planner.params().seed;
            planner.set_seed(seed.wrapping_add(attempt));
            let plan = planner
                .plan_from(start.clone(), goal)
                .map_err(|e| format!("the RRT-Connect planner found no way: {e}"))?;
            if plan.transitions.is_empty() {
                return Ok(None);
            }
            // The moves up to the first transition that cannot be carried out one at a
            // time; the walk is planned again from there when the robot gets there.
            let (steps, problem) = self.steps_of(&plan, state);
            if let Some(p) = problem {
                tracing::debug!(attempt, problem = %p, kept = steps.len(), "a planned move cannot be carried out");
                last_problem = p;
            }
            if !steps.is_empty() {
                *queue = steps.into();
                return Ok(queue.pop_front().map(|(_, step)| NextStep {
                    step,
                    new_plan: Some(plan),
                }));
            }
        }
        Err(format!(
            "{PLAN_ATTEMPTS} plans from here (seeds {} on) begin with a move that cannot be carried out: {last_problem}",
            self.planner.params().seed
        ))
    }

    /// The planner's posture for the robot's state.
    fn posture_of(&self, state: &GaitState) -> Result<tca_rrt::Posture, String> {
        let robot = self.planner.robot();
        let feet = state
            .legs
            .iter()
            .enumerate()
            .map(|(i, l)| l.foot + Vector3::z() * robot.foot_radius(i))
            .collect();
        self.planner
            .posture_from(BodyPose::from_isometry(&state.body), feet, state.posture())
            .ok_or_else(|| "the robot's state does not fit its description".to_owned())
    }

    /// The plan's transitions as steps of one-at-a-time moves, from `state`, up to the
    /// first that cannot be carried out so (and why it cannot).
    fn steps_of(
        &self,
        plan: &Plan,
        state: &GaitState,
    ) -> (Vec<(GaitState, StepPlan)>, Option<String>) {
        let mut at = state.clone();
        let mut steps = Vec::with_capacity(plan.transitions.len());
        for t in &plan.transitions {
            let step = match self.step_of(t, &at) {
                Ok(step) => step,
                Err(e) => return (steps, Some(e)),
            };
            let next = step.end.clone();
            steps.push((at, step));
            at = next;
        }
        (steps, None)
    }

    /// One transition as a step.
    fn step_of(&self, t: &Transition, from: &GaitState) -> Result<StepPlan, String> {
        let mut state = from.clone();
        let mut actions = Vec::new();
        for phase in &t.phases {
            let (mut moves, end) = match self.phase_body_first(phase, &state) {
                Ok(done) => done,
                Err(first) => self.phase_interleaved(phase, &state).map_err(|second| {
                    format!(
                        "the planned move near ({:.2}, {:.2}) cannot be carried out: {first}; in small steps: {second}",
                        phase.body_from.x, phase.body_from.y
                    )
                })?,
            };
            actions.append(&mut moves);
            state = end;
        }
        Ok(StepPlan {
            actions,
            end: state,
            min_margin_m: t.min_margin_m,
        })
    }

    /// The body to the phase's end pose on all feet, then each swing alone.
    fn phase_body_first(
        &self,
        phase: &Phase,
        state: &GaitState,
    ) -> Result<(Vec<Action>, GaitState), String> {
        let mut s = state.clone();
        let mut actions = vec![self.body_move(&mut s, &phase.body_to.isometry())?];
        for swing in &phase.swings {
            let points = along(&swing.path, 0.0, 1.0);
            actions.push(self.leg_move(&mut s, swing.leg, &points, true)?);
        }
        Ok((actions, s))
    }

    /// The phase as the planner checked it, in steps of at most a centimetre of the body's
    /// or a foot's travel: each swinging foot on along its path (set down in the last
    /// step), then the body along its line to the same fraction of the phase (or the body
    /// first where a foot cannot reach on before it).
    fn phase_interleaved(
        &self,
        phase: &Phase,
        state: &GaitState,
    ) -> Result<(Vec<Action>, GaitState), String> {
        let mut s = state.clone();
        let mut actions = Vec::new();
        let from = phase.body_from.isometry();
        if (s.body.translation.vector - from.translation.vector).norm() > BODY_MATCH_M {
            actions.push(self.body_move(&mut s, &from)?);
        }
        let body_len =
            (phase.body_to.isometry().translation.vector - from.translation.vector).norm();
        let swing_len = phase
            .swings
            .iter()
            .map(|w| path_length(&w.path))
            .fold(0.0, f64::max);
        let n = ((body_len.max(swing_len) / WAYPOINT_SPACING_M).ceil() as usize).max(1);
        for k in 1..=n {
            let (t0, t1) = ((k - 1) as f64 / n as f64, k as f64 / n as f64);
            let body = phase.body_from.lerp(&phase.body_to, t1).isometry();
            // The feet first, then the body; where a foot cannot reach its next point from
            // the body where it is, the body first.
            let mut trial = s.clone();
            let mut moves = Vec::new();
            let feet_first = phase.swings.iter().try_for_each(|w| {
                let points = along(&w.path, t0, t1);
                moves.push(self.leg_move(&mut trial, w.leg, &points, k == n)?);
                Ok::<_, String>(())
            });
            let done = feet_first.and_then(|()| {
                moves.push(self.body_move(&mut trial, &body)?);
                Ok(())
            });
            if done.is_err() {
                trial = s.clone();
                moves = vec![self.body_move(&mut trial, &body)?];
                for w in &phase.swings {
                    let points = along(&w.path, t0, t1);
                    moves.push(self.leg_move(&mut trial, w.leg, &points, k == n)?);
                }
            }
            actions.append(&mut moves);
            s = trial;
        }
        Ok((actions, s))
    }

    /// The body's move to `target` on a straight line (position and orientation), every
    /// standing foot staying where it is (a foot in the air goes with the body); each
    /// centimetre of it checked for reach and for the robot's parts against each other
    /// and the ground.
    fn body_move(&self, s: &mut GaitState, target: &Isometry3<f64>) -> Result<Action, String> {
        let robot = self.planner.robot();
        let from = s.body;
        let travel = (target.translation.vector - from.translation.vector).norm()
            + 0.15 * from.rotation.angle_to(&target.rotation);
        let n = ((travel / WAYPOINT_SPACING_M).ceil() as usize).max(1);
        for k in 1..=n {
            let body = from.lerp_slerp(target, k as f64 / n as f64);
            let inverse = body.inverse();
            for i in 0..s.legs.len() {
                if !s.legs[i].stance {
                    continue;
                }
                let centre = s.legs[i].foot + Vector3::z() * robot.foot_radius(i);
                let q = self
                    .ik(i, &(inverse * centre), &s.legs[i].joints)
                    .ok_or_else(|| {
                        format!(
                            "leg {} cannot reach its foothold from the body at ({:.2}, {:.2})",
                            self.leg_name(i),
                            body.translation.x,
                            body.translation.y
                        )
                    })?;
                s.legs[i].joints = q;
            }
            self.planner
                .check_clear(&body, &s.posture(), 0.0)
                .map_err(|why| {
                    format!(
                        "moving the body to ({:.2}, {:.2}): {why}",
                        body.translation.x, body.translation.y
                    )
                })?;
        }
        s.body = *target;
        Ok(Action::Body { target: *target })
    }

    /// A move of `leg`'s foot through `points` (contact-sphere centres, world) with the
    /// body where it is; with `set_down`, on to a little below the last point, the move
    /// ending at contact.
    fn leg_move(
        &self,
        s: &mut GaitState,
        leg: usize,
        points: &[Point3<f64>],
        set_down: bool,
    ) -> Result<Action, String> {
        let robot = self.planner.robot();
        let Some(&last) = points.last() else {
            return Err(format!(
                "the plan's swing of leg {} has no path",
                self.leg_name(leg)
            ));
        };
        let mut targets = points.to_vec();
        if set_down {
            targets.push(self.below_foothold(leg, &last));
        }
        let inverse = s.body.inverse();
        let mut joints = s.legs[leg].joints.clone();
        let mut waypoints = Vec::with_capacity(targets.len());
        let mut at_last = joints.clone();
        for (k, p) in targets.iter().enumerate() {
            joints = self.ik(leg, &(inverse * p), &joints).ok_or_else(|| {
                format!(
                    "leg {} cannot reach ({:.3}, {:.3}, {:.3}) on its swing",
                    self.leg_name(leg),
                    p.x,
                    p.y,
                    p.z
                )
            })?;
            if k < points.len() {
                at_last = joints.clone();
                let mut posture = s.posture();
                posture[leg] = joints.clone();
                self.planner
                    .check_clear(&s.body, &posture, 0.0)
                    .map_err(|why| format!("swinging leg {}: {why}", self.leg_name(leg)))?;
            }
            waypoints.push(joints.clone());
        }
        let r = robot.foot_radius(leg);
        s.legs[leg] = LegGaitState {
            joints: at_last,
            stance: set_down,
            foot: last - Vector3::z() * r,
        };
        Ok(if set_down {
            Action::Swing {
                leg,
                waypoints,
                foothold: last - Vector3::z() * r,
            }
        } else {
            Action::Reach { leg, waypoints }
        })
    }

    /// Where a swing ending at `centre` (the contact sphere's, world) goes on to, so that
    /// the move ends at contact: [`RrtSteps::new`]'s depth below it, or below the terrain's
    /// height under it if the planner's conservative terrain put it higher.
    fn below_foothold(&self, leg: usize, centre: &Point3<f64>) -> Point3<f64> {
        let r = self.planner.robot().foot_radius(leg);
        let ground = self
            .planner
            .terrain()
            .height(Point2::new(centre.x, centre.y));
        let z = (centre.z - self.below_foothold_m).min(ground + r - self.below_foothold_m);
        Point3::new(centre.x, centre.y, z)
    }

    /// A step that sets every foot in the air down straight below it (after a failed
    /// move), or `None` when every foot stands.
    fn set_down(&self, state: &GaitState) -> Result<Option<StepPlan>, String> {
        let robot = self.planner.robot();
        let mut s = state.clone();
        let mut actions = Vec::new();
        for i in 0..s.legs.len() {
            if s.legs[i].stance {
                continue;
            }
            let centre = s.legs[i].foot + Vector3::z() * robot.foot_radius(i);
            actions.push(self.leg_move(&mut s, i, &[centre], true)?);
        }
        if actions.is_empty() {
            return Ok(None);
        }
        // The margin once every foot stands (the feet already standing held it before).
        let min_margin_m = self.posture_of(&s)?.margin_m;
        Ok(Some(StepPlan {
            actions,
            end: s,
            min_margin_m,
        }))
    }

    /// Inverse kinematics of one leg for a foot at `local` (body frame), from `initial`,
    /// else from the leg's neutral joints.
    fn ik(&self, leg: usize, local: &Point3<f64>, initial: &[f64]) -> Option<Vec<f64>> {
        let robot = self.planner.robot();
        robot.leg_ik(leg, local, initial).or_else(|| {
            let options = tca_legged_model::IkOptions {
                initial: Some(initial.to_vec()),
                ..tca_legged_model::IkOptions::default()
            };
            let leg = robot.model().legs().get(leg)?;
            leg.inverse_kinematics(local, &options)
                .ok()
                .map(|s| s.joints)
        })
    }

    fn leg_name(&self, leg: usize) -> String {
        self.planner
            .robot()
            .model()
            .legs()
            .get(leg)
            .map(|l| l.name().to_owned())
            .unwrap_or_else(|| format!("#{leg}"))
    }
}

/// Points of `path` (by length) from fraction `t0` (excluded) to `t1` (included), at most
/// [`WAYPOINT_SPACING_M`] apart, with every vertex of the path in between.
fn along(path: &[Point3<f64>], t0: f64, t1: f64) -> Vec<Point3<f64>> {
    let total = path_length(path);
    if path.len() < 2 || total <= 0.0 {
        return path.last().copied().into_iter().collect();
    }
    let (s0, s1) = (t0 * total, t1 * total);
    // Stations: the path's vertices strictly inside (s0, s1), then s1.
    let mut stations = Vec::new();
    let mut run = 0.0;
    for w in path.windows(2) {
        run += (w[1] - w[0]).norm();
        if run > s0 + 1e-9 && run < s1 - 1e-9 {
            stations.push(run);
        }
    }
    stations.push(s1);
    let mut out = Vec::new();
    let mut prev = s0;
    for st in stations {
        let n = (((st - prev) / WAYPOINT_SPACING_M).ceil() as usize).max(1);
        for k in 1..=n {
            let d = prev + (st - prev) * (k as f64 / n as f64);
            out.push(point_along(path, d / total));
        }
        prev = st;
    }
    out
}

/// Whether two states are the same place: the bodies within [`BODY_MATCH_M`] and 0.01 rad,
/// the same feet standing, every foot within [`FOOT_MATCH_M`].
fn same_place(a: &GaitState, b: &GaitState) -> bool {
    (a.body.translation.vector - b.body.translation.vector).norm() <= BODY_MATCH_M
        && a.body.rotation.angle_to(&b.body.rotation) <= 0.01
        && a.legs.len() == b.legs.len()
        && a.legs
            .iter()
            .zip(&b.legs)
            .all(|(x, y)| x.stance == y.stance && (x.foot - y.foot).norm() <= FOOT_MATCH_M)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The state the robot stands in at a planner's posture.
    fn state_of(p: &tca_rrt::Posture, steps: &RrtSteps) -> GaitState {
        let robot = steps.planner().robot();
        GaitState {
            body: p.body.isometry(),
            legs: (0..p.feet.len())
                .map(|i| LegGaitState {
                    joints: p.joints[i].clone(),
                    stance: true,
                    foot: p.feet[i] - Vector3::z() * robot.foot_radius(i),
                })
                .collect(),
        }
    }

    #[test]
    fn a_plan_across_the_walls_becomes_moves_of_one_leg_or_the_body() {
        let course = tca_legged_courses::Course::builtin("hexapod-walls", 1).unwrap();
        let model = Arc::new(RobotModel::builtin("hexapod").unwrap());
        let steps = RrtSteps::new(
            model,
            Arc::new(course.terrain.clone()),
            RrtParams::default(),
            0.01,
        )
        .unwrap();
        let start = steps
            .planner()
            .posture_at(Point2::new(course.start.x_m, course.start.y_m), 0.0)
            .unwrap();
        let state = state_of(&start, &steps);
        let goal = Point2::new(course.goal.x, course.goal.y);
        let mut at = state.clone();
        let (mut n, mut plans) = (0, 0);
        while let Some(next) = steps.next_step(&at, goal).unwrap() {
            plans += usize::from(next.new_plan.is_some());
            assert!(!next.step.actions.is_empty());
            assert!(
                next.step.actions.iter().all(|a| match a {
                    Action::Swing { waypoints, .. } | Action::Reach { waypoints, .. } =>
                        !waypoints.is_empty(),
                    Action::Body { .. } => true,
                }),
                "every leg move has way-points"
            );
            at = next.step.end.clone();
            n += 1;
            assert!(n < 500, "the walk ends");
        }
        assert!(n > 10, "{n} steps");
        assert!(plans <= 5, "{plans} plans: the plans are followed");
        let end = at.body.translation;
        assert!((Point2::new(end.x, end.y) - goal).norm() < 0.02);
        assert!(at.legs.iter().all(|l| l.stance));
    }
}
