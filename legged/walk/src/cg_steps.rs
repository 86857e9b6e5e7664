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

use std::cell::{Cell, RefCell};
use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion};
use tca_cg_space::{
    BatchParams, CgCell, CgError, CgGrid, CgParams, CgSpace, FootStep, JoinedRoutes, LocalRoutes,
    MoveCheck, Plan, PlanParams, RoutePlanner, Stance, Standing, apply_step, millimetres,
    plan_with,
};
use tca_cg_space_bus::DistributedJoiner;
use tca_free_gait::terrain::GridView;
use tca_free_gait::{FreeGait, GaitParams, GaitState, StepPlan};
use tca_legged_model::RobotModel;
use tca_module::Module;
use tca_robot::HeightField;

/// Nodes the foot-level search expands without getting further along the route before a
/// walk's planner marks the next cell (see [`SearchParams`](tca_cg_space::SearchParams)).
const WALK_STALL_NODES: usize = 3_000;
/// Route cells a walk's planner backs off from where a search stuck before it searches the
/// new route (see [`PlanParams::backoff_cells`]).
const WALK_BACKOFF_CELLS: usize = 4;

/// The robot is where a planned step starts when its body is within this share of a cell
/// and every foot within [`FOOT_MATCH`] of one.
const BODY_MATCH: f64 = 0.05;
/// See [`BODY_MATCH`].
const FOOT_MATCH: f64 = 0.1;

/// The CG-space layout for walking: one heading bin, so that the robot keeps its heading
/// (the paper allows one bin, "no rotation"): with eight, a route may turn the body a whole
/// bin (45°) between two cells, more than legs with their feet planted follow. The rest as
/// [`CgParams::default`].
pub fn walking_cg_params() -> CgParams {
    CgParams {
        theta_bins: Some(1),
        ..CgParams::default()
    }
}

/// Steps from the CG-space planner, planned once for the walk and again when the robot is
/// not where they expected it.
pub struct CgSteps {
    gait: FreeGait,
    view: GridView,
    space: Mutex<CgSpace>,
    /// The layout the space was built with (workers must build theirs the same).
    cg: CgParams,
    /// Runs the route's roadmap joins on worker modules, if there are any.
    joiner: Option<Mutex<DistributedJoiner>>,
    params: PlanParams,
    lift_m: f64,
    /// The plan's steps still to come, each with the state it starts from.
    queue: Mutex<VecDeque<Queued>>,
}

/// A planned step: the state it was planned from, the step, and its foot-level moves.
#[derive(Debug, Clone)]
struct Queued {
    start: GaitState,
    step: StepPlan,
    moves: Vec<FootStep>,
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
    /// Moves the foot-level search considered that the robot could not carry out.
    pub refused_moves: usize,
}

