//! The free gait: [`FreeGait`] plans one step at a time (a body move toward the goal, then
//! one leg re-placed ahead).

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector2, Vector3};
use tca_legged_model::{IkOptions, JointKind, RobotModel, SelfContact};
use tca_stability::{Polygon, conservative_support_polygon, margin_along_path};

mod moves;

use crate::collision::{Hit, Probes};
use crate::error::GaitError;
use crate::geometry::{
    centre_of_contact, com_world, contact_of_centre, margin, polygon_of, rest_height,
    sphere_clearance, wrap, yaw_of,
};
use crate::params::GaitParams;
use crate::state::{Action, GaitState, LegGaitState, StepPlan};
use crate::terrain::TerrainView;

/// Where the body goes after the step being planned: along `direction` (world, unit) by
/// up to `ahead_m` (a full step, or what is left to the goal).
#[derive(Debug, Clone, Copy)]
struct Next {
    direction: Vector2<f64>,
    ahead_m: f64,
}

/// The body part of the way along the next step, for checking footholds against it.
struct FurtherOn {
    /// How much of the next step.
    fraction: f64,
    /// The inverse of the body's pose there.
    inverse: Isometry3<f64>,
    /// Every leg's joints there, the standing legs' following their feet.
    posture: Vec<Vec<f64>>,
    /// The first standing leg (other than the one being placed) that cannot follow.
    out_of_reach: Option<usize>,
}

/// Joint samples of each leg's workspace from which candidate footholds are drawn.
const WORKSPACE_SAMPLES: usize = 8192;
/// Footholds fully evaluated per leg and body target.
const FOOTHOLDS_EVALUATED: usize = 12;
/// Candidates looked at per leg and body target before giving up on finding more.
const CANDIDATES_TRIED: usize = 1500;
/// Swings planned (the best footholds first) before giving up on a body target.
const SWINGS_TRIED: usize = 12;
/// Fractions of the full body move tested for each leg's reach.
const REACH_FRACTIONS: usize = 6;
/// Bisections of the first sixth of a move, when a leg does not reach its end, for the
/// fraction it does.
const REACH_REFINEMENTS: usize = 4;
/// Steps of body height tried above and below the neutral height over the feet, and their
/// size as a share of the robot's neutral standing height.
const HEIGHT_STEPS: usize = 5;
const HEIGHT_STEP: f64 = 0.1;

/// Body poses along a move and the posture at each.
type Samples = Vec<(Isometry3<f64>, Vec<Vec<f64>>)>;

/// Where a lowering foot first touches: the leg's joints and the foot-sphere centre.
type Contact = (Vec<f64>, Point3<f64>);

/// What the gait knows of one leg, computed once.
#[derive(Debug, Clone)]
struct LegInfo {
    name: String,
    radius: f64,
    /// A prismatic joint whose axis is vertical in the body frame: the leg lifts with it.
    slide: Option<usize>,
    /// Foot-sphere centre at the neutral joints, body frame.
    neutral: Point3<f64>,
    /// Candidate foot positions in the body frame.
    candidates: Vec<Candidate>,
    /// Lowest and highest foot-sphere centre in the body frame.
    z_range: (f64, f64),
    /// The candidate of each workspace cell.
    cells: HashMap<(i64, i64), usize>,
}

/// A candidate foot position: (x, y) in the body frame and the heights (body frame) the
/// workspace samples reached there, widened a little.
#[derive(Debug, Clone)]
struct Candidate {
    at: Point2<f64>,
    z_range: (f64, f64),
}

/// A checked body move: the posture at its end and its smallest margin.
#[derive(Debug, Clone)]
struct BodyMove {
    target: Isometry3<f64>,
    posture: Vec<Vec<f64>>,
    min_margin: f64,
}

/// A chosen foothold, not yet swung to.
#[derive(Debug, Clone)]
struct Foothold {
    centre: Point3<f64>,
    joints: Vec<f64>,
    score: f64,
    progress: f64,
}

/// A planned swing.
#[derive(Debug, Clone)]
struct Swing {
    waypoints: Vec<Vec<f64>>,
    contact_joints: Vec<f64>,
    contact_centre: Point3<f64>,
    min_margin: f64,
}

/// How a swing segment treats the foot.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Segment {
    /// Leaving the ground: the foot may touch at first.
    Lift,
    /// Above the terrain with clearance.
    Travel,
    /// Coming down: ends at the first contact.
    Lower,
}

/// A free gait for a multi-legged robot: see the [crate documentation](crate).
#[derive(Debug, Clone)]
pub struct FreeGait {
    model: Arc<RobotModel>,
    params: GaitParams,
    legs: Vec<LegInfo>,
    probes: Probes,
}

impl LegInfo {
    /// The body-frame heights the foot reaches over (x, y), from the workspace samples of
    /// that cell; `None` when the cell has none (the foot is out of reach there at any
    /// height).
    fn z_at(&self, x: f64, y: f64, cell: f64) -> Option<(f64, f64)> {
        let key = ((x / cell).round() as i64, (y / cell).round() as i64);
        self.cells.get(&key).map(|&k| self.candidates[k].z_range)
    }
}

