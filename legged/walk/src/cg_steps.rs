//! CG-space planning (`tca-cg-space`) as the walking module's step source.
//!
//! At the first step, and whenever the robot is not where the plan expected it, the walk is
//! planned from where the robot stands to the goal: a route of CG cells and the foot moves
//! along it (advance the CG one cell; place, move or lift one foot). Each foot move and each
//! advance is carried out by one of the free gait's single moves (a swing to the foot cell's
//! centre, a lift, the body's move to the next cell), which checks it against the real robot
//! as the free gait checks its own moves: reach along the way, the stability margin with the
//! centre of mass from the links, every part against the terrain, the legs against each
//! other. The moves before each advance and the advance make one step.
//!
//! Where a move cannot be carried out, the steps before it are kept, and the foot cell it
//! went to (for a swing) or the CG cell it went to (for an advance) is marked unusable in
//! the CG-space before the walk is planned again from where the kept steps leave the robot:
//! the feedback from execution to the route planner, one level below the foot-level
//! search's own.
//!
//! The planner plans on the terrain it is given, as the paper's planner did on its height
//! map of the whole terrain.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion};
use tca_cg_space::{CgCell, CgError, CgParams, CgSpace, FootStep, Plan, PlanParams, plan};
use tca_free_gait::terrain::GridView;
use tca_free_gait::{FreeGait, GaitParams, GaitState, StepPlan};
use tca_legged_model::RobotModel;
use tca_robot::HeightField;

/// Plans tried from one place (each after marking what the last could not do) before the
/// walk gives up there.
const PLAN_ATTEMPTS: usize = 12;
/// The robot is where a planned step starts when its body is within this share of a cell
/// and every foot within [`FOOT_MATCH`] of one.
const BODY_MATCH: f64 = 0.02;
/// See [`BODY_MATCH`].
const FOOT_MATCH: f64 = 0.05;
/// Body heights tried for an advance, as multiples of a tenth of the standing height
/// about the planner's height.
const HEIGHT_TRIES: [f64; 7] = [0.0, -0.5, 0.5, -1.0, 1.0, -1.5, 1.5];

/// Steps from the CG-space planner, planned once for the walk and again when the robot is
/// not where they expected it.
pub struct CgSteps {
    gait: FreeGait,
    view: GridView,
    space: Mutex<CgSpace>,
    params: PlanParams,
    lift_m: f64,
    stand_m: f64,
    /// The plan's steps still to come, each with the state it starts from.
    queue: Mutex<VecDeque<(GaitState, StepPlan)>>,
}

impl std::fmt::Debug for CgSteps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CgSteps").finish_non_exhaustive()
    }
}

/// What [`CgSteps::next_step`] gives.
pub struct CgNext {
    /// The step.
    pub step: StepPlan,
    /// The whole plan, when this step began a new one.
    pub new_plan: Option<CgPlanned>,
}

/// A plan of the whole walk, for the report.
#[derive(Debug, Clone, PartialEq)]
pub struct CgPlanned {
    /// The route's cells as `[x, y, heading]`, world frame, metres and radians.
    pub route: Vec<[f64; 3]>,
    /// Every foothold the plan places a foot on, `[x, y]`.
    pub footholds: Vec<[f64; 2]>,
    /// Foot-level search nodes expanded.
    pub nodes: usize,
    /// Routes planned (the first, and one after each cell the search marked).
    pub routes: usize,
    /// The route's length over the ground, metres.
    pub length_m: f64,
    /// Cells and foot cells marked unusable so far by moves that could not be carried out.
    pub marked_by_execution: usize,
}

/// What a move that cannot be carried out should mark.
enum Unusable {
    /// A foot cell.
    Foot((i32, i32)),
    /// A CG cell.
    Cg(CgCell),
}

