//! One planned step of one leg, from where its foot stands to a target on the ground:
//!
//! 1. the target must be a green cell of the leg's maps (the same rules, at that point);
//! 2. the start and goal joints (`q_I`, `q_G`) and the lift and drop way-points straight
//!    above them (`q_L`, `q_D`; 20 cm with the field heuristics, just clear of the margin
//!    without), the wheel upright at each;
//! 3. the lift `q_I → q_L` and the drop `q_D → q_G`, simple vertical motions, checked with
//!    the wheel allowed to touch the ground but not sink into it;
//! 4. `q_L → q_D` planned by task-space A* over a 20 cm lattice, with SBL when A* finds no
//!    way (or by SBL alone), against the terrain raised 15 cm with the heuristics;
//! 5. the path smoothed by shortcuts until a round shortens it by less than 25 %;
//! 6. the whole plan checked again, densely: every configuration at most the resolution
//!    from the next keeps every margin.
//!
//! The plan is what the robot is sent: joint way-points after the start, the last segment
//! ending at ground contact.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use nalgebra::{Point2, Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::astar::{AstarParams, astar};
use crate::collision::{CheckerParams, LegChecker, Phase, lerp};
use crate::error::FootfallError;
use crate::maps::{Colour, Evaluator, MapParams};
use crate::reach::has_steering_axis;
use crate::sbl::{SblParams, sbl};
use crate::scene::Scene;
use crate::smooth::{SmoothParams, path_length, smooth};

/// Which planner plans the swing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PlannerKind {
    /// Task-space A* first, SBL when it finds no way.
    Astar,
    /// SBL alone.
    Sbl,
}

impl PlannerKind {
    /// `astar` or `sbl`.
    pub fn name(self) -> &'static str {
        match self {
            PlannerKind::Astar => "astar",
            PlannerKind::Sbl => "sbl",
        }
    }
}

impl std::str::FromStr for PlannerKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "astar" | "a*" => Ok(PlannerKind::Astar),
            "sbl" => Ok(PlannerKind::Sbl),
            other => Err(format!("unknown planner `{other}`: give astar or sbl")),
        }
    }
}

/// The field heuristics of the ATHLETE field test, which make up for the limbs sagging
/// under load: plan against the terrain raised, and pass through way-points high above
/// the start and the target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Heuristics {
    /// The terrain is raised this much for planning, metres (0.15).
    pub raise_m: f64,
    /// The lift and drop way-points this far above the start and the target, metres (0.20).
    pub waypoint_m: f64,
}

impl Default for Heuristics {
    fn default() -> Self {
        Self {
            raise_m: 0.15,
            waypoint_m: 0.20,
        }
    }
}

/// How steps are planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanOptions {
    /// Which planner plans the swing.
    pub planner: PlannerKind,
    /// The field heuristics, or `None` to plan against the terrain as it is with the
    /// lift and drop way-points only `base_lift_m` up.
    pub heuristics: Option<Heuristics>,
    /// The lift and drop way-points' height without the heuristics, metres: just enough
    /// for the wheel to clear the ground by its margin.
    pub base_lift_m: f64,
    /// The joint-space resolution of collision checks, radians.
    pub resolution_rad: f64,
    /// The maps' rules the target must pass, and the margins.
    pub map: MapParams,
    /// SBL's parameters.
    pub sbl: SblParams,
    /// A*'s parameters.
    pub astar: AstarParams,
    /// When A* finds no way, let SBL plan (true), or fail.
    pub astar_fallback: bool,
    /// Smoothing's parameters.
    pub smooth: SmoothParams,
}

impl Default for PlanOptions {
    fn default() -> Self {
        let map = MapParams::default();
        Self {
            planner: PlannerKind::Astar,
            heuristics: Some(Heuristics::default()),
            base_lift_m: map.margins.environment_m + 0.02,
            resolution_rad: 0.01,
            map,
            sbl: SblParams::default(),
            astar: AstarParams::default(),
            astar_fallback: true,
            smooth: SmoothParams::default(),
        }
    }
}