impl FreeGait {
    /// A gait for a robot. Each leg's workspace is sampled once here (some milliseconds).
    pub fn new(model: Arc<RobotModel>, params: GaitParams) -> Self {
        let legs = model
            .legs()
            .iter()
            .map(|leg| {
                let neutral = leg
                    .foot_position(&leg.neutral())
                    .unwrap_or_else(|_| Point3::origin());
                let samples = leg.workspace_samples(WORKSPACE_SAMPLES);
                let (lo, hi) = samples
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(p.z), hi.max(p.z))
                    });
                let cell = params.foothold_spacing_m.max(1e-4);
                let mut cells: Vec<((i64, i64), f64)> = samples
                    .iter()
                    .map(|p| {
                        (
                            ((p.x / cell).round() as i64, (p.y / cell).round() as i64),
                            p.z,
                        )
                    })
                    .collect();
                cells.sort_unstable_by_key(|a| a.0);
                let slack = 0.1 * (hi - lo).max(1e-6);
                let mut candidates: Vec<Candidate> = Vec::new();
                for ((i, j), z) in cells {
                    let at = Point2::new(i as f64 * cell, j as f64 * cell);
                    match candidates.last_mut() {
                        Some(c) if c.at == at => {
                            c.z_range.0 = c.z_range.0.min(z - slack);
                            c.z_range.1 = c.z_range.1.max(z + slack);
                        }
                        _ => candidates.push(Candidate {
                            at,
                            z_range: (z - slack, z + slack),
                        }),
                    }
                }
                let index = candidates
                    .iter()
                    .enumerate()
                    .map(|(k, c)| {
                        (
                            (
                                (c.at.x / cell).round() as i64,
                                (c.at.y / cell).round() as i64,
                            ),
                            k,
                        )
                    })
                    .collect();
                let slide = leg.joint_frames(&leg.neutral()).ok().and_then(|frames| {
                    leg.joints()
                        .iter()
                        .enumerate()
                        .position(|(k, j)| match j.kind() {
                            JointKind::Prismatic { axis } => {
                                (frames[k].rotation * axis.into_inner()).z.abs() > 0.99
                            }
                            JointKind::Revolute { .. } => false,
                        })
                });
                LegInfo {
                    name: leg.name().to_string(),
                    radius: leg.foot_radius(),
                    slide,
                    neutral,
                    candidates,
                    z_range: (lo, hi),
                    cells: index,
                }
            })
            .collect();
        let probes = Probes::new(&model, params.sample_m * 2.0);
        FreeGait {
            model,
            params,
            legs,
            probes,
        }
    }

    /// The robot.
    pub fn model(&self) -> &RobotModel {
        &self.model
    }

    /// The parameters.
    pub fn params(&self) -> &GaitParams {
        &self.params
    }

    /// Whether the body is within `tolerance_m` (horizontally) of the goal.
    pub fn reached(&self, state: &GaitState, goal: Point2<f64>, tolerance_m: f64) -> bool {
        let t = state.body.translation.vector;
        (Point2::new(t.x, t.y) - goal).norm() <= tolerance_m
    }

    /// The centre of mass of a state in the world, and its margin over the standing feet.
    pub fn stability(&self, state: &GaitState) -> Option<(Point3<f64>, f64)> {
        let com = com_world(&self.model, &state.body, &state.posture())?;
        let polygon = polygon_of(state.legs.iter().filter(|l| l.stance).map(|l| l.foot));
        Some((com, margin(&polygon, com)))
    }

    /// Plans the next step from `state` toward `goal` over `terrain`: a body move (when
    /// the body can advance or must shift) and one leg swung to a new foothold, or, when a
    /// leg is off the ground, that leg set down.
    pub fn plan_step(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        goal: Point2<f64>,
    ) -> Result<StepPlan, GaitError> {
        self.check_state(state, goal)?;
        let here = Point2::new(state.body.translation.x, state.body.translation.y);
        let distance = (goal - here).norm();
        if distance <= self.params.goal_tolerance_m {
            return Err(GaitError::GoalReached {
                distance_m: distance,
            });
        }
        let stance = state.stance_legs();
        if stance.len() < 3 {
            return Err(GaitError::Unstable {
                reason: format!(
                    "only {} feet stand ({}); at least three must",
                    stance.len(),
                    self.names(&stance)
                ),
            });
        }
        let direction = (goal - here) / distance;
        if let Some(air) = (0..state.legs.len()).find(|&i| !state.legs[i].stance) {
            return self.place_leg(state, terrain, direction, air);
        }
        self.walk_step(state, terrain, goal, direction)
    }

    fn names(&self, legs: &[usize]) -> String {
        legs.iter()
            .map(|&i| self.legs[i].name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn check_state(&self, state: &GaitState, goal: Point2<f64>) -> Result<(), GaitError> {
        let bad = |reason: String| Err(GaitError::BadState { reason });
        if !(goal.x.is_finite() && goal.y.is_finite()) {
            return bad(format!("the goal ({}, {}) is not a point", goal.x, goal.y));
        }
        if state.legs.len() != self.legs.len() {
            return bad(format!(
                "it has {} legs, the robot {}",
                state.legs.len(),
                self.legs.len()
            ));
        }
        let t = state.body.translation.vector;
        if !(t.iter().all(|v| v.is_finite())
            && state.body.rotation.coords.iter().all(|v| v.is_finite()))
        {
            return bad("the body pose is not finite".into());
        }
        for (leg, l) in self.model.legs().iter().zip(&state.legs) {
            if let Err(e) = leg.check(&l.joints) {
                return bad(e.to_string());
            }
            if !l.foot.coords.iter().all(|v| v.is_finite()) {
                return bad(format!("leg `{}`'s foot is not a point", leg.name()));
            }
        }
        Ok(())
    }

    /// Inverse kinematics of a leg toward a body-frame foot-sphere centre.
    fn ik(
        &self,
        leg: usize,
        target: &Point3<f64>,
        initial: &[f64],
        random_starts: usize,
    ) -> Option<Vec<f64>> {
        let options = IkOptions {
            random_starts,
            initial: Some(initial.to_vec()),
            ..IkOptions::default()
        };
        self.model.legs()[leg]
            .inverse_kinematics(target, &options)
            .ok()
            .map(|s| s.joints)
    }

    /// The foot-sphere centre of a leg in the world.
    fn foot_centre(&self, body: &Isometry3<f64>, leg: usize, q: &[f64]) -> Point3<f64> {
        let p = self.model.legs()[leg]
            .foot_position(q)
            .unwrap_or_else(|_| Point3::origin());
        body * p
    }

    /// The standing feet's IK along a body move, every `sample_m`; `None` at the first
    /// leg that cannot follow, with its name.
    fn follow(
        &self,
        state: &GaitState,
        from: &Isometry3<f64>,
        to: &Isometry3<f64>,
        posture: &[Vec<f64>],
        stance: &[usize],
    ) -> Result<Samples, String> {
        let n = self.move_samples(from, to);
        let mut q = posture.to_vec();
        let mut out = Vec::with_capacity(n);
        for k in 1..=n {
            let pose = from.lerp_slerp(to, k as f64 / n as f64);
            let inverse = pose.inverse();
            for &i in stance {
                let centre = centre_of_contact(&state.legs[i].foot, self.legs[i].radius);
                let target = inverse * centre;
                match self.ik(i, &target, &q[i], 0) {
                    Some(joints) => q[i] = joints,
                    None => {
                        return Err(format!(
                            "leg `{}` cannot reach its foothold {:.0}% of the way",
                            self.legs[i].name,
                            100.0 * k as f64 / n as f64
                        ));
                    }
                }
            }
            out.push((pose, q.clone()));
        }
        Ok(out)
    }

    /// Two legs' links nearer than the leg clearance in `posture` (with `leg`, only pairs
    /// involving that leg).
    fn legs_touch(&self, posture: &[Vec<f64>], leg: Option<usize>) -> Option<SelfContact> {
        self.model
            .legs_touching(posture, leg, self.params.leg_clearance_m)
            .ok()
            .flatten()
    }

    fn move_samples(&self, from: &Isometry3<f64>, to: &Isometry3<f64>) -> usize {
        let travel = (to.translation.vector - from.translation.vector).norm();
        let turn = from.rotation.angle_to(&to.rotation) * 2.0 * self.params.scale;
        (((travel + turn) / self.params.sample_m).ceil() as usize).clamp(1, 400)
    }

    /// Checks a body move with every standing foot fixed: reach, margin, collisions.
    fn body_move(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        target: &Isometry3<f64>,
    ) -> Result<BodyMove, String> {
        let stance = state.stance_legs();
        let posture = state.posture();
        let from = state.body;
        let samples = self.follow(state, &from, target, &posture, &stance)?;
        let polygon = polygon_of(stance.iter().map(|&i| state.legs[i].foot));
        let mut path = Vec::with_capacity(samples.len() + 1);
        path.extend(com_world(&self.model, &from, &posture));
        for (pose, q) in &samples {
            path.extend(com_world(&self.model, pose, q));
        }
        let worst = margin_along_path(&polygon, &path)
            .map(|m| m.margin_m)
            .unwrap_or(f64::NEG_INFINITY);
        if worst.is_nan() || worst < self.params.min_margin_m {
            return Err(format!(
                "the body move's stability margin would fall to {worst:.3} m (at least {:.3} m needed)",
                self.params.min_margin_m
            ));
        }
        let top_foot = stance
            .iter()
            .map(|&i| state.legs[i].foot.z)
            .fold(f64::NEG_INFINITY, f64::max);
        let unknown_body = top_foot + self.params.unknown_rise_m;
        let fallback = |leg: Option<usize>| match leg {
            None => Some(unknown_body),
            Some(i) => Some(state.legs[i].foot.z),
        };
        for (pose, q) in &samples {
            self.probes
                .check(
                    &self.model,
                    terrain,
                    pose,
                    q,
                    &|_| true,
                    self.params.clearance_m * 0.5,
                    &fallback,
                )
                .map_err(|h| format!("during the body move {}", h.describe()))?;
        }
        // Legs that already touch (a posture the gait did not choose) may move apart.
        if self.legs_touch(&posture, None).is_none() {
            for (_, q) in &samples {
                if let Some(contact) = self.legs_touch(q, None) {
                    return Err(format!("during the body move {contact}"));
                }
            }
        }
        let posture = samples.last().map(|(_, q)| q.clone()).unwrap_or(posture);
        Ok(BodyMove {
            target: *target,
            posture,
            min_margin: worst,
        })
    }

    /// The level body's height at (x, y), from the heights (body-frame) at which each
    /// standing foot stays in its leg's sampled workspace there.
    ///
    /// With a `height_bias`, the body stands that far from the lowest to the highest
    /// height every foot allows (a foot out of reach at (x, y) allowing its whole
    /// workspace's heights; the neutral height over the feet when they allow none). Without one (legs of revolute joints, whose sampled heights at an (x, y)
    /// are too thin a band to intersect), it stands at the neutral height over the feet
    /// or the nearest height at which every foot can be reached, and at the neutral height
    /// when no height reaches them all: one foot at the edge of its workspace does not drag
    /// the body up or down; it is swung first.
    fn body_height(
        &self,
        state: &GaitState,
        stance: &[usize],
        x: f64,
        y: f64,
        rotation: &UnitQuaternion<f64>,
    ) -> f64 {
        let centre = |i: usize| centre_of_contact(&state.legs[i].foot, self.legs[i].radius);
        let mean = stance
            .iter()
            .map(|&i| centre(i).z - self.legs[i].neutral.z)
            .sum::<f64>()
            / stance.len().max(1) as f64;
        let Some(bias) = self.params.height_bias else {
            return self.most_reached_height(state, stance, x, y, rotation, mean);
        };
        let (mut low, mut high) = (f64::NEG_INFINITY, f64::INFINITY);
        for &i in stance {
            let (info, c) = (&self.legs[i], centre(i));
            let local = rotation.inverse() * Vector3::new(c.x - x, c.y - y, 0.0);
            // local z = c.z - body z must lie in the range; a foot out of reach at (x, y)
            // bounds the height by its whole workspace.
            let range = info
                .z_at(local.x, local.y, self.params.foothold_spacing_m)
                .unwrap_or(info.z_range);
            low = low.max(c.z - range.1);
            high = high.min(c.z - range.0);
        }
        if low <= high && low.is_finite() && high.is_finite() {
            low + bias * (high - low)
        } else {
            mean
        }
    }

    /// The body height nearest the neutral height over the feet, among it and heights
    /// stepped above and below it, at which every standing foot can be reached (inverse
    /// kinematics from the present posture); the neutral height when none is.
    fn most_reached_height(
        &self,
        state: &GaitState,
        stance: &[usize],
        x: f64,
        y: f64,
        rotation: &UnitQuaternion<f64>,
        neutral: f64,
    ) -> f64 {
        let step = HEIGHT_STEP * self.model.neutral_height().max(1e-3);
        let reached = |z: f64| {
            let inverse = Isometry3::from_parts(Translation3::new(x, y, z), *rotation).inverse();
            stance
                .iter()
                .filter(|&&i| {
                    let centre = centre_of_contact(&state.legs[i].foot, self.legs[i].radius);
                    self.ik(i, &(inverse * centre), &state.legs[i].joints, 0)
                        .is_some()
                })
                .count()
        };
        if reached(neutral) == stance.len() {
            return neutral;
        }
        for k in 1..=HEIGHT_STEPS {
            for z in [neutral - k as f64 * step, neutral + k as f64 * step] {
                if reached(z) == stance.len() {
                    return z;
                }
            }
        }
        neutral
    }

    /// A walking step: choose the leg, the body move, the foothold and the swing.
    fn walk_step(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        goal: Point2<f64>,
        direction: Vector2<f64>,
    ) -> Result<StepPlan, GaitError> {
        let p = &self.params;
        let stance = state.stance_legs();
        let here = Point2::new(state.body.translation.x, state.body.translation.y);
        let distance = (goal - here).norm();
        let yaw = yaw_of(&state.body);
        let error = wrap(direction.y.atan2(direction.x) - yaw);
        let turn = error.clamp(-p.max_turn_rad, p.max_turn_rad);
        let advance = p.max_body_step_m.min(distance) * error.cos().max(0.0);
        let heading = yaw + turn;
        let (x, y) = (
            here.x + direction.x * advance,
            here.y + direction.y * advance,
        );
        let rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, heading);
        let z = self.body_height(state, &stance, x, y, &rotation);
        let full = Isometry3::from_parts(Translation3::new(x, y, z), rotation);
        // How far along the full move each standing foot stays within reach.
        let posture = state.posture();
        let mut reach = vec![1.0f64; state.legs.len()];
        for &i in &stance {
            let mut q = posture[i].clone();
            let mut last = 0.0;
            let centre = centre_of_contact(&state.legs[i].foot, self.legs[i].radius);
            for k in 1..=REACH_FRACTIONS {
                let f = k as f64 / REACH_FRACTIONS as f64;
                let pose = state.body.lerp_slerp(&full, f);
                match self.ik(i, &(pose.inverse() * centre), &q, 0) {
                    Some(joints) => {
                        q = joints;
                        last = f;
                    }
                    None => break,
                }
            }
            // When not even the first sixth is reached, the furthest fraction of it that
            // is, backed off by a bisection step so as not to end at the edge of the
            // workspace: near the goal or an obstacle a short move may be all there is.
            if last == 0.0 {
                let (mut lo, mut hi) = (last, last + 1.0 / REACH_FRACTIONS as f64);
                for _ in 0..REACH_REFINEMENTS {
                    let mid = 0.5 * (lo + hi);
                    let pose = state.body.lerp_slerp(&full, mid);
                    match self.ik(i, &(pose.inverse() * centre), &q, 0) {
                        Some(joints) => {
                            q = joints;
                            lo = mid;
                        }
                        None => hi = mid,
                    }
                }
                last = (lo - (hi - lo)).max(0.0);
            }
            reach[i] = last;
        }
        let f_max = stance.iter().map(|&i| reach[i]).fold(1.0, f64::min);
        tracing::debug!(
            z_now = state.body.translation.z,
            z_target = z,
            advance,
            reach = ?stance.iter().map(|&i| (self.legs[i].name.as_str(), reach[i])).collect::<Vec<_>>(),
            "reach along the full body move"
        );
        let behind = |i: usize| {
            let neutral = state.body * self.legs[i].neutral;
            let foot = state.legs[i].foot;
            (foot.x - neutral.x) * direction.x + (foot.y - neutral.y) * direction.y
        };
        let mut order = stance.clone();
        order.sort_by(|&a, &b| {
            reach[a]
                .total_cmp(&reach[b])
                .then(behind(a).total_cmp(&behind(b)))
        });
        let mut fractions = vec![f_max, f_max * 2.0 / 3.0, f_max / 3.0, 0.0];
        fractions.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let mut moves: Vec<(f64, Result<BodyMove, String>)> = Vec::new();
        let mut reasons: Vec<String> = Vec::new();
        let here_progress = |pose: &Isometry3<f64>| {
            let t = Point2::new(pose.translation.x, pose.translation.y);
            let yaw_gain = (wrap(direction.y.atan2(direction.x) - yaw).abs()
                - wrap(direction.y.atan2(direction.x) - yaw_of(pose)).abs())
                * p.scale;
            distance - (goal - t).norm() + yaw_gain
        };
        for &leg in &order {
            let mut why = Vec::new();
            for &f in &fractions {
                let pose = state.body.lerp_slerp(&full, f);
                let body = match moves.iter().find(|(g, _)| *g == f) {
                    Some((_, m)) => m.clone(),
                    None => {
                        let m = if f == 0.0 {
                            Ok(BodyMove {
                                target: state.body,
                                posture: posture.clone(),
                                min_margin: self.margin_of(state, &state.body, &posture, None),
                            })
                        } else {
                            self.body_move(state, terrain, &pose)
                        };
                        moves.push((f, m.clone()));
                        m
                    }
                };
                let body = match body {
                    Ok(b) => b,
                    Err(e) => {
                        why.push(e);
                        continue;
                    }
                };
                let mut candidates = vec![body];
                // When lifting the leg would leave too little margin, shift the body toward
                // the middle of the feet that stay.
                let lift_margin = self.margin_of(
                    state,
                    &candidates[0].target,
                    &candidates[0].posture,
                    Some(leg),
                );
                if lift_margin < p.min_margin_m {
                    why.push(format!(
                        "lifting it after a {:.2} m body move leaves a margin of {lift_margin:.3} m",
                        f * advance
                    ));
                    candidates.clear();
                    for shift in [0.6, 1.0] {
                        match self.shifted(state, terrain, &pose, leg, shift) {
                            Ok(b) => candidates.push(b),
                            Err(e) => why.push(e),
                        }
                    }
                }
                for body in candidates {
                    let lift_margin = self.margin_of(state, &body.target, &body.posture, Some(leg));
                    if lift_margin < p.min_margin_m {
                        continue;
                    }
                    let body_progress = here_progress(&body.target);
                    let next = Next {
                        direction,
                        ahead_m: p.max_body_step_m.min((distance - advance * f).max(0.0)),
                    };
                    match self.step_leg(state, terrain, &body, leg, next, body_progress) {
                        Ok((swing, foothold)) => {
                            if f < 1.0 {
                                tracing::debug!(
                                    leg = %self.legs[leg].name,
                                    fraction = f,
                                    f_max,
                                    why = %why.join("; "),
                                    earlier_legs = %reasons.join(" | "),
                                    "step with less than the full body move"
                                );
                            }
                            return Ok(self.assemble(state, &body, leg, swing, foothold));
                        }
                        Err(e) => why.push(e),
                    }
                }
            }
            why.dedup();
            reasons.push(format!("`{}`: {}", self.legs[leg].name, why.join("; ")));
        }
        Err(GaitError::Blocked {
            reason: reasons.join(" | "),
        })
    }

    /// A body move that also shifts the body toward the middle of the feet that stay when
    /// `leg` lifts.
    fn shifted(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        pose: &Isometry3<f64>,
        leg: usize,
        shift: f64,
    ) -> Result<BodyMove, String> {
        let others = polygon_of(
            state
                .stance_legs()
                .into_iter()
                .filter(|&i| i != leg)
                .map(|i| state.legs[i].foot),
        );
        let centre = others
            .centroid()
            .ok_or_else(|| "no feet would stay".to_string())?;
        let com = com_world(&self.model, pose, &state.posture())
            .ok_or_else(|| "no centre of mass".to_string())?;
        let offset = Vector3::new(centre.x - com.x, centre.y - com.y, 0.0) * shift;
        let target = Isometry3::from_parts(
            Translation3::from(pose.translation.vector + offset),
            pose.rotation,
        );
        self.body_move(state, terrain, &target)
    }

    /// The margin at a body pose and posture over the standing feet, less `lifted`.
    fn margin_of(
        &self,
        state: &GaitState,
        body: &Isometry3<f64>,
        posture: &[Vec<f64>],
        lifted: Option<usize>,
    ) -> f64 {
        let polygon = polygon_of(
            (0..state.legs.len())
                .filter(|&i| state.legs[i].stance && Some(i) != lifted)
                .map(|i| state.legs[i].foot),
        );
        com_world(&self.model, body, posture)
            .map(|c| margin(&polygon, c))
            .unwrap_or(f64::NEG_INFINITY)
    }

    /// Footholds for `leg` with the body at `body`, then a swing to the best that can be
    /// reached.
    fn step_leg(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        body: &BodyMove,
        leg: usize,
        next: Next,
        body_progress: f64,
    ) -> Result<(Swing, Foothold), String> {
        let others: Vec<usize> = state
            .stance_legs()
            .into_iter()
            .filter(|&i| i != leg)
            .collect();
        let polygon = polygon_of(others.iter().map(|&i| state.legs[i].foot));
        let start = body.posture[leg].clone();
        let mut why = Vec::new();
        // The best-ranked footholds first; if none of them is ahead, the best of those
        // that are.
        let needed = self.params.min_progress_m - body_progress;
        for filter in [f64::NEG_INFINITY, needed] {
            let footholds = match self.footholds(state, terrain, body, leg, next, filter) {
                Ok(f) => f,
                Err(e) => {
                    why.push(e);
                    continue;
                }
            };
            let mut tried = 0;
            let mut ahead = false;
            for foothold in footholds {
                if body_progress + foothold.progress < self.params.min_progress_m {
                    continue;
                }
                ahead = true;
                tried += 1;
                if tried > SWINGS_TRIED {
                    break;
                }
                match self.swing(
                    terrain,
                    &body.target,
                    &body.posture,
                    leg,
                    &start,
                    &foothold,
                    &polygon,
                ) {
                    Ok(swing) => return Ok((swing, foothold)),
                    Err(e) => why.push(e),
                }
            }
            if ahead {
                break;
            }
            why.push("no foothold ahead of it".to_string());
        }
        why.dedup();
        Err(if why.is_empty() {
            "no foothold".to_string()
        } else {
            why.join("; ")
        })
    }

    /// Candidate footholds for `leg` with the body at `body`, best first.
    fn footholds(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        body: &BodyMove,
        leg: usize,
        next: Next,
        needed: f64,
    ) -> Result<Vec<Foothold>, String> {
        let direction = next.direction;
        let info = &self.legs[leg];
        let p = &self.params;
        let inverse = body.target.inverse();
        let d3 = inverse.rotation * Vector3::new(direction.x, direction.y, 0.0);
        let d = Vector2::new(d3.x, d3.y);
        let d = if d.norm() > 1e-9 {
            d.normalize()
        } else {
            Vector2::x()
        };
        let n = Point2::new(info.neutral.x, info.neutral.y);
        let ahead = info
            .candidates
            .iter()
            .map(|c| (c.at - n).dot(&d))
            .fold(0.0f64, f64::max);
        let target = 0.8 * ahead;
        // A foot keeps to its own side of the body: no nearer the body's centre line than
        // half its neutral distance from it, so that legs never fold under the body.
        let inboard = 0.5 * n.y.abs();
        let mut ranked: Vec<(f64, &Candidate)> = info
            .candidates
            .iter()
            .filter(|c| c.at.y * n.y.signum() >= inboard)
            .map(|c| {
                let rel = c.at - n;
                let along = rel.dot(&d);
                let side = (rel.x * d.y - rel.y * d.x).abs();
                let pre = -along.min(target) + 0.5 * (along - target).max(0.0) + 0.3 * side;
                (pre / p.scale, c)
            })
            .collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
        let others: Vec<Point3<f64>> = state
            .stance_legs()
            .into_iter()
            .filter(|&i| i != leg)
            .map(|i| state.legs[i].foot)
            .collect();
        let spacing = 2.0 * info.radius + 2.0 * p.clearance_m;
        // Feet of the legs ahead of this one on its side (along the travel direction): its
        // foot does not pass them, so that no leg is left behind another.
        let side = |v: Point3<f64>| (d.x * v.y - d.y * v.x).signum();
        let rank = |v: Point3<f64>| v.x * d.x + v.y * d.y;
        let ahead_of_it: Vec<Point3<f64>> = state
            .stance_legs()
            .into_iter()
            .filter(|&i| {
                i != leg
                    && side(self.legs[i].neutral) == side(info.neutral)
                    && rank(self.legs[i].neutral) > rank(info.neutral) + 1e-6
            })
            .map(|i| state.legs[i].foot)
            .collect();
        let old = state.legs[leg].foot;
        let (mut unknown, mut forbidden, mut unreachable, mut crowded, mut unstable, mut trapping) =
            (0, 0, 0, 0, 0, 0);
        let (mut touching, mut blocking) = (0, 0);
        let further = self.further_on(state, body, leg, next);
        let mut pits = 0;
        let mut found = Vec::new();
        for (pre, candidate) in ranked.into_iter().take(CANDIDATES_TRIED) {
            if found.len() >= FOOTHOLDS_EVALUATED {
                break;
            }
            let c = candidate.at;
            let w = body.target * Point3::new(c.x, c.y, info.neutral.z);
            let xy = Point2::new(w.x, w.y);
            if (xy.x - old.x) * direction.x + (xy.y - old.y) * direction.y < needed {
                continue;
            }
            if ahead_of_it
                .iter()
                .any(|f| (xy.x - f.x) * direction.x + (xy.y - f.y) * direction.y > -0.5 * spacing)
            {
                crowded += 1;
                continue;
            }
            if others
                .iter()
                .any(|o| (Point2::new(o.x, o.y) - xy).norm() < spacing)
            {
                crowded += 1;
                continue;
            }
            let Some(rest) = rest_height(terrain, xy, info.radius) else {
                unknown += 1;
                continue;
            };
            let cost = match terrain.foothold_cost(xy, info.radius) {
                None => {
                    unknown += 1;
                    continue;
                }
                Some(c) if !c.is_finite() => {
                    forbidden += 1;
                    continue;
                }
                Some(c) => c,
            };
            let centre = Point3::new(xy.x, xy.y, rest);
            let local = inverse * centre;
            if local.z < candidate.z_range.0 || local.z > candidate.z_range.1 {
                unreachable += 1;
                continue;
            }
            let Some(joints) = self.ik(leg, &local, &body.posture[leg], 0) else {
                unreachable += 1;
                continue;
            };
            // A foot set in a hollow must be able to climb out of it again.
            let rim = terrain
                .max_height_in_disc(xy, 3.0 * info.radius + p.foothold_spacing_m)
                .unwrap_or(f64::INFINITY);
            let pit = rim - (centre.z - info.radius);
            if pit > 2.0 * p.clearance_m
                && self
                    .raise(&body.target, leg, &joints, pit + 2.0 * p.clearance_m)
                    .is_none()
            {
                pits += 1;
                continue;
            }
            let mut posture = body.posture.clone();
            posture[leg] = joints.clone();
            if self.legs_touch(&posture, Some(leg)).is_some() {
                touching += 1;
                continue;
            }
            if self.blocks_the_next_move(further.as_deref(), leg, &centre, &joints) {
                blocking += 1;
                continue;
            }
            let contact = contact_of_centre(&centre, info.radius);
            let polygon = polygon_of(others.iter().copied().chain(std::iter::once(contact)));
            let Some(com) = com_world(&self.model, &body.target, &posture) else {
                unstable += 1;
                continue;
            };
            let mut new_margin = margin(&polygon, com);
            if new_margin < p.min_margin_m {
                unstable += 1;
                continue;
            }
            // With five feet or more, keep the centre of mass where any one of them could
            // be lifted next (the conservative support polygon), so that no leg is trapped.
            if others.len() + 1 >= 5 {
                let feet: Vec<Point2<f64>> = others
                    .iter()
                    .chain(std::iter::once(&contact))
                    .map(|f| Point2::new(f.x, f.y))
                    .collect();
                let conservative = margin(&conservative_support_polygon(&feet), com);
                if conservative < p.min_margin_m {
                    trapping += 1;
                    continue;
                }
                new_margin = conservative;
            }
            let progress = (xy.x - old.x) * direction.x + (xy.y - old.y) * direction.y;
            let rise = (centre.z - old.z - info.radius).abs();
            let score = pre + p.cost_weight * cost + rise / p.scale
                - p.margin_weight * new_margin.min(5.0 * p.min_margin_m) / (5.0 * p.min_margin_m);
            found.push(Foothold {
                centre,
                joints,
                score,
                progress,
            });
        }
        if found.is_empty() {
            return Err(format!(
                "none of its candidate footholds will do ({unknown} on unknown ground, \
                 {forbidden} on forbidden ground, {unreachable} out of reach, {pits} in a hollow it could \
                 not climb out of, {crowded} too near \
                 another foot, {touching} bringing its links against another leg's, {blocking} \
                 from which the body could not go on, {unstable} too little margin, {trapping} would leave another leg \
                 unable to lift)"
            ));
        }
        found.sort_by(|a, b| a.score.total_cmp(&b.score));
        Ok(found)
    }

    /// The body half and a whole of the next step on, with every other standing leg's
    /// joints there (its foot where it stands), for [`Self::blocks_the_next_move`]: the same
    /// for every foothold of `leg`, so worked out once per leg and body move. `None` when
    /// there is no next step.
    fn further_on(
        &self,
        state: &GaitState,
        body: &BodyMove,
        leg: usize,
        next: Next,
    ) -> Option<Vec<FurtherOn>> {
        if next.ahead_m <= 0.0 {
            return None;
        }
        let step = Vector3::new(next.direction.x, next.direction.y, 0.0) * next.ahead_m;
        let poses = [0.5, 1.0]
            .into_iter()
            .map(|fraction| {
                let pose = Isometry3::from_parts(
                    Translation3::from(body.target.translation.vector + step * fraction),
                    body.target.rotation,
                );
                let inverse = pose.inverse();
                let mut posture = body.posture.clone();
                let mut out_of_reach = None;
                for (i, q) in posture.iter_mut().enumerate() {
                    if i == leg || !state.legs[i].stance {
                        continue;
                    }
                    let at = centre_of_contact(&state.legs[i].foot, self.legs[i].radius);
                    match self.ik(i, &(inverse * at), q, 0) {
                        Some(joints) => *q = joints,
                        None => {
                            out_of_reach = Some(i);
                            break;
                        }
                    }
                }
                FurtherOn {
                    fraction,
                    inverse,
                    posture,
                    out_of_reach,
                }
            })
            .collect();
        Some(poses)
    }

    /// Whether `leg`, set down at `centre` with `joints`, would stop the body going on
    /// (`further`, from [`Self::further_on`]), every standing foot staying where it is: out
    /// of its leg's reach after half the next step, or touching another leg after half or
    /// all of it (a rear foot set far forward under the middle leg's links, a front foot
    /// turned in front of its column, would block every later body move).
    fn blocks_the_next_move(
        &self,
        further: Option<&[FurtherOn]>,
        leg: usize,
        centre: &Point3<f64>,
        joints: &[f64],
    ) -> bool {
        for f in further.unwrap_or_default() {
            // Another foot out of reach there (before this one, in leg order): not this
            // foothold's doing; the body goes less far.
            if f.out_of_reach.is_some_and(|i| i < leg) {
                continue;
            }
            let Some(q) = self.ik(leg, &(f.inverse * centre), joints, 0) else {
                // This foot out of reach half a step on: it would hold the body back.
                if f.fraction <= 0.5 {
                    return true;
                }
                continue;
            };
            if f.out_of_reach.is_some() {
                continue;
            }
            let mut posture = f.posture.clone();
            posture[leg] = q;
            if self.legs_touch(&posture, Some(leg)).is_some() {
                return true;
            }
        }
        false
    }

    /// Joint positions that move the foot of `leg` up by `rise` metres (world).
    fn raise(&self, body: &Isometry3<f64>, leg: usize, q: &[f64], rise: f64) -> Option<Vec<f64>> {
        let model_leg = &self.model.legs()[leg];
        if let Some(k) = self.legs[leg].slide {
            let jacobian = model_leg.jacobian(q).ok()?;
            let column = jacobian.column(k);
            let per_unit = (body.rotation * Vector3::new(column[0], column[1], column[2])).z;
            if per_unit.abs() > 0.7 {
                let mut out = q.to_vec();
                out[k] += rise / per_unit;
                if model_leg.within_limits(&out) {
                    return Some(out);
                }
                return None;
            }
        }
        let centre = body * model_leg.foot_position(q).ok()? + Vector3::z() * rise;
        self.ik(leg, &(body.inverse() * centre), q, 2)
    }

    /// Samples along a joint-space segment of one leg: enough for the foot to move at most
    /// `sample_m` between them.
    fn segment_samples(&self, leg: usize, a: &[f64], b: &[f64]) -> usize {
        let l = &self.model.legs()[leg];
        let mid: Vec<f64> = a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect();
        let (Ok(fa), Ok(fm), Ok(fb)) = (
            l.foot_position(a),
            l.foot_position(&mid),
            l.foot_position(b),
        ) else {
            return 1;
        };
        let travel = (fm - fa).norm() + (fb - fm).norm();
        ((travel / self.params.sample_m).ceil() as usize).clamp(2, 400)
    }

    /// Plans a swing of `leg` from `start` to a foothold with the body still: lift, travel
    /// above the terrain, lower to a way-point a little below the foothold.
    #[allow(clippy::too_many_arguments)]
    fn swing(
        &self,
        terrain: &dyn TerrainView,
        body: &Isometry3<f64>,
        posture: &[Vec<f64>],
        leg: usize,
        start: &[f64],
        foothold: &Foothold,
        polygon: &Polygon,
    ) -> Result<Swing, String> {
        let p = &self.params;
        let info = &self.legs[leg];
        let r = info.radius;
        let name = &info.name;
        let inverse = body.inverse();
        let start_centre = self.foot_centre(body, leg, start);
        // The last way-point, a little below the foothold.
        let below = [p.below_foothold_m, p.below_foothold_m / 3.0]
            .iter()
            .find_map(|&depth| {
                let target = inverse * (foothold.centre - Vector3::z() * depth);
                self.ik(leg, &target, &foothold.joints, 2)
            })
            .ok_or_else(|| format!("leg `{name}` cannot reach below its foothold"))?;
        // The height the foot must travel at: above both ends and the ground between.
        let mut top = start_centre.z.max(foothold.centre.z) + 2.0 * p.clearance_m;
        let span = Point2::new(
            foothold.centre.x - start_centre.x,
            foothold.centre.y - start_centre.y,
        );
        let steps = ((span.coords.norm() / p.sample_m).ceil() as usize).max(1);
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            let c = Point2::new(start_centre.x, start_centre.y) + span.coords * t;
            let h = terrain
                .max_height_in_disc(c, r + p.clearance_m)
                .ok_or_else(|| format!("the ground under leg `{name}`'s swing is unknown"))?;
            top = top.max(h + r + p.clearance_m * 1.5);
        }
        let mut why = String::from("no lift height clears the terrain");
        for level in 0..6 {
            let z = top + level as f64 * 0.15 * p.scale;
            // Lift to the travel height, or when the leg cannot, a little: the travel then
            // climbs toward the height over the foothold.
            let rise = z - start_centre.z;
            let Some(lifted) = self.raise(body, leg, start, rise).or_else(|| {
                // As high as the leg can: bisect between a small lift and the full one.
                let small = (3.0 * p.clearance_m).min(rise);
                let mut best = self.raise(body, leg, start, small)?;
                let (mut lo, mut hi) = (small, rise);
                for _ in 0..8 {
                    let mid = 0.5 * (lo + hi);
                    match self.raise(body, leg, start, mid) {
                        Some(q) => {
                            best = q;
                            lo = mid;
                        }
                        None => hi = mid,
                    }
                }
                Some(best)
            }) else {
                why = format!("leg `{name}` cannot lift {rise:.2} m");
                break;
            };
            let Some(high) = self.raise(body, leg, &foothold.joints, z - foothold.centre.z) else {
                why = format!(
                    "leg `{name}` cannot reach {:.2} m above its foothold",
                    z - foothold.centre.z
                );
                break;
            };
            let mut com_path = Vec::new();
            // The first segment leaves where the foot is, on the ground or in the air: that
            // place is free whatever the map says (a foot stopped in the air below the
            // mapped ground found the map too high there), so it is judged as a lift.
            let first = Segment::Lift;
            let result = self
                .segment(
                    terrain,
                    body,
                    posture,
                    leg,
                    start,
                    &lifted,
                    first,
                    &mut com_path,
                )
                .and_then(|_| {
                    self.segment(
                        terrain,
                        body,
                        posture,
                        leg,
                        &lifted,
                        &high,
                        Segment::Travel,
                        &mut com_path,
                    )
                })
                .and_then(|_| {
                    self.segment(
                        terrain,
                        body,
                        posture,
                        leg,
                        &high,
                        &below,
                        Segment::Lower,
                        &mut com_path,
                    )
                });
            let contact = match result {
                Ok(Some(c)) => c,
                Ok(None) => {
                    why = format!("leg `{name}` would not reach the ground at its foothold");
                    continue;
                }
                Err(e) => {
                    why = e;
                    continue;
                }
            };
            let (contact_joints, contact_centre) = contact;
            if (contact_centre - foothold.centre).norm() > 0.5 * r + 2.0 * p.sample_m {
                why = format!("leg `{name}` would touch down away from its foothold");
                continue;
            }
            let worst = margin_along_path(polygon, &com_path)
                .map(|m| m.margin_m)
                .unwrap_or(f64::NEG_INFINITY);
            if worst.is_nan() || worst < p.min_margin_m {
                return Err(format!(
                    "swinging leg `{name}` would leave a margin of {worst:.3} m"
                ));
            }
            let mut waypoints = vec![lifted, high, below];
            waypoints.dedup_by(|a, b| a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() < 1e-9));
            if waypoints
                .first()
                .is_some_and(|w| w.iter().zip(start).all(|(x, y)| (x - y).abs() < 1e-9))
            {
                waypoints.remove(0);
            }
            return Ok(Swing {
                waypoints,
                contact_joints,
                contact_centre,
                min_margin: worst,
            });
        }
        Err(why)
    }

    /// Checks one swing segment, adding the centre of mass along it to `com_path`. A
    /// lowering segment returns where it first touches the ground.
    #[allow(clippy::too_many_arguments)]
    fn segment(
        &self,
        terrain: &dyn TerrainView,
        body: &Isometry3<f64>,
        posture: &[Vec<f64>],
        leg: usize,
        a: &[f64],
        b: &[f64],
        kind: Segment,
        com_path: &mut Vec<Point3<f64>>,
    ) -> Result<Option<Contact>, String> {
        let p = &self.params;
        let info = &self.legs[leg];
        let r = info.radius;
        let n = self.segment_samples(leg, a, b);
        let at = |t: f64| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x + (y - x) * t).collect() };
        let mut q = posture.to_vec();
        let start = if kind == Segment::Lift { 0 } else { 1 };
        // A foot lifting starts where it stands, which a map with noise may put a little in
        // the ground: it must not go deeper than it starts.
        let mut lift_floor = -0.25 * p.clearance_m;
        for k in start..=n {
            let t = k as f64 / n as f64;
            let joints = at(t);
            let centre = self.foot_centre(body, leg, &joints);
            let clearance = sphere_clearance(terrain, &centre, r);
            match kind {
                Segment::Lift => {
                    if k == 0
                        && let Some(c) = clearance
                    {
                        lift_floor = lift_floor.min(c - 0.25 * p.clearance_m);
                    }
                    if let Some(c) = clearance
                        && c < lift_floor
                    {
                        return Err(format!("leg `{}` would drag its foot lifting", info.name));
                    }
                }
                Segment::Travel => match clearance {
                    None => {
                        return Err(format!(
                            "the ground under leg `{}`'s swing is unknown",
                            info.name
                        ));
                    }
                    Some(c) if c < p.clearance_m * 0.5 => {
                        return Err(format!(
                            "leg `{}`'s foot would pass {c:.3} m over the ground",
                            info.name
                        ));
                    }
                    Some(_) => {
                        // The foot's path bends away from the straight line the travel
                        // height was chosen over: keep it as high above the highest ground
                        // near it, which a map of a steep flank may put lower than it is.
                        let near = terrain
                            .max_height_in_disc(Point2::new(centre.x, centre.y), r + p.clearance_m);
                        if let Some(h) = near
                            && centre.z - r - h < p.clearance_m
                        {
                            return Err(format!(
                                "leg `{}`'s foot would pass {:.3} m over the ground beside it",
                                info.name,
                                centre.z - r - h
                            ));
                        }
                    }
                },
                Segment::Lower => {
                    let Some(c) = clearance else {
                        return Err(format!(
                            "the ground under leg `{}`'s foothold is unknown",
                            info.name
                        ));
                    };
                    if c <= 0.0 {
                        // Contact between the previous sample and this one: bisect.
                        let (mut lo, mut hi) = ((k - 1) as f64 / n as f64, t);
                        for _ in 0..30 {
                            let mid = 0.5 * (lo + hi);
                            let cm = self.foot_centre(body, leg, &at(mid));
                            match sphere_clearance(terrain, &cm, r) {
                                Some(v) if v > 0.0 => lo = mid,
                                _ => hi = mid,
                            }
                        }
                        let joints = at(lo);
                        let centre = self.foot_centre(body, leg, &joints);
                        q[leg] = joints.clone();
                        com_path.extend(com_world(&self.model, body, &q));
                        return Ok(Some((joints, centre)));
                    }
                }
            }
            q[leg] = joints;
            // Where the leg starts is where it is: only where it goes is checked.
            if k > 0
                && let Some(contact) = self.legs_touch(&q, Some(leg))
            {
                return Err(format!("swinging leg `{}`, {contact}", info.name));
            }
            com_path.extend(com_world(&self.model, body, &q));
            let own = Some(leg);
            let fallback = |_: Option<usize>| None;
            self.probes
                .check(
                    &self.model,
                    terrain,
                    body,
                    &q,
                    &|l| l == own,
                    if kind == Segment::Travel {
                        p.clearance_m
                    } else {
                        p.clearance_m * 0.5
                    },
                    &fallback,
                )
                .map_err(|h| match (&h, kind) {
                    (Hit::Unknown { .. }, Segment::Lift) => format!("lifting, {}", h.describe()),
                    _ => format!("swinging leg `{}`, {}", info.name, h.describe()),
                })?;
        }
        Ok(None)
    }

    /// Sets down a leg that is off the ground, the body staying where it is.
    fn place_leg(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        direction: Vector2<f64>,
        leg: usize,
    ) -> Result<StepPlan, GaitError> {
        let posture = state.posture();
        let body = BodyMove {
            target: state.body,
            posture: posture.clone(),
            min_margin: self.margin_of(state, &state.body, &posture, None),
        };
        let name = self.legs[leg].name.clone();
        let footholds = self
            .footholds(
                state,
                terrain,
                &body,
                leg,
                Next {
                    direction,
                    ahead_m: 0.0,
                },
                f64::NEG_INFINITY,
            )
            .map_err(|reason| GaitError::NoFoothold {
                leg: name.clone(),
                reason,
            })?;
        let polygon = polygon_of(state.stance_legs().into_iter().map(|i| state.legs[i].foot));
        let mut why = Vec::new();
        for foothold in footholds.into_iter().take(SWINGS_TRIED) {
            match self.swing(
                terrain,
                &state.body,
                &posture,
                leg,
                &posture[leg],
                &foothold,
                &polygon,
            ) {
                Ok(swing) => return Ok(self.assemble(state, &body, leg, swing, foothold)),
                Err(e) => why.push(e),
            }
        }
        why.dedup();
        Err(GaitError::NoFoothold {
            leg: name,
            reason: why.join("; "),
        })
    }

    /// The plan of a step: the body move (if it moves) and the swing.
    fn assemble(
        &self,
        state: &GaitState,
        body: &BodyMove,
        leg: usize,
        swing: Swing,
        _foothold: Foothold,
    ) -> StepPlan {
        let mut actions = Vec::new();
        let moved = (body.target.translation.vector - state.body.translation.vector).norm() > 1e-9
            || body.target.rotation.angle_to(&state.body.rotation) > 1e-9;
        if moved {
            actions.push(Action::Body {
                target: body.target,
            });
        }
        let r = self.legs[leg].radius;
        let foothold = contact_of_centre(&swing.contact_centre, r);
        actions.push(Action::Swing {
            leg,
            waypoints: swing.waypoints.clone(),
            foothold,
        });
        let mut legs: Vec<LegGaitState> = state.legs.clone();
        for (i, l) in legs.iter_mut().enumerate() {
            l.joints = body.posture[i].clone();
        }
        legs[leg] = LegGaitState {
            joints: swing.contact_joints,
            stance: true,
            foot: foothold,
        };
        let min_margin = if moved {
            body.min_margin.min(swing.min_margin)
        } else {
            swing.min_margin
        };
        StepPlan {
            actions,
            end: GaitState {
                body: body.target,
                legs,
            },
            min_margin_m: min_margin,
        }
    }
}