impl CgSteps {
    /// A step source for `model` on `terrain`: the CG-space with `cg` (its stability margin
    /// raised to the free gait's, plus an allowance for the legs' share of the centre of
    /// mass, unless given), planned with `params`, the moves checked with the free gait's
    /// `gait` parameters.
    pub fn new(
        model: Arc<RobotModel>,
        terrain: Arc<HeightField>,
        mut cg: CgParams,
        params: PlanParams,
        gait: GaitParams,
    ) -> Result<Self, String> {
        if cg.stability_margin_m.is_none() {
            cg.stability_margin_m = Some(1.5 * gait.min_margin_m);
        }
        let space = CgSpace::for_model(&model, &terrain, cg).map_err(|e| e.to_string())?;
        let lift_m = 3.0 * gait.clearance_m;
        let stand_m = model.neutral_height();
        Ok(CgSteps {
            gait: FreeGait::new(model, gait),
            view: GridView::new(terrain),
            space: Mutex::new(space),
            params,
            lift_m,
            stand_m,
            queue: Mutex::new(VecDeque::new()),
        })
    }

    /// The next step from `state` toward `goal`: the plan's next one if the robot stands
    /// where it starts, otherwise the first of a new plan from where it stands. `Ok(None)`
    /// when the plan has no step left (the CG is in the goal's cell).
    pub fn next_step(
        &self,
        state: &GaitState,
        goal: Point2<f64>,
    ) -> Result<Option<CgNext>, String> {
        let mut queue = self.queue.lock().unwrap_or_else(|p| p.into_inner());
        let cell_m = self.cell_m();
        if let Some((start, _)) = queue.front()
            && same_place(start, state, cell_m)
        {
            return Ok(queue.pop_front().map(|(_, step)| CgNext {
                step,
                new_plan: None,
            }));
        }
        queue.clear();
        let mut space = self.space.lock().unwrap_or_else(|p| p.into_inner());
        let mut last_problem = String::new();
        let mut marked = 0;
        for attempt in 0..PLAN_ATTEMPTS {
            let began = Instant::now();
            let found = self.plan_from(&mut space, state, goal)?;
            tracing::debug!(
                attempt,
                ms = began.elapsed().as_secs_f64() * 1e3,
                steps = found.feet.steps.len(),
                "CG-space planned the walk"
            );
            if found.feet.steps.is_empty() {
                return Ok(None);
            }
            let (steps, problem) = self.steps_of(&space, &found, state);
            let summary = self.summary(&space, &found, marked);
            if let Some((why, unusable)) = problem {
                tracing::debug!(attempt, problem = %why, kept = steps.len(), "a planned move cannot be carried out");
                match unusable {
                    Unusable::Foot((ix, iy)) => space.forbid_foot(ix, iy),
                    Unusable::Cg(c) => space.mark_invalid(c),
                }
                marked += 1;
                last_problem = why;
            }
            if !steps.is_empty() {
                *queue = steps.into();
                return Ok(queue.pop_front().map(|(_, step)| CgNext {
                    step,
                    new_plan: Some(summary),
                }));
            }
        }
        Err(format!(
            "{PLAN_ATTEMPTS} CG-space plans from here begin with a move that cannot be carried out; the last: {last_problem}"
        ))
    }

    /// The CG cell's side, metres.
    pub fn cell_m(&self) -> f64 {
        self.space
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .grid()
            .cell_m
    }

    /// A CG-space plan from the robot's state to `goal`, heading kept.
    fn plan_from(
        &self,
        space: &mut CgSpace,
        state: &GaitState,
        goal: Point2<f64>,
    ) -> Result<Plan, String> {
        let t = state.body.translation;
        let yaw = state.body.rotation.euler_angles().2;
        let feet: Vec<Option<Point2<f64>>> = state
            .legs
            .iter()
            .map(|l| l.stance.then(|| Point2::new(l.foot.x, l.foot.y)))
            .collect();
        plan(
            space,
            (Point2::new(t.x, t.y), yaw),
            (goal, yaw),
            Some(&feet),
            &self.params,
        )
        .map_err(|e| match e {
            CgError::Unreachable { .. } => format!("the goal cannot be reached: {e}"),
            e => format!("the CG-space planner found no way: {e}"),
        })
    }