impl PlanOptions {
    /// The way-points' height.
    pub fn lift_m(&self) -> f64 {
        self.heuristics.map_or(self.base_lift_m, |h| h.waypoint_m)
    }

    /// The terrain's raise.
    pub fn raise_m(&self) -> f64 {
        self.heuristics.map_or(0.0, |h| h.raise_m)
    }
}

/// Time spent, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanTimes {
    /// Everything, from the request to the checked plan (the terrain's mesh excluded when
    /// it was made before).
    pub total_ms: f64,
    /// Making the terrain mesh and the parts (0 when reused).
    pub setup_ms: f64,
    /// A* (0 when not run).
    pub astar_ms: f64,
    /// SBL (0 when not run).
    pub sbl_ms: f64,
    /// Smoothing.
    pub smooth_ms: f64,
    /// The final dense check.
    pub verify_ms: f64,
}

/// A planned step: what the robot is sent and what the operator previews.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootfallPlan {
    /// The robot's name.
    pub robot: String,
    /// The leg.
    pub leg: String,
    /// Where the wheel goes, world XY.
    pub target: [f64; 2],
    /// The leg's joints when it was planned; the plan is carried out only from there.
    pub start_joints: Vec<f64>,
    /// The body's position when it was planned, world frame (x, y, z).
    pub body_position: [f64; 3],
    /// The joint way-points after the start: the lift way-point, the swing's way-points,
    /// the drop way-point and the goal; the last segment ends at ground contact.
    pub waypoints: Vec<Vec<f64>>,
    /// Way-points of the smoothed swing from the lift way-point to the drop way-point,
    /// both included.
    pub swing_waypoints: usize,
    /// The goal's joints pressed `press_m` further down: the last way-point the robot is
    /// sent, so that the move ends where the wheel meets the ground even when the ground is
    /// a little higher than the map says or the wheel a little short.
    pub press_joints: Vec<f64>,
    /// How far below its resting place the wheel is aimed, metres.
    pub press_m: f64,
    /// Which planner found the swing: `astar`, `sbl`, or `sbl` after A* failed
    /// (`astar_failed`).
    pub planner: String,
    /// Whether A* was tried and failed (SBL then planned).
    pub astar_failed: bool,
    /// The heuristics planned with, if any.
    pub heuristics: Option<Heuristics>,
    /// The lift and drop way-points' height, metres.
    pub lift_m: f64,
    /// The wheel's centre along the plan, world frame, about every centimetre of joint
    /// motion: the "ghost" the operator previews.
    pub foot_path: Vec<[f64; 3]>,
    /// The swing's length in joint space before and after smoothing, radians.
    pub swing_length_rad: [f64; 2],
    /// Milestones SBL made (0 when not run).
    pub milestones: usize,
    /// Cells A* expanded (0 when not run).
    pub expansions: usize,
    /// Configurations checked for collision.
    pub checks: u64,
    /// Times.
    pub times: PlanTimes,
}

impl FootfallPlan {
    /// Reads a plan written by [`Self::to_json`].
    pub fn from_json(text: &str) -> Result<Self, FootfallError> {
        serde_json::from_str(text).map_err(|e| {
            FootfallError::Plan(format!(
                "not a FootFall plan ({e}); write one with `tca footfall plan --out FILE`"
            ))
        })
    }

    /// The plan as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The way-points a `legged.legMove` carries out (with a transition: the last segment
    /// stops at ground contact): the plan's, the last pressed down.
    pub fn leg_move_waypoints(&self) -> Vec<Vec<f64>> {
        let mut w = self.waypoints.clone();
        if let Some(last) = w.last_mut() {
            last.clone_from(&self.press_joints);
        }
        w
    }

    /// The whole motion, start included.
    pub fn full_path(&self) -> Vec<Vec<f64>> {
        let mut p = vec![self.start_joints.clone()];
        p.extend(self.waypoints.iter().cloned());
        p
    }
}

/// How far below its resting place a plan aims the wheel at the end, metres.
pub const PRESS_M: f64 = 0.03;