/// Stands a robot on the terrain at (x, y) facing `yaw`: the body level, every foot where
/// its neutral position puts it, resting on the ground, the body at its neutral height
/// over the feet's mean. Fails where a foot's ground is unknown or out of reach.
pub fn stand(
    model: &RobotModel,
    terrain: &dyn TerrainView,
    x: f64,
    y: f64,
    yaw: f64,
) -> Result<GaitState, GaitError> {
    let rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
    let mut rests = Vec::new();
    for leg in model.legs() {
        let n = leg
            .foot_position(&leg.neutral())
            .map_err(|e| GaitError::BadState {
                reason: e.to_string(),
            })?;
        let w = Point2::new(x, y) + (rotation * Vector3::new(n.x, n.y, 0.0)).xy();
        let rest = rest_height(terrain, w, leg.foot_radius()).ok_or_else(|| {
            GaitError::UnknownTerrain {
                what: format!(
                    "under leg `{}` standing at ({:.2}, {:.2})",
                    leg.name(),
                    w.x,
                    w.y
                ),
            }
        })?;
        rests.push((w, rest, n));
    }
    let z = rests.iter().map(|(_, rest, n)| rest - n.z).sum::<f64>() / rests.len().max(1) as f64;
    let body = Isometry3::from_parts(Translation3::new(x, y, z), rotation);
    let inverse = body.inverse();
    let mut legs = Vec::new();
    for (leg, (w, rest, _)) in model.legs().iter().zip(rests) {
        let centre = Point3::new(w.x, w.y, rest);
        let joints = leg
            .inverse_kinematics(&(inverse * centre), &IkOptions::starting_at(&leg.neutral()))
            .map_err(|e| GaitError::NoFoothold {
                leg: leg.name().to_string(),
                reason: format!("it cannot reach the ground standing: {e}"),
            })?
            .joints;
        legs.push(LegGaitState {
            joints,
            stance: true,
            foot: contact_of_centre(&centre, leg.foot_radius()),
        });
    }
    Ok(GaitState { body, legs })
}
