//! Forward and turn speeds into leg and body moves: the walking robot's side of the
//! body-level interface.
//!
//! A drive command of speeds `(v, ω)` held for `dt` becomes a target for the body: its
//! planar pose moved `v·dt` forward and turned by `ω·dt`. The [`Stepper`] then gives one
//! checked move at a time (the free gait's `move_body_to` and `swing_to`, which test reach,
//! the stability margin, the links against the terrain and the legs against each other)
//! until the body is there:
//!
//! 1. a foot in the air is set down first;
//! 2. a standing foot that would stray more than `max_foot_offset_m` from its place under
//!    the body's next pose is re-placed, the farthest first: swung to its neutral place
//!    under that pose moved on by a lead (the command's speeds times `lead_s`), so that the
//!    feet run ahead of the body in the direction it goes;
//! 3. otherwise the body moves toward the target by at most `max_body_move_m` and
//!    `max_body_turn_rad`, level, at the robot's neutral height over its standing feet;
//! 4. a body move that cannot be made re-places the foot that strays most, and failing
//!    that a shorter body move is tried.
//!
//! Any number of legs works; one leg swings at a time (the quasi-static simulator's
//! `legged.legMove` moves one leg), so at least all but one foot always stand.

use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion};
use tca_free_gait::{Action, FreeGait, GaitParams, GaitState, GridView, StepPlan};
use tca_legged_model::RobotModel;
use tca_nav_sensing::{Pose2, wrap};
use tca_robot::HeightField;

/// How the stepper walks.
#[derive(Debug, Clone, PartialEq)]
pub struct StepperParams {
    /// Longest body translation of one move, m.
    pub max_body_move_m: f64,
    /// Largest body turn of one move, rad.
    pub max_body_turn_rad: f64,
    /// A standing foot farther than this (horizontally) from its neutral place under the
    /// body's next pose is re-placed before the body moves, m.
    pub max_foot_offset_m: f64,
    /// Feet are set where the command's speeds take the body in this time, s.
    pub lead_s: f64,
    /// The lead at most, m.
    pub max_lead_m: f64,
    /// The lead's turn at most, rad.
    pub max_lead_rad: f64,
    /// The body counts as at its target within this distance, m.
    pub position_tolerance_m: f64,
    /// ... and within this heading, rad.
    pub heading_tolerance_rad: f64,
    /// Moves tried for one drive command before it ends where the body is.
    pub max_moves: usize,
}

impl StepperParams {
    /// Defaults scaled to a robot: for the hexapod (feet about 0.33 m from the body's
    /// centre), 3 cm body moves of at most 0.1 rad, feet re-placed beyond 5 cm from
    /// their place, led by up to 3 cm and 0.08 rad.
    pub fn for_model(model: &RobotModel) -> Self {
        let size = foot_spread_m(model).max(1e-3);
        let s = size / 0.33;
        Self {
            max_body_move_m: 0.03 * s,
            max_body_turn_rad: 0.1,
            max_foot_offset_m: 0.05 * s,
            lead_s: 0.5,
            max_lead_m: 0.03 * s,
            max_lead_rad: 0.08,
            position_tolerance_m: 0.001 * s,
            heading_tolerance_rad: 0.005,
            max_moves: 40,
        }
    }
}

/// The mean horizontal distance of the neutral feet from the body's origin, m.
pub fn foot_spread_m(model: &RobotModel) -> f64 {
    let legs = model.legs();
    let total: f64 = legs
        .iter()
        .filter_map(|l| l.foot_position(&l.neutral()).ok())
        .map(|p| p.x.hypot(p.y))
        .sum();
    total / legs.len().max(1) as f64
}

/// The largest horizontal distance of a neutral foot's outer edge from the body's origin,
/// m: the radius of the circle the robot stands in.
pub fn footprint_radius_m(model: &RobotModel) -> f64 {
    model
        .legs()
        .iter()
        .filter_map(|l| {
            l.foot_position(&l.neutral())
                .ok()
                .map(|p| p.x.hypot(p.y) + l.foot_radius())
        })
        .fold(0.0, f64::max)
}