/// Plans steps for the legs of one scene, keeping each leg's collision checker (the
/// terrain mesh is made once per leg and terrain raise).
pub struct StepPlanner {
    scene: Arc<Scene>,
    options: PlanOptions,
    checkers: Mutex<HashMap<(usize, u64), Arc<LegChecker>>>,
}

impl std::fmt::Debug for StepPlanner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StepPlanner")
            .field("robot", &self.scene.model.name())
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

impl StepPlanner {
    /// A planner for `scene` with `options`.
    pub fn new(scene: Arc<Scene>, options: PlanOptions) -> Result<Self, FootfallError> {
        scene.check()?;
        options.map.margins.check()?;
        options.map.check()?;
        Ok(Self {
            scene,
            options,
            checkers: Mutex::new(HashMap::new()),
        })
    }

    /// The scene.
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// The options.
    pub fn options(&self) -> &PlanOptions {
        &self.options
    }

    /// The collision checker of `leg` against the terrain raised `raise_m`, made once.
    pub fn checker(
        &self,
        leg: usize,
        raise_m: f64,
    ) -> Result<(Arc<LegChecker>, f64), FootfallError> {
        let key = (leg, raise_m.to_bits());
        let mut cache = self.checkers.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(c) = cache.get(&key) {
            return Ok((c.clone(), 0.0));
        }
        let t = Instant::now();
        let params = CheckerParams {
            margins: self.options.map.margins.clone(),
            resolution_rad: self.options.resolution_rad,
            raise_m,
            terrain: true,
        };
        let c = Arc::new(LegChecker::new(self.scene.clone(), leg, &params)?);
        cache.insert(key, c.clone());
        Ok((c, t.elapsed().as_secs_f64() * 1e3))
    }

    /// Plans a step of leg `leg` to world XY `target` with the planner's options.
    pub fn plan(&self, leg: usize, target: Point2<f64>) -> Result<FootfallPlan, FootfallError> {
        self.plan_with(leg, target, &self.options)
    }

    /// The problem a step poses, checked: the target's verdict, the four configurations
    /// (start, lift, drop, goal), the lift and drop checked, and the checker to plan with.
    pub fn problem(
        &self,
        leg: usize,
        target: Point2<f64>,
        options: &PlanOptions,
    ) -> Result<StepProblem, FootfallError> {
        let scene = &*self.scene;
        let l = scene
            .model
            .leg_at(leg)
            .map_err(|e| FootfallError::Scene(e.to_string()))?;
        let name = l.name().to_owned();
        let bad = |reason: String| FootfallError::BadTarget {
            leg: name.clone(),
            x: target.x,
            y: target.y,
            reason,
        };
        let mut map = options.map.clone();
        map.waypoint_m = options.lift_m();
        let eval = Evaluator::new(scene, leg, &map)?;
        let verdict = eval.evaluate(target, None);
        if verdict.colour != Colour::Green {
            return Err(bad(verdict
                .reason
                .unwrap_or_else(|| "not a green cell".into())));
        }
        let (Some(q_goal), Some(q_drop)) = (verdict.joints.clone(), verdict.waypoint.clone())
        else {
            return Err(bad("no joints place the foot there".into()));
        };
        let q_start = scene.posture[leg].clone();
        let start_centre = scene.foot_centre(leg, &q_start);
        let lift_centre = start_centre + Vector3::z() * options.lift_m();
        let no_path = |reason: String| FootfallError::NoPath {
            leg: name.clone(),
            reason,
        };
        let q_lift = eval.place(&lift_centre, Some(&q_start)).ok_or_else(|| {
            no_path(format!(
                "the way-point {:.0} cm above the foot's start cannot be reached",
                options.lift_m() * 100.0
            ))
        })?;
        // The goal and the drop way-point keep the start's steering angle.
        let (q_goal, q_drop) = (
            steer_like(&q_goal, &q_start, l),
            steer_like(&q_drop, &q_start, l),
        );
        let (checker, setup_ms) = self.checker(leg, options.raise_m())?;
        for (q, what) in [(&q_lift, "lift"), (&q_drop, "drop")] {
            if let Some(hit) = checker.check(q, Phase::Free) {
                return Err(no_path(format!("the {what} way-point collides: {hit}")));
            }
        }
        if let Err((_, hit)) = checker.segment(&q_start, &q_lift, Phase::LiftOrDrop) {
            return Err(no_path(format!("the lift collides: {hit}")));
        }
        if let Err((_, hit)) = checker.segment(&q_drop, &q_goal, Phase::LiftOrDrop) {
            return Err(no_path(format!("the drop collides: {hit}")));
        }
        let active = (0..l.dof())
            .filter(|&i| !(has_steering_axis(l) && i + 1 == l.dof()))
            .collect();
        Ok(StepProblem {
            leg,
            leg_name: name,
            target,
            q_start,
            q_lift,
            q_drop,
            q_goal,
            active,
            checker,
            setup_ms,
            map,
        })
    }