impl CgSteps {
    /// A step source for `model` on `terrain`: the CG-space with `cg` (unless given, its
    /// stability margin half as much again as the free gait's, its leg clearance the free
    /// gait's and a swing's rise the free gait's travel height over a swing's ends),
    /// planned with `params`, the moves checked with the free gait's `gait` parameters.
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
        cg.leg_clearance_m.get_or_insert(gait.leg_clearance_m);
        cg.swing_rise_m.get_or_insert(2.0 * gait.clearance_m);
        let space = CgSpace::for_model(&model, &terrain, cg.clone()).map_err(|e| e.to_string())?;
        let mut params = params;
        // The search's budget before it hands a cell back to the route planner: on the
        // cliff course, 1,000 nodes gave up on cells a few hundred more would have passed,
        // and the marks then walked the route round the goal until the replans ran out.
        params.search.stall_nodes = params.search.stall_nodes.max(WALK_STALL_NODES);
        // Where the robot cannot get past a cell, its neighbours are usually no better (the
        // edge of a ramp): the next route keeps two cells further off.
        params.mark_radius = params.mark_radius.max(2);
        params.max_replans = params.max_replans.max(60);
        params.backoff_cells = params.backoff_cells.max(WALK_BACKOFF_CELLS);
        // Walks keep the roadmap's routes uncut: with one heading bin there are no turns to
        // take out, and the shortest routes the cuts make graze the invalid regions, where
        // the hexapod's and the spider's searches stuck until the replans ran out.
        params.route.shortcut_cells = 0;
        let lift_m = 3.0 * gait.clearance_m;
        Ok(CgSteps {
            gait: FreeGait::new(model, gait),
            view: GridView::new(terrain),
            space: Mutex::new(space),
            cg,
            joiner: None,
            params,
            lift_m,
            queue: Mutex::new(VecDeque::new()),
        })
    }

    /// Routes planned with their roadmap joins on workers, through `joiner`.
    pub fn with_joiner(mut self, joiner: DistributedJoiner) -> Self {
        self.joiner = Some(Mutex::new(joiner));
        self
    }

    /// The layout the CG-space was built with.
    pub fn cg_params(&self) -> &CgParams {
        &self.cg
    }

    /// A fresh CG-space of the same robot tables, grid and foot map (what workers in this
    /// process start from).
    pub fn space_template(&self) -> CgSpace {
        let space = self.space.lock().unwrap_or_else(|p| p.into_inner());
        CgSpace::with_foot_map(space.robot().clone(), *space.grid(), space.foot_shared())
    }

    /// The next step from `state` toward `goal`: the plan's next one if the robot stands
    /// where it starts, otherwise the first of a new plan from where it stands. A plan ends
    /// in the goal's cell, or, where the foot search cannot get there, on the route cell it
    /// reached whose centre is within `tolerance_m` of the goal (the walk's own test of
    /// arrival). `Ok(None)` when the plan has no step left. A plan's joins on workers are
    /// asked through `asker` (the planning handler's module).
    pub fn next_step(
        &self,
        state: &GaitState,
        goal: Point2<f64>,
        tolerance_m: f64,
        asker: Module,
    ) -> Result<Option<CgNext>, String> {
        let mut queue = self.queue.lock().unwrap_or_else(|p| p.into_inner());
        let cell_m = self.cell_m();
        if let Some(next) = queue.front()
            && same_place(&next.start, state, cell_m)
        {
            // The robot stands where the step starts, give or take a few millimetres: its
            // moves are carried out again from where it really stands, so that the feet
            // keep their clearances from the real state, not the planned one.
            let planned = queue.pop_front().expect("a front");
            let grid = *self.space.lock().unwrap_or_else(|p| p.into_inner()).grid();
            match self.replay(state, &grid, &planned.moves) {
                Ok(step) => {
                    return Ok(Some(CgNext {
                        step,
                        new_plan: None,
                    }));
                }
                Err(why) => {
                    tracing::debug!(%why, "a planned step does not hold from where the robot stands; planning again");
                }
            }
        }
        queue.clear();
        let mut space = self.space.lock().unwrap_or_else(|p| p.into_inner());
        let began = Instant::now();
        let grid = *space.grid();
        let executor = Executor::new(self, &grid, state);
        let found = match &self.joiner {
            None => self.plan_from(
                &mut space,
                state,
                (goal, tolerance_m),
                &executor,
                &mut LocalRoutes,
            )?,
            Some(joiner) => {
                let mut joiner = joiner.lock().unwrap_or_else(|p| p.into_inner());
                joiner.ask_as(asker);
                let mut routes = JoinedRoutes {
                    joiner: &mut *joiner,
                    batch: BatchParams::default(),
                };
                self.plan_from(
                    &mut space,
                    state,
                    (goal, tolerance_m),
                    &executor,
                    &mut routes,
                )?
            }
        };
        tracing::debug!(
            ms = began.elapsed().as_secs_f64() * 1e3,
            steps = found.feet.steps.len(),
            checked = executor.checked.get(),
            refused = executor.refused.get(),
            "CG-space planned the walk"
        );
        if found.feet.steps.is_empty() {
            return Ok(self.final_approach(state, goal, tolerance_m));
        }
        let steps = executor.steps_of(&found)?;
        let summary = self.summary(&space, &found, executor.refused.get());
        *queue = steps.into();
        Ok(queue.pop_front().map(|q| CgNext {
            step: q.step,
            new_plan: Some(summary),
        }))
    }

    /// The CG cell's side, metres.
    pub fn cell_m(&self) -> f64 {
        self.space
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .grid()
            .cell_m
    }

    /// A CG-space plan from the robot's state to `goal` (a point and the tolerance of
    /// arrival), heading kept.
    fn plan_from(
        &self,
        space: &mut CgSpace,
        state: &GaitState,
        (goal, tolerance_m): (Point2<f64>, f64),
        executor: &Executor<'_>,
        routes: &mut dyn RoutePlanner,
    ) -> Result<Plan, String> {
        let t = state.body.translation;
        let yaw = state.body.rotation.euler_angles().2;
        if space.grid().theta_bins == 1 && yaw.abs() > 0.05 {
            return Err(format!(
                "with one heading bin the CG-space plans for a robot facing +X (yaw 0), and this one faces {yaw:.2} rad; start it facing +X or plan with more heading bins"
            ));
        }
        let standing = Standing {
            feet: state
                .legs
                .iter()
                .map(|l| l.stance.then(|| Point2::new(l.foot.x, l.foot.y)))
                .collect(),
            body_z: t.z,
        };
        // The plan may end on a cell this near the goal: a millimetre less than the walk's
        // tolerance, so that the walk agrees the robot has arrived, but at least a cell and
        // a half, since the last body move carries the body the rest of the way (see
        // `final_approach`): a goal whose own cell is invalid (the body's underside reaching
        // past the map's edge there) is then approached from the next valid cell.
        let params = PlanParams {
            goal_tolerance_m: (tolerance_m - 1e-3).max(1.5 * space.grid().cell_m),
            ..self.params.clone()
        };
        plan_with(
            space,
            (Point2::new(t.x, t.y), yaw),
            (goal, yaw),
            Some(&standing),
            &params,
            Some(executor),
            routes,
        )
        .map_err(|e| match e {
            CgError::Unreachable { .. } => format!("the goal cannot be reached: {e}"),
            e => format!("the CG-space planner found no way: {e}"),
        })
    }

    /// The body's move to a CG cell at the planner's height (to the millimetre the search
    /// holds it at).
    fn advance(
        &self,
        at: &GaitState,
        grid: &CgGrid,
        to: CgCell,
        body_z: f64,
    ) -> Result<StepPlan, String> {
        let c = grid.centre(to.ix, to.iy);
        let rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, grid.theta(to.it));
        let z = f64::from(millimetres(body_z)) / 1000.0;
        let target = Isometry3::from_parts(Translation3::new(c.x, c.y, z), rotation);
        self.gait
            .move_body_to(at, &self.view, &target)
            .map_err(|e| format!("the body's move to ({:.2}, {:.2}): {e}", c.x, c.y))
    }

    /// With the plan done (the CG in its last cell) but the body further than `tolerance_m`
    /// from the goal (a cell wider than the tolerance, or a goal whose own cell is invalid),
    /// the body's move onto the goal itself, the feet where they stand, or where some foot
    /// cannot follow it that far, a step of the free gait toward the goal; `None` when the
    /// body is near enough already or neither can be made (the walk then reports how far it
    /// stopped).
    fn final_approach(
        &self,
        state: &GaitState,
        goal: Point2<f64>,
        tolerance_m: f64,
    ) -> Option<CgNext> {
        let t = state.body.translation.vector;
        if (Point2::new(t.x, t.y) - goal).norm() <= tolerance_m {
            return None;
        }
        let target =
            Isometry3::from_parts(Translation3::new(goal.x, goal.y, t.z), state.body.rotation);
        let step = match self.gait.move_body_to(state, &self.view, &target) {
            Ok(step) => step,
            Err(why) => {
                // Some foot cannot follow the body all the way: a step of the free gait toward
                // the goal (a body move and one foot re-placed) instead, until the body is
                // near enough.
                tracing::debug!(%why, "the body cannot move onto the goal from the plan's last cell; a free-gait step toward it");
                self.gait
                    .plan_step(state, &self.view, goal)
                    .map_err(
                        |why| tracing::debug!(%why, "no free-gait step toward the goal either"),
                    )
                    .ok()?
            }
        };
        Some(CgNext {
            step,
            new_plan: None,
        })
    }

    /// Foot-level moves carried out one after another from `state` with the free gait's
    /// checked single moves, as one step.
    fn replay(
        &self,
        state: &GaitState,
        grid: &CgGrid,
        moves: &[FootStep],
    ) -> Result<StepPlan, String> {
        let mut at = state.clone();
        let mut whole: Option<StepPlan> = None;
        for fs in moves {
            let plan = self.carry_out(&at, grid, fs)?;
            at = plan.end.clone();
            match &mut whole {
                Some(step) => append_step(step, &plan),
                None => whole = Some(plan),
            }
        }
        whole.ok_or_else(|| "a step without moves".to_owned())
    }

    /// One foot-level move carried out from `at`.
    fn carry_out(&self, at: &GaitState, grid: &CgGrid, fs: &FootStep) -> Result<StepPlan, String> {
        match *fs {
            FootStep::Place { leg, to, .. } => {
                self.gait
                    .swing_to(at, &self.view, leg, grid.centre(to.0, to.1))
            }
            FootStep::Lift { leg, .. } => self.gait.lift_leg(at, &self.view, leg, self.lift_m),
            FootStep::Advance { to, body_z } => self.advance(at, grid, to, body_z),
        }
    }

    fn summary(&self, space: &CgSpace, found: &Plan, refused_moves: usize) -> CgPlanned {
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
            refused_moves,
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

/// The robot's state at a route cell and stance, and the move that led to it.
type Reached = (GaitState, Option<StepPlan>);

/// The foot-level search's move check: each move the search considers is carried out on
/// the robot's planned state with the free gait's checked single moves; the states and
/// moves that pass are kept, by route cell and stance, to become the walk's steps.
struct Executor<'a> {
    steps: &'a CgSteps,
    grid: CgGrid,
    /// Per (route cell, stance): the robot's state there, the move that led to it, and the
    /// generation of that state (a new one each time a move is carried out).
    states: RefCell<HashMap<Place, (Reached, u64)>>,
    /// Every move carried out so far, by where it started (place and the generation of the
    /// state there) and where it ended: what it gave, `None` where the robot could not carry
    /// it out. A search that runs again after a refusal offers the same moves again; they
    /// are answered from here instead of being carried out again.
    outcomes: RefCell<HashMap<MoveKey, Option<(Reached, u64)>>>,
    generations: Cell<u64>,
    checked: Cell<usize>,
    refused: Cell<usize>,
}