    /// The plan's moves as steps from `state`, up to the first that cannot be carried out
    /// (why, and what to mark for it).
    fn steps_of(
        &self,
        space: &CgSpace,
        found: &Plan,
        state: &GaitState,
    ) -> (Vec<(GaitState, StepPlan)>, Option<(String, Unusable)>) {
        let grid = *space.grid();
        let mut at = state.clone();
        let mut steps = Vec::new();
        let mut pending: Option<(GaitState, StepPlan)> = None;
        let route = &found.feet.route;
        let mut k = 0;
        for fs in &found.feet.steps {
            let next_cell = route[(k + 1).min(route.len() - 1)];
            let planned = match *fs {
                FootStep::Place { leg, to, .. } => self
                    .gait
                    .swing_to(&at, &self.view, leg, grid.centre(to.0, to.1))
                    .map_err(|e| (e, Unusable::Foot(to))),
                FootStep::Lift { leg, .. } => self
                    .gait
                    .lift_leg(&at, &self.view, leg, self.lift_m)
                    .map_err(|e| (e, Unusable::Cg(next_cell))),
                FootStep::Advance { to, body_z } => self
                    .advance(&at, &grid, to, body_z)
                    .map_err(|e| (e, Unusable::Cg(to))),
            };
            let move_plan = match planned {
                Ok(p) => p,
                Err(problem) => {
                    // A step whose advance is missing is not kept: the next plan starts
                    // where its foot moves left the robot anyway.
                    if let Some(p) = pending.take() {
                        steps.push(p);
                    }
                    return (steps, Some(problem));
                }
            };
            let end = move_plan.end.clone();
            match &mut pending {
                Some((_, step)) => {
                    step.actions.extend(move_plan.actions);
                    step.min_margin_m = step.min_margin_m.min(move_plan.min_margin_m);
                    step.end = end.clone();
                }
                None => pending = Some((at.clone(), move_plan)),
            }
            if matches!(fs, FootStep::Advance { .. }) {
                k += 1;
                if let Some(p) = pending.take() {
                    steps.push(p);
                }
            }
            at = end;
        }
        if let Some(p) = pending.take() {
            steps.push(p);
        }
        (steps, None)
    }

    /// The body's move to a CG cell at the planner's height, or the nearest height to it at
    /// which the move can be carried out.
    fn advance(
        &self,
        at: &GaitState,
        grid: &tca_cg_space::CgGrid,
        to: CgCell,
        body_z: f64,
    ) -> Result<StepPlan, String> {
        let c = grid.centre(to.ix, to.iy);
        let rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, grid.theta(to.it));
        let mut first = None;
        for k in HEIGHT_TRIES {
            let z = body_z + k * 0.1 * self.stand_m;
            let target = Isometry3::from_parts(Translation3::new(c.x, c.y, z), rotation);
            match self.gait.move_body_to(at, &self.view, &target) {
                Ok(p) => return Ok(p),
                Err(e) => {
                    first.get_or_insert(e);
                }
            }
        }
        Err(format!(
            "the body's move to ({:.2}, {:.2}): {}",
            c.x,
            c.y,
            first.unwrap_or_default()
        ))
    }

    fn summary(&self, space: &CgSpace, found: &Plan, marked_by_execution: usize) -> CgPlanned {
        let grid = space.grid();
        let route: Vec<[f64; 3]> = found
            .feet
            .route
            .iter()
            .map(|c| {
                let p = grid.centre(c.ix, c.iy);
                [p.x, p.y, grid.theta(c.it)]
            })
            .collect();
        let length_m = route
            .windows(2)
            .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
            .sum();
        let footholds = found
            .feet
            .steps
            .iter()
            .filter_map(|s| match *s {
                FootStep::Place { to, .. } => {
                    let p = grid.centre(to.0, to.1);
                    Some([p.x, p.y])
                }
                _ => None,
            })
            .collect();
        CgPlanned {
            route,
            footholds,
            nodes: found.feet.nodes,
            routes: found.routes,
            length_m,
            marked_by_execution,
        }
    }
}

/// Whether two states are the same place: the bodies within [`BODY_MATCH`] of a cell and
/// 0.01 rad, the same feet standing, every foot within [`FOOT_MATCH`] of a cell.
fn same_place(a: &GaitState, b: &GaitState, cell_m: f64) -> bool {
    (a.body.translation.vector - b.body.translation.vector).norm() <= BODY_MATCH * cell_m
        && a.body.rotation.angle_to(&b.body.rotation) <= 0.01
        && a.legs.len() == b.legs.len()
        && a.legs
            .iter()
            .zip(&b.legs)
            .all(|(x, y)| x.stance == y.stance && (x.foot - y.foot).norm() <= FOOT_MATCH * cell_m)
}