    /// Plans a step with other options (planner, heuristics, seeds) on the same scene.
    pub fn plan_with(
        &self,
        leg: usize,
        target: Point2<f64>,
        options: &PlanOptions,
    ) -> Result<FootfallPlan, FootfallError> {
        let started = Instant::now();
        let p = self.problem(leg, target, options)?;
        let scene = &*self.scene;
        let checker = p.checker.clone();
        let checks_before = checker.checks();
        let no_path = |reason: String| FootfallError::NoPath {
            leg: p.leg_name.clone(),
            reason,
        };
        let mut times = PlanTimes {
            setup_ms: p.setup_ms,
            ..PlanTimes::default()
        };
        let mut astar_failed = false;
        let mut expansions = 0;
        let mut milestones = 0;
        let mut found = None;
        if options.planner == PlannerKind::Astar {
            let t = Instant::now();
            let eval = Evaluator::new(scene, leg, &p.map)?;
            match astar(&checker, &eval, &p.q_lift, &p.q_drop, &options.astar) {
                Ok(o) => {
                    expansions = o.expansions;
                    found = Some((o.path, "astar"));
                }
                Err(why) => {
                    tracing::debug!(%why, "A* found no way");
                    astar_failed = true;
                    if !options.astar_fallback {
                        return Err(no_path(why));
                    }
                }
            }
            times.astar_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        let (raw, planner) = match found {
            Some(f) => f,
            None => {
                let t = Instant::now();
                let o = sbl(&checker, &p.q_lift, &p.q_drop, &p.active, &options.sbl).map_err(
                    |why| {
                        no_path(if astar_failed {
                            format!("A* found no way, and {why}")
                        } else {
                            why
                        })
                    },
                )?;
                times.sbl_ms = t.elapsed().as_secs_f64() * 1e3;
                milestones = o.milestones;
                (o.path, "sbl")
            }
        };
        let t = Instant::now();
        let smoothed = smooth(&checker, &raw, Phase::Free, &options.smooth);
        times.smooth_ms = t.elapsed().as_secs_f64() * 1e3;
        let swing = smoothed.path;
        let mut waypoints: Vec<Vec<f64>> = swing.clone();
        waypoints.push(p.q_goal.clone());
        // The final dense check of everything the robot will do.
        let t = Instant::now();
        if let Some((_, hit)) = checker.path_dense(&swing, Phase::Free) {
            return Err(no_path(format!("the smoothed swing collides: {hit}")));
        }
        for (a, b) in [(&p.q_start, &p.q_lift), (&p.q_drop, &p.q_goal)] {
            if let Some((_, hit)) = checker.path_dense(&[a.clone(), b.clone()], Phase::LiftOrDrop) {
                return Err(no_path(format!("the lift or drop collides: {hit}")));
            }
        }
        times.verify_ms = t.elapsed().as_secs_f64() * 1e3;
        let (press_joints, press_m) = press(scene, leg, &p, &Evaluator::new(scene, leg, &p.map)?);
        let mut full = vec![p.q_start.clone()];
        full.extend(waypoints.iter().cloned());
        let foot_path = foot_trace(scene, leg, &full, options.resolution_rad);
        times.total_ms = started.elapsed().as_secs_f64() * 1e3 - p.setup_ms;
        let body = scene.body.translation.vector;
        Ok(FootfallPlan {
            robot: scene.model.name().to_owned(),
            leg: p.leg_name.clone(),
            target: [target.x, target.y],
            start_joints: p.q_start.clone(),
            body_position: [body.x, body.y, body.z],
            swing_waypoints: swing.len(),
            waypoints,
            press_joints,
            press_m,
            planner: planner.to_owned(),
            astar_failed,
            heuristics: options.heuristics,
            lift_m: options.lift_m(),
            foot_path,
            swing_length_rad: [path_length(&raw), smoothed.length_after],
            milestones,
            expansions,
            checks: checker.checks() - checks_before,
            times,
        })
    }
}

/// A step's problem: its four configurations, checked, and the checker to plan with.
#[derive(Debug, Clone)]
pub struct StepProblem {
    /// The leg.
    pub leg: usize,
    /// Its name.
    pub leg_name: String,
    /// The target, world XY.
    pub target: Point2<f64>,
    /// The leg's joints now.
    pub q_start: Vec<f64>,
    /// At the lift way-point.
    pub q_lift: Vec<f64>,
    /// At the drop way-point.
    pub q_drop: Vec<f64>,
    /// On the target.
    pub q_goal: Vec<f64>,
    /// The joints the swing moves (all but a wheel's steering).
    pub active: Vec<usize>,
    /// The checker, against the terrain raised as the options say.
    pub checker: Arc<LegChecker>,
    /// Time spent making the checker, milliseconds (0 when it was made before).
    pub setup_ms: f64,
    /// The maps' rules used (way-point height as the options say).
    pub map: MapParams,
}

/// The goal pressed down [`PRESS_M`] (with the wheel upright, else by position only, else
/// less), and how far.
fn press(scene: &Scene, leg: usize, p: &StepProblem, eval: &Evaluator<'_>) -> (Vec<f64>, f64) {
    let l = &scene.model.legs()[leg];
    let goal = scene.foot_centre(leg, &p.q_goal);
    for depth in [PRESS_M, PRESS_M / 2.0] {
        let centre = goal - Vector3::z() * depth;
        if let Some(q) = eval.place(&centre, Some(&p.q_goal)) {
            return (steer_like(&q, &p.q_start, l), depth);
        }
        let target = scene.body.inverse() * centre;
        let options = tca_legged_model::IkOptions {
            random_starts: 0,
            ..tca_legged_model::IkOptions::starting_at(&p.q_goal)
        };
        if let Ok(s) = l.inverse_kinematics(&target, &options) {
            return (steer_like(&s.joints, &p.q_start, l), depth);
        }
    }
    (p.q_goal.clone(), 0.0)
}

/// `q` with the steering joint (the last, when the leg has one) set as in `like`.
fn steer_like(q: &[f64], like: &[f64], leg: &tca_legged_model::Leg) -> Vec<f64> {
    let mut out = q.to_vec();
    if has_steering_axis(leg)
        && let (Some(o), Some(l)) = (out.last_mut(), like.last())
    {
        *o = *l;
    }
    out
}

/// The wheel's centre along a joint path, world frame, a point every `step` radians of
/// joint motion at most.
pub fn foot_trace(scene: &Scene, leg: usize, path: &[Vec<f64>], step: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    let mut push = |p: Point3<f64>| out.push([p.x, p.y, p.z]);
    if let Some(first) = path.first() {
        push(scene.foot_centre(leg, first));
    }
    for w in path.windows(2) {
        let n = (crate::collision::linf(&w[0], &w[1]) / step)
            .ceil()
            .max(1.0) as usize;
        for k in 1..=n {
            push(scene.foot_centre(leg, &lerp(&w[0], &w[1], k as f64 / n as f64)));
        }
    }
    out
}