/// What the stepper asks for next.
#[derive(Debug, Clone, PartialEq)]
pub enum Next {
    /// Carry out these moves, in order (stop at the first that fails), then ask again.
    Move(StepPlan),
    /// The body is at its target.
    Arrived,
    /// No move gets the body nearer its target from here: why.
    Stuck(String),
}

/// One drive command being walked: its target and lead, and the moves made so far.
#[derive(Debug, Clone, PartialEq)]
pub struct Walk {
    target: Pose2,
    lead: (f64, f64),
    moves: usize,
    failures: usize,
    /// Swings planned since the body last moved.
    swings: usize,
    ended: Option<WalkEnd>,
}

/// How a drive command's walk ended.
#[derive(Debug, Clone, PartialEq)]
pub enum WalkEnd {
    /// The body reached the target.
    Arrived,
    /// The stepper found no move: why.
    Stuck(String),
    /// The moves allowed for one command ran out.
    OutOfMoves,
}

impl Walk {
    /// The moves planned so far.
    pub fn moves(&self) -> usize {
        self.moves
    }

    /// Moves that failed when carried out.
    pub fn failures(&self) -> usize {
        self.failures
    }

    /// How it ended (`None` while it goes on).
    pub fn end(&self) -> Option<&WalkEnd> {
        self.ended.as_ref()
    }

    /// The target of the body's planar pose.
    pub fn target(&self) -> Pose2 {
        self.target
    }

    /// The moves to carry out next from `state` (as the Controller reports it after the
    /// last ones), or `None` when the walk is over ([`Walk::end`] says how).
    pub fn next(&mut self, stepper: &Stepper, state: &GaitState) -> Option<Vec<Action>> {
        if self.ended.is_some() {
            return None;
        }
        if self.moves >= stepper.params.max_moves {
            self.ended = Some(WalkEnd::OutOfMoves);
            return None;
        }
        match stepper.next(state, self.target, self.lead) {
            Next::Move(plan) => {
                self.moves += 1;
                if plan
                    .actions
                    .iter()
                    .any(|a| matches!(a, Action::Body { .. }))
                {
                    self.swings = 0;
                } else {
                    self.swings += 1;
                }
                // Every foot re-placed twice over without the body moving: it goes nowhere.
                if self.swings > 2 * stepper.neutral.len() {
                    self.ended = Some(WalkEnd::Stuck(format!(
                        "{} feet re-placed without the body moving",
                        self.swings - 1
                    )));
                    return None;
                }
                Some(plan.actions)
            }
            Next::Arrived => {
                self.ended = Some(WalkEnd::Arrived);
                None
            }
            Next::Stuck(why) => {
                self.ended = Some(WalkEnd::Stuck(why));
                None
            }
        }
    }

    /// A move of the last ones failed when carried out (the rest were not): the next call
    /// plans from where the robot is.
    pub fn failed(&mut self) {
        self.failures += 1;
    }
}

/// Plans a walking robot's moves toward body targets on a terrain it knows (the
/// simulator's, standing in for a walking robot's own foot sensing: the navigator that
/// chooses the targets sees only its camera's map).
#[derive(Debug, Clone)]
pub struct Stepper {
    gait: FreeGait,
    view: GridView,
    params: StepperParams,
    /// Each leg's neutral foot-sphere centre, body frame.
    neutral: Vec<Point3<f64>>,
    /// The body's neutral height over the feet's contact points, m.
    height_m: f64,
}

impl Stepper {
    /// A stepper for `model` on `terrain`, with the free gait's defaults for the robot.
    pub fn new(model: Arc<RobotModel>, terrain: Arc<HeightField>, params: StepperParams) -> Self {
        let gait_params = GaitParams::for_model(&model);
        let neutral = model
            .legs()
            .iter()
            .map(|l| {
                l.foot_position(&l.neutral())
                    .unwrap_or_else(|_| Point3::origin())
            })
            .collect();
        let height_m = model.neutral_height();
        Self {
            gait: FreeGait::new(model, gait_params),
            view: GridView::new(terrain),
            params,
            neutral,
            height_m,
        }
    }