/// A route cell and the stance there.
type Place = (CgCell, Stance);

/// A move by where it started (the place and the generation of the state there) and where
/// it ended.
type MoveKey = (Place, u64, Place);

impl<'a> Executor<'a> {
    /// An executor whose plan starts from `state`.
    fn new(steps: &'a CgSteps, grid: &CgGrid, state: &GaitState) -> Self {
        let t = state.body.translation;
        let yaw = state.body.rotation.euler_angles().2;
        let mut states = HashMap::new();
        if let Some(cell) = grid.cell_of(Point2::new(t.x, t.y), yaw) {
            let feet = state
                .legs
                .iter()
                .map(|l| {
                    l.stance
                        .then(|| grid.xy_of(Point2::new(l.foot.x, l.foot.y)))
                })
                .collect();
            let start = Stance::new(0, feet, millimetres(t.z));
            states.insert((cell, start), ((state.clone(), None), 0));
        }
        Executor {
            steps,
            grid: *grid,
            states: RefCell::new(states),
            outcomes: RefCell::new(HashMap::new()),
            generations: Cell::new(1),
            checked: Cell::new(0),
            refused: Cell::new(0),
        }
    }

    /// The plan's moves as steps, each the moves before an advance and the advance.
    fn steps_of(&self, found: &Plan) -> Result<Vec<Queued>, String> {
        let states = self.states.borrow();
        let route = &found.feet.route;
        let mut stance = found.feet.start.clone();
        let Some(((mut at, _), _)) = states.get(&(route[0], stance.clone())).cloned() else {
            return Err("the plan does not start where the robot stands".to_owned());
        };
        let mut steps = Vec::new();
        let mut pending: Option<Queued> = None;
        for fs in &found.feet.steps {
            apply_step(&mut stance, fs);
            let Some(((end, Some(move_plan)), _)) = states.get(&(route[stance.k], stance.clone()))
            else {
                return Err(format!("the plan's move {fs:?} was not checked"));
            };
            match &mut pending {
                Some(q) => {
                    append_step(&mut q.step, move_plan);
                    q.moves.push(*fs);
                }
                None => {
                    pending = Some(Queued {
                        start: at.clone(),
                        step: move_plan.clone(),
                        moves: vec![*fs],
                    });
                }
            }
            if matches!(fs, FootStep::Advance { .. })
                && let Some(q) = pending.take()
            {
                steps.push(q);
            }
            at = end.clone();
        }
        if let Some(q) = pending.take() {
            steps.push(q);
        }
        Ok(steps)
    }
}