    /// The parameters.
    pub fn params(&self) -> &StepperParams {
        &self.params
    }

    /// The robot.
    pub fn model(&self) -> &RobotModel {
        self.gait.model()
    }

    /// The walk of one drive command from `state`: speeds `forward_mps` and `turn_rps`
    /// held for `duration_s`.
    pub fn walk(
        &self,
        state: &GaitState,
        forward_mps: f64,
        turn_rps: f64,
        duration_s: f64,
    ) -> Walk {
        let p = &self.params;
        let target =
            planar(&state.body).moved(forward_mps * duration_s, 0.0, turn_rps * duration_s);
        let lead = (
            (forward_mps * p.lead_s).clamp(-p.max_lead_m, p.max_lead_m),
            (turn_rps * p.lead_s).clamp(-p.max_lead_rad, p.max_lead_rad),
        );
        Walk {
            target,
            lead,
            moves: 0,
            failures: 0,
            swings: 0,
            ended: None,
        }
    }

    /// The next move from `state` toward the body's planar `target`, feet led by `lead`
    /// (forward m, turn rad).
    pub fn next(&self, state: &GaitState, target: Pose2, lead: (f64, f64)) -> Next {
        if state.legs.len() != self.neutral.len() {
            return Next::Stuck(format!(
                "the state has {} legs, the robot {}",
                state.legs.len(),
                self.neutral.len()
            ));
        }
        let here = planar(&state.body);
        // A foot in the air (a swing that found no ground, say): set it down first.
        if let Some(leg) = state.legs.iter().position(|l| !l.stance) {
            let led = self.led(&here, lead);
            return match self.place(state, leg, &led, &here) {
                Ok(plan) => Next::Move(plan),
                Err(why) => Next::Stuck(why),
            };
        }
        let (forward, left, turn) = here.delta_to(&target);
        let distance = forward.hypot(left);
        let p = &self.params;
        if distance <= p.position_tolerance_m && turn.abs() <= p.heading_tolerance_rad {
            return Next::Arrived;
        }
        let k = (p.max_body_move_m / distance.max(1e-12))
            .min(p.max_body_turn_rad / turn.abs().max(1e-12))
            .min(1.0);
        let next = here.moved(forward * k, left * k, turn * k);
        let led = self.led(&next, lead);
        let mut why = Vec::new();
        // Feet that would stray too far from their places: re-placed first.
        let mut offsets: Vec<(usize, f64)> = (0..state.legs.len())
            .map(|i| (i, self.offset(state, i, &next)))
            .collect();
        offsets.sort_by(|a, b| b.1.total_cmp(&a.1));
        for &(leg, off) in &offsets {
            if off <= p.max_foot_offset_m {
                break;
            }
            match self.place(state, leg, &led, &next) {
                Ok(plan) => return Next::Move(plan),
                Err(e) => why.push(e),
            }
        }
        match self
            .gait
            .move_body_to(state, &self.view, &self.body_pose(state, &next))
        {
            Ok(plan) => return Next::Move(plan),
            Err(e) => {
                tracing::debug!(error = %e, "the body move toward the target is refused");
                why.push(format!("the body move: {e}"))
            }
        }
        for &(leg, off) in &offsets {
            if off > p.max_foot_offset_m || off < 0.2 * p.max_foot_offset_m {
                continue;
            }
            match self.place(state, leg, &led, &next) {
                Ok(plan) => return Next::Move(plan),
                Err(e) => why.push(e),
            }
        }
        for fraction in [0.5, 0.25] {
            let shorter = here.moved(
                forward * k * fraction,
                left * k * fraction,
                turn * k * fraction,
            );
            if let Ok(plan) =
                self.gait
                    .move_body_to(state, &self.view, &self.body_pose(state, &shorter))
            {
                return Next::Move(plan);
            }
        }
        why.dedup();
        Next::Stuck(why.join("; "))
    }

    /// The pose the feet are set under: `at` moved on by the lead, shortened so that no
    /// foot's place moves by more than half the offset at which feet are re-placed (a foot
    /// just set down must not count as straying at once).
    fn led(&self, at: &Pose2, lead: (f64, f64)) -> Pose2 {
        let full = at.moved(lead.0, 0.0, lead.1);
        let shift = (0..self.neutral.len())
            .map(|i| (self.place_under(i, &full) - self.place_under(i, at)).norm())
            .fold(0.0, f64::max);
        let most = 0.5 * self.params.max_foot_offset_m;
        if shift <= most {
            return full;
        }
        let k = most / shift;
        at.moved(lead.0 * k, 0.0, lead.1 * k)
    }

    /// How far (horizontally) a standing foot is from its neutral place under `at`, m.
    fn offset(&self, state: &GaitState, leg: usize, at: &Pose2) -> f64 {
        let l = &state.legs[leg];
        if !l.stance {
            return f64::INFINITY;
        }
        (self.place_under(leg, at) - Point2::new(l.foot.x, l.foot.y)).norm()
    }

    /// Where a leg's neutral foot comes under the planar pose `at`, world X and Y.
    fn place_under(&self, leg: usize, at: &Pose2) -> Point2<f64> {
        let n = self.neutral[leg];
        let (s, c) = at.yaw.sin_cos();
        Point2::new(at.x + c * n.x - s * n.y, at.y + s * n.x + c * n.y)
    }

    /// A swing of `leg` to its place under `led`, or nearer the body at `next` when that
    /// cannot be reached, or a little to either side.
    fn place(
        &self,
        state: &GaitState,
        leg: usize,
        led: &Pose2,
        next: &Pose2,
    ) -> Result<StepPlan, String> {
        let ahead = self.place_under(leg, led);
        let under = self.place_under(leg, next);
        let side = {
            let d = ahead - under;
            let n = d.norm();
            if n > 1e-9 {
                nalgebra::Vector2::new(-d.y, d.x) / n
            } else {
                let (s, c) = next.yaw.sin_cos();
                nalgebra::Vector2::new(-s, c)
            }
        };
        let jog = 0.4 * self.params.max_foot_offset_m;
        let candidates = [
            ahead,
            Point2::from(0.5 * (ahead.coords + under.coords)),
            under,
            ahead + side * jog,
            ahead - side * jog,
        ];
        let mut why = Vec::new();
        for at in candidates {
            match self.gait.swing_to(state, &self.view, leg, at) {
                Ok(plan) => return Ok(plan),
                Err(e) => why.push(e),
            }
        }
        why.dedup();
        Err(format!(
            "leg `{}` cannot be re-placed: {}",
            self.gait.model().legs()[leg].name(),
            why.join("; ")
        ))
    }

    /// The body's pose at the planar pose `at`: level, at the neutral height over the
    /// standing feet.
    fn body_pose(&self, state: &GaitState, at: &Pose2) -> Isometry3<f64> {
        let standing: Vec<f64> = state
            .legs
            .iter()
            .filter(|l| l.stance)
            .map(|l| l.foot.z)
            .collect();
        let ground = if standing.is_empty() {
            state.body.translation.z - self.height_m
        } else {
            standing.iter().sum::<f64>() / standing.len() as f64
        };
        Isometry3::from_parts(
            Translation3::new(at.x, at.y, ground + self.height_m),
            UnitQuaternion::from_euler_angles(0.0, 0.0, at.yaw),
        )
    }
}

/// The planar pose of a body: its origin's X and Y and its yaw (of roll, pitch and yaw,
/// as the Controller's body pose gives them).
pub fn planar(body: &Isometry3<f64>) -> Pose2 {
    let (_, _, yaw) = body.rotation.euler_angles();
    Pose2::new(body.translation.x, body.translation.y, wrap(yaw))
}