/// Appends `next` (a move carried out from where `step` ends) to `step`: its actions, the
/// lower of the two margins, its end.
fn append_step(step: &mut StepPlan, next: &StepPlan) {
    step.actions.extend(next.actions.iter().cloned());
    step.min_margin_m = step.min_margin_m.min(next.min_margin_m);
    step.end = next.end.clone();
}

impl MoveCheck for Executor<'_> {
    fn check(
        &self,
        from: &Stance,
        from_cell: CgCell,
        step: &FootStep,
        to: &Stance,
        to_cell: CgCell,
    ) -> bool {
        let start = (from_cell, from.clone());
        let Some((state, generation)) = self
            .states
            .borrow()
            .get(&start)
            .map(|((state, _), generation)| (state.clone(), *generation))
        else {
            return false;
        };
        let end = (to_cell, to.clone());
        let key = (start, generation, end.clone());
        if let Some(known) = self.outcomes.borrow().get(&key) {
            return match known {
                Some(reached) => {
                    self.states.borrow_mut().insert(end, reached.clone());
                    true
                }
                None => false,
            };
        }
        self.checked.set(self.checked.get() + 1);
        if self.checked.get().is_multiple_of(200) {
            tracing::debug!(
                checked = self.checked.get(),
                refused = self.refused.get(),
                k = from.k,
                "checking moves"
            );
        }
        let planned = self.steps.carry_out(&state, &self.grid, step);
        match planned {
            Ok(p) => {
                let generation = self.generations.get();
                self.generations.set(generation + 1);
                let reached = ((p.end.clone(), Some(p)), generation);
                self.states.borrow_mut().insert(end, reached.clone());
                self.outcomes.borrow_mut().insert(key, Some(reached));
                true
            }
            Err(why) => {
                tracing::trace!(?step, %why, feet = ?state.legs.iter().map(|l| (l.stance, (l.foot.x * 100.0).round() / 100.0, (l.foot.y * 100.0).round() / 100.0, (l.foot.z * 100.0).round() / 100.0)).collect::<Vec<_>>(), body = ?state.body.translation.vector, "a move the robot cannot carry out");
                self.refused.set(self.refused.get() + 1);
                self.outcomes.borrow_mut().insert(key, None);
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_free_gait::stand;

    /// The Ambler standing at (5, 0) on flat ground 20 m by 16 m (x 0..20, y -8..8), and
    /// its step source.
    fn ambler_on_flat() -> (CgSteps, GaitState) {
        let model = Arc::new(RobotModel::builtin("ambler").expect("the Ambler"));
        let terrain = Arc::new(
            HeightField::flat(Point2::new(0.0, -8.0), Point2::new(20.0, 8.0), 0.1, 0.0)
                .expect("flat ground"),
        );
        let gait = GaitParams::for_model(&model);
        let state = stand(&model, &GridView::new(terrain.clone()), 5.0, 0.0, 0.0)
            .expect("the Ambler stands");
        let steps = CgSteps::new(
            model,
            terrain,
            walking_cg_params(),
            PlanParams::default(),
            gait,
        )
        .expect("a step source");
        (steps, state)
    }

    /// A plan from `state` to `goal` (the goal's own cell), with the executor that checked it.
    fn plan_to<'a>(
        steps: &'a CgSteps,
        state: &GaitState,
        goal: Point2<f64>,
    ) -> (CgGrid, Executor<'a>, Plan) {
        let mut space = steps.space.lock().expect("the space");
        let grid = *space.grid();
        let executor = Executor::new(steps, &grid, state);
        let plan = steps
            .plan_from(&mut space, state, (goal, 0.0), &executor, &mut LocalRoutes)
            .expect("a plan");
        (grid, executor, plan)
    }

    /// The place the executor starts from, as it keys it.
    fn start_of(grid: &CgGrid, state: &GaitState) -> (CgCell, Stance) {
        let t = state.body.translation;
        let cell = grid
            .cell_of(Point2::new(t.x, t.y), 0.0)
            .expect("on the map");
        let feet = state
            .legs
            .iter()
            .map(|l| Some(grid.xy_of(Point2::new(l.foot.x, l.foot.y))))
            .collect();
        (cell, Stance::new(0, feet, millimetres(t.z)))
    }

    /// The body's move from `from` to `cell` at its height, and the stance it leads to.
    fn advance_to(from: &Stance, cell: CgCell) -> (FootStep, Stance) {
        let step = FootStep::Advance {
            to: cell,
            body_z: from.body_z(),
        };
        let mut to = from.clone();
        apply_step(&mut to, &step);
        (step, to)
    }

    #[test]
    fn a_move_checked_again_is_answered_from_memory_with_the_same_state() {
        let (steps, state) = ambler_on_flat();
        let grid = *steps.space.lock().expect("the space").grid();
        let executor = Executor::new(&steps, &grid, &state);
        let (cell, from) = start_of(&grid, &state);
        // The body's move one cell ahead, at its height.
        let next = CgCell::new(cell.ix + 1, cell.iy, cell.it);
        let (advance, to) = advance_to(&from, next);
        assert!(executor.check(&from, cell, &advance, &to, next));
        assert_eq!(executor.checked.get(), 1);
        let first = executor.states.borrow()[&(next, to.clone())].clone();
        assert!(executor.check(&from, cell, &advance, &to, next));
        assert_eq!(executor.checked.get(), 1, "carried out a second time");
        let again = executor.states.borrow()[&(next, to.clone())].clone();
        assert_eq!(first.1, again.1, "the same state, the same generation");
        assert_eq!(first.0.0.body, again.0.0.body);
        // A foot sent 12 m away cannot get there; the refusal is remembered too.
        let far = (cell.ix + 40, cell.iy);
        let swing = FootStep::Place {
            leg: 0,
            from: from.feet[0],
            to: far,
        };
        let mut moved = from.clone();
        apply_step(&mut moved, &swing);
        assert!(!executor.check(&from, cell, &swing, &moved, cell));
        assert!(!executor.check(&from, cell, &swing, &moved, cell));
        assert_eq!(executor.checked.get(), 2);
        assert_eq!(executor.refused.get(), 1);
    }

    #[test]
    fn a_state_reached_again_by_another_way_is_checked_anew_from_there() {
        let (steps, state) = ambler_on_flat();
        let grid = *steps.space.lock().expect("the space").grid();
        let executor = Executor::new(&steps, &grid, &state);
        let (cell, from) = start_of(&grid, &state);
        let next = CgCell::new(cell.ix + 1, cell.iy, cell.it);
        let (advance, to) = advance_to(&from, next);
        assert!(executor.check(&from, cell, &advance, &to, next));
        let (back, home) = advance_to(&to, cell);
        let before = executor.checked.get();
        let outcome = executor.check(&to, next, &back, &home, cell);
        assert_eq!(executor.checked.get(), before + 1);
        // The same place reached again by another move: a new generation there, so the
        // move from it is carried out again rather than answered for the old state, and
        // then answered from memory for the new one.
        {
            let mut states = executor.states.borrow_mut();
            let entry = states.get_mut(&(next, to.clone())).expect("reached");
            entry.1 += 100;
        }
        assert_eq!(executor.check(&to, next, &back, &home, cell), outcome);
        assert_eq!(executor.checked.get(), before + 2);
        assert_eq!(executor.check(&to, next, &back, &home, cell), outcome);
        assert_eq!(executor.checked.get(), before + 2);
    }

    #[test]
    fn a_plan_near_the_maps_edge_swings_no_leg_over_unknown_ground() {
        // The goal 4 m inside the north edge: the Ambler's left legs, reaching 4 m and more
        // from its body, would swing over ground off the map, which the robot's own check
        // refuses (a planner that let them offered 142 such moves on the way).
        let (steps, state) = ambler_on_flat();
        let goal = Point2::new(9.0, 4.0);
        let (grid, executor, plan) = plan_to(&steps, &state, goal);
        let end = plan.feet.route.last().expect("a route");
        assert!((grid.centre(end.ix, end.iy) - goal).norm() < grid.cell_m);
        assert!(executor.checked.get() > 0);
        assert_eq!(
            executor.refused.get(),
            0,
            "the planner offered moves the robot refuses"
        );
    }

    #[test]
    fn a_step_taken_a_few_millimetres_off_its_start_is_carried_out_from_there() {
        let (steps, state) = ambler_on_flat();
        let (grid, executor, plan) = plan_to(&steps, &state, Point2::new(9.0, 0.0));
        let queued = executor.steps_of(&plan).expect("the plan's steps");
        // The second step, with the robot standing 3 mm further along x than planned (the
        // whole robot shifted: the same joints, every foot 3 mm along).
        let planned = &queued[1];
        let shift = nalgebra::Vector3::new(0.003, 0.0, 0.0);
        let mut real = planned.start.clone();
        real.body.translation.vector += shift;
        for leg in &mut real.legs {
            leg.foot += shift;
        }
        assert!(same_place(&planned.start, &real, grid.cell_m));
        let step = steps
            .replay(&real, &grid, &planned.moves)
            .expect("the step holds from there");
        let moved: Vec<usize> = planned
            .moves
            .iter()
            .filter_map(|m| match *m {
                FootStep::Place { leg, .. } | FootStep::Lift { leg, .. } => Some(leg),
                FootStep::Advance { .. } => None,
            })
            .collect();
        let kept: Vec<usize> = (0..real.legs.len())
            .filter(|l| real.legs[*l].stance && !moved.contains(l))
            .collect();
        assert!(!kept.is_empty(), "every leg moved in the step");
        for l in kept {
            let (got, was) = (step.end.legs[l].foot, planned.step.end.legs[l].foot);
            assert!(
                (got - real.legs[l].foot).norm() < 1e-9,
                "leg {l}'s foot stays where it really stands"
            );
            assert!((got - was).norm() > 0.002, "leg {l} still as planned");
        }
    }

    #[test]
    fn a_goal_off_its_cells_centre_is_reached_by_a_last_body_move() {
        // The goal 0.2 m from where the body stands, in a cell of 0.3 m: the plan has
        // nothing to do at the cell level, so the body moves onto the goal itself.
        let (steps, state) = ambler_on_flat();
        let t = state.body.translation.vector;
        let goal = Point2::new(t.x + 0.12, t.y + 0.16);
        let step = steps
            .final_approach(&state, goal, 0.05)
            .expect("a move onto the goal");
        let end = step.step.end.body.translation.vector;
        assert!((Point2::new(end.x, end.y) - goal).norm() < 1e-6);
        assert!((end.z - t.z).abs() < 1e-9);
        assert!(step.new_plan.is_none());
        // Near enough already: nothing to do.
        assert!(steps.final_approach(&state, goal, 0.3).is_none());
    }

    #[test]
    fn a_goal_whose_cell_is_invalid_is_planned_to_the_valid_cell_beside_it() {
        // Toward the map's east edge the body's underside soon reaches past it; the goal in
        // the first such cell (a walk's tolerance of 5 cm, less than a cell) is planned to
        // the valid cell before it, for the last move to finish.
        let (steps, state) = ambler_on_flat();
        let mut space = steps.space.lock().expect("the space");
        let grid = *space.grid();
        let row = grid
            .cell_of(Point2::new(5.0, 0.0), 0.0)
            .expect("on the map");
        let last_valid = (row.ix..grid.nx)
            .map(|ix| CgCell::new(ix, row.iy, 0))
            .take_while(|c| space.is_valid(*c))
            .last()
            .expect("valid cells east of the start");
        assert!(last_valid.ix < grid.nx - 1, "the whole row is valid");
        let past = grid.centre(last_valid.ix + 1, row.iy);
        let goal = Point2::new(past.x + 0.1, past.y);
        assert!(!space.is_valid(grid.cell_of(goal, 0.0).expect("on the map")));
        let executor = Executor::new(&steps, &grid, &state);
        let plan = steps
            .plan_from(
                &mut space,
                &state,
                (goal, 0.05),
                &executor,
                &mut LocalRoutes,
            )
            .expect("a plan to the cell beside the goal");
        assert_eq!(plan.feet.route.last(), Some(&last_valid));
    }

    #[test]
    fn a_goal_the_feet_cannot_follow_the_body_to_is_approached_by_a_free_gait_step() {
        // The goal 2.5 m ahead: no leg reaches that far with its foot where it stands, so
        // the last move is a step of the free gait toward the goal.
        let (steps, state) = ambler_on_flat();
        let t = state.body.translation.vector;
        let here = Point2::new(t.x, t.y);
        let goal = Point2::new(t.x + 2.5, t.y);
        let target =
            Isometry3::from_parts(Translation3::new(goal.x, goal.y, t.z), state.body.rotation);
        assert!(
            steps
                .gait
                .move_body_to(&state, &steps.view, &target)
                .is_err(),
            "the body alone cannot move 2.5 m"
        );
        let step = steps
            .final_approach(&state, goal, 0.05)
            .expect("a free-gait step toward the goal");
        assert!(step.new_plan.is_none());
        let end = step.step.end.body.translation.vector;
        let nearer = (Point2::new(end.x, end.y) - goal).norm();
        assert!(
            nearer < (here - goal).norm() - 0.05,
            "the step ends {nearer:.2} m from the goal"
        );
        assert!(step.step.actions.len() > 1, "a body move and a swing");
    }
}
