//! The walking module on the bus (`gait` by default): the `legged.walk` goal and its steps.
//!
//! The walk handler takes the Controller's exceptions at the walk node and sends the first
//! `legged.gaitStep`. Each step asks the Controller where the body and every leg are (or,
//! planned ahead, starts where the step before will leave them), asks the LTM Manager for the
//! elevation and footfall maps around the body (a fresh image first), plans with the free
//! gait, and sends its moves as `legged.legMove` and `legged.bodyMove` commands, each to be
//! achieved before the next starts; then it sends the next step. Sequentially, the next step
//! is planned once this step's last move is achieved; concurrently, while this step executes,
//! from where it will leave the robot (not before the step before it has ended: what the
//! scanner sees from where the body stands).
//!
//! A failed move (`legged.moveFailed`) ends the steps in progress and plans again from where
//! the robot is, up to a limit; a tip-over or a hardware fault halts the walk with the reason.
//! A step at the goal sends nothing, and the walk is achieved when its last move is.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Point2;
use tca_free_gait::{
    Action, FreeGait, GaitError, GaitParams, GaitState, GridView, LegGaitState, StepPlan,
};
use tca_legged_messages::{
    BodyMove, BodyPose, HardwareFault, LegMove, LegState, LeggedWalk, MoveFailed, TipOver,
    WorldPoint,
};
use tca_legged_model::RobotModel;
use tca_legged_sim::{isometry_to_pose, pose_to_isometry};
use tca_module::{
    ComputeTime, Connector, ConstraintSpec, Context, HandlerError, Module, ModuleError, TaskRef,
};
use tca_robot::HeightField;
use tca_single_leg_messages::{MapKind, MapRegion, PlanePoint};

use crate::cg_steps::CgSteps;
use crate::map_view::{MapView, StepView};
use crate::messages::{GaitStep, PlannedLeg, PlannedStart, RoutePlanned, StepPlanned};
use crate::rrt_steps::RrtSteps;
use crate::walks::{WalkState, Walks};

/// The module's default name.
pub const DEFAULT_MODULE_NAME: &str = "gait";

/// How the walking module runs.
#[derive(Debug, Clone)]
pub struct GaitModuleConfig {
    /// The module's name.
    pub module_name: String,
    /// The robot.
    pub model: Arc<RobotModel>,
    /// The free gait's parameters.
    pub params: GaitParams,
    /// Half the side of the square map asked for around the body, metres.
    pub map_half_side_m: f64,
    /// The map's cell size, metres.
    pub map_cell_m: f64,
    /// Failed moves re-planned in one walk before it gives up.
    pub max_replans: u32,
    /// Stamp messages with simulated time and charge the planning to it.
    pub simulated_time: bool,
    /// Plan on this true terrain instead of the LTM Manager's maps (to tell a planner's
    /// failings from perception's); `None`: the maps.
    pub ground_truth: Option<Arc<HeightField>>,
    /// What plans the steps.
    pub planner: StepPlanner,
}

/// What plans the walking module's steps.
#[derive(Debug, Clone, Default)]
pub enum StepPlanner {
    /// The free gait, one step at a time on the map around the body.
    #[default]
    FreeGait,
    /// The integrated RRT-Connect planner (`tca-rrt`): the whole walk at once on the given
    /// terrain, planned again from where the robot stands after a failed move.
    Rrt {
        /// The terrain it plans on.
        terrain: Arc<HeightField>,
        /// Its parameters.
        params: tca_rrt::RrtParams,
    },
    /// CG-space planning (`tca-cg-space`): the route and the footfalls of the whole walk on
    /// the given terrain, each move carried out by one of the free gait's checked moves,
    /// planned again from where the robot stands when a move cannot be.
    CgSpace {
        /// The terrain it plans on.
        terrain: Arc<HeightField>,
        /// How its CG-space is laid out.
        cg: tca_cg_space::CgParams,
        /// How it plans.
        params: tca_cg_space::PlanParams,
        /// Worker modules that run the route's roadmap joins (`None`: the walking module
        /// runs them itself).
        workers: Option<crate::cg_workers::CgWorkers>,
    },
}

/// Allowance for a perceived map's height error, metres: twice it (1 cm) is about the 95th
/// percentile of the LTM Manager's error with the Perceptron (0.6 to 1.1 cm over the cells
/// it knows).
pub const MAP_HEIGHT_ERROR_M: f64 = 0.005;

impl GaitModuleConfig {
    /// The free gait's clearance of the ground widened to at least three times
    /// [`MAP_HEIGHT_ERROR_M`] and the depth a swing reaches below its foothold to at least
    /// twice it, so that a small robot planning on a perceived map neither brushes the
    /// ground nor stops short of it. The clearance takes the larger allowance because the
    /// error is largest where a swing passes: a pebble's peak narrower than two cells is
    /// seen lower than it stands.
    pub fn with_map_allowance(mut self) -> Self {
        let p = &mut self.params;
        p.clearance_m = p.clearance_m.max(3.0 * MAP_HEIGHT_ERROR_M);
        p.below_foothold_m = p.below_foothold_m.max(2.0 * MAP_HEIGHT_ERROR_M);
        self
    }

    /// The defaults for a robot: the free gait's own for its size.
    pub fn new(model: Arc<RobotModel>, map_half_side_m: f64, map_cell_m: f64) -> Self {
        let params = GaitParams::for_model(&model);
        GaitModuleConfig {
            module_name: DEFAULT_MODULE_NAME.into(),
            model,
            params,
            map_half_side_m,
            map_cell_m,
            max_replans: 8,
            simulated_time: true,
            ground_truth: None,
            planner: StepPlanner::FreeGait,
        }
    }
}

#[derive(Clone)]
struct Shared {
    gait: Arc<FreeGait>,
    rrt: Option<Arc<RrtSteps>>,
    cg: Option<Arc<CgSteps>>,
    model: Arc<RobotModel>,
    config: Arc<GaitModuleConfig>,
    walks: Walks,
}

/// Connects the walking module and serves `legged.walk` until the module is closed.
pub async fn connect(
    connector: &Connector,
    config: GaitModuleConfig,
) -> Result<Module, ModuleError> {
    if !(config.map_half_side_m > 0.0 && config.map_cell_m > 0.0) {
        return Err(ModuleError::Config(format!(
            "the walking module's map must have a positive size and cell (got {} m and {} m)",
            config.map_half_side_m, config.map_cell_m
        )));
    }
    let gait = FreeGait::new(config.model.clone(), config.params.clone());
    let rrt = match &config.planner {
        StepPlanner::FreeGait | StepPlanner::CgSpace { .. } => None,
        StepPlanner::Rrt { terrain, params } => Some(Arc::new(
            RrtSteps::new(
                config.model.clone(),
                terrain.clone(),
                params.clone(),
                config.params.below_foothold_m,
            )
            .map_err(|e| ModuleError::Config(format!("the RRT-Connect planner: {e}")))?,
        )),
    };
    let cg = match &config.planner {
        StepPlanner::CgSpace {
            terrain,
            cg,
            params,
            workers,
        } => {
            let mut steps = CgSteps::new(
                config.model.clone(),
                terrain.clone(),
                cg.clone(),
                params.clone(),
                config.params.clone(),
            )
            .map_err(|e| ModuleError::Config(format!("the CG-space planner: {e}")))?;
            if let Some(workers) = workers {
                let joiner = crate::cg_workers::start(
                    connector,
                    &config.module_name,
                    workers,
                    &steps.space_template(),
                    steps.cg_params(),
                )
                .await?;
                steps = steps.with_joiner(joiner);
            }
            Some(Arc::new(steps))
        }
        _ => None,
    };
    let shared = Shared {
        gait: Arc::new(gait),
        rrt,
        cg,
        model: config.model.clone(),
        walks: Walks::default(),
        config: Arc::new(config.clone()),
    };
    let (s1, s2, s3) = (shared.clone(), shared.clone(), shared);
    let max_replans = config.max_replans;
    Module::builder(config.module_name.clone())
        .capacity(4)
        .simulated_time(config.simulated_time)
        .requery_after_crash(tca_module::REQUERIES_AFTER_CRASH)
        .handle(move |ctx: Context, walk: LeggedWalk| {
            let s = s1.clone();
            async move { s.start_walk(&ctx, walk).await }
        })
        .handle(move |ctx: Context, step: GaitStep| {
            let s = s2.clone();
            async move { s.step(&ctx, step).await }
        })
        .handle(move |ctx: Context, failure: MoveFailed| {
            let s = s3.clone();
            async move { s.replan(&ctx, failure, max_replans).await }
        })
        .handle(|_ctx: Context, t: TipOver| async move {
            Err::<(), _>(HandlerError::new(format!(
                "the robot tipped over ({}; margin {:.3} m, standing on {}); the walk was halted",
                t.detail,
                t.margin_m,
                t.standing.join(", ")
            )))
        })
        .handle(|_ctx: Context, f: HardwareFault| async move {
            Err::<(), _>(HandlerError::new(format!(
                "hardware fault{}: {}; the walk was halted",
                f.leg.map(|l| format!(" on {l}")).unwrap_or_default(),
                f.detail
            )))
        })
        .connect(connector)
        .await
}

/// Refuses a walk goal that is not a point or whose tolerance is not a positive distance.
pub fn check_walk(walk: &LeggedWalk) -> Result<(), String> {
    if !(walk.goal_x_m.is_finite() && walk.goal_y_m.is_finite()) {
        return Err(format!(
            "the walk's goal ({}, {}) is not a point; give world X and Y in metres",
            walk.goal_x_m, walk.goal_y_m
        ));
    }
    if !(walk.tolerance_m > 0.0 && walk.tolerance_m.is_finite()) {
        return Err(format!(
            "the walk's tolerance {} m must be a positive distance",
            walk.tolerance_m
        ));
    }
    Ok(())
}

fn to_world(p: &nalgebra::Point3<f64>) -> WorldPoint {
    WorldPoint {
        x_m: p.x,
        y_m: p.y,
        z_m: p.z,
    }
}

fn to_planned(state: &GaitState) -> PlannedStart {
    PlannedStart {
        body: isometry_to_pose(&state.body),
        legs: state
            .legs
            .iter()
            .map(|l| PlannedLeg {
                joints: l.joints.clone(),
                stance: l.stance,
                foot: to_world(&l.foot),
            })
            .collect(),
    }
}

fn from_planned(start: &PlannedStart) -> GaitState {
    GaitState {
        body: pose_to_isometry(&start.body),
        legs: start
            .legs
            .iter()
            .map(|l| LegGaitState {
                joints: l.joints.clone(),
                stance: l.stance,
                foot: nalgebra::Point3::new(l.foot.x_m, l.foot.y_m, l.foot.z_m),
            })
            .collect(),
    }
}

impl Shared {
    async fn start_walk(&self, ctx: &Context, walk: LeggedWalk) -> Result<(), HandlerError> {
        check_walk(&walk).map_err(HandlerError::new)?;
        let node = ctx
            .node()
            .ok_or_else(|| HandlerError::new("a walk must be sent as a goal"))?;
        ctx.on_exception::<MoveFailed>(node).await?;
        ctx.on_exception::<TipOver>(node).await?;
        ctx.on_exception::<HardwareFault>(node).await?;
        self.walks.insert(
            node,
            WalkState::new(
                [walk.goal_x_m, walk.goal_y_m],
                walk.tolerance_m,
                walk.concurrent,
            ),
        );
        tracing::info!(
            x = walk.goal_x_m,
            y = walk.goal_y_m,
            concurrent = walk.concurrent,
            "legged walk started"
        );
        ctx.goal(&GaitStep {
            step: 1,
            goal_x_m: walk.goal_x_m,
            goal_y_m: walk.goal_y_m,
            tolerance_m: walk.tolerance_m,
            concurrent: walk.concurrent,
            start: None,
            after: None,
        })?;
        Ok(())
    }

    /// Where the robot is now, from the Controller.
    async fn robot_state(&self, ctx: &Context) -> Result<GaitState, HandlerError> {
        let body = ctx.query(&BodyPose).await?;
        let mut legs = Vec::with_capacity(self.model.legs().len());
        for leg in self.model.legs() {
            let s = ctx
                .query(&LegState {
                    leg: leg.name().to_string(),
                })
                .await?;
            legs.push(LegGaitState {
                joints: s.joints,
                stance: s.stance,
                foot: nalgebra::Point3::new(s.foot.x_m, s.foot.y_m, s.foot.z_m),
            });
        }
        Ok(GaitState {
            body: pose_to_isometry(&body),
            legs,
        })
    }

    async fn maps(&self, ctx: &Context, centre: Point2<f64>) -> Result<StepView, HandlerError> {
        if let Some(truth) = &self.config.ground_truth {
            return Ok(StepView::Truth(GridView::new(truth.clone())));
        }
        let h = self.config.map_half_side_m;
        let polygon = [(-h, -h), (h, -h), (h, h), (-h, h)]
            .iter()
            .map(|(dx, dy)| PlanePoint {
                x_m: centre.x + dx,
                y_m: centre.y + dy,
            })
            .collect::<Vec<_>>();
        let resolution_m = self.config.map_cell_m;
        let elevation = ctx
            .query(&MapRegion {
                kind: MapKind::Elevation,
                polygon: polygon.clone(),
                resolution_m,
                refresh: true,
            })
            .await?;
        let footfall = ctx
            .query(&MapRegion {
                kind: MapKind::Footfall,
                polygon: polygon.clone(),
                resolution_m,
                refresh: false,
            })
            .await?;
        let slope = ctx
            .query(&MapRegion {
                kind: MapKind::Slope,
                polygon,
                resolution_m,
                refresh: false,
            })
            .await?;
        MapView::new(&elevation, &footfall, &slope)
            .map(StepView::Map)
            .map_err(HandlerError::new)
    }

    async fn step(&self, ctx: &Context, step: GaitStep) -> Result<(), HandlerError> {
        let walk = ctx.origin();
        if let (Some(walk), Some(me)) = (walk, ctx.node()) {
            if self.walks.is_stale(walk, step.step) {
                tracing::debug!(step = step.step, "step abandoned by a replan");
                return Ok(());
            }
            self.walks.step_started(walk, me);
        }
        let goal = Point2::new(step.goal_x_m, step.goal_y_m);
        let state = match &step.start {
            Some(start) => from_planned(start),
            None => self.robot_state(ctx).await?,
        };
        if self.gait.reached(&state, goal, step.tolerance_m) {
            tracing::info!(step = step.step, "at the goal: no step needed");
            return Ok(());
        }
        let planned = match (&self.rrt, &self.cg) {
            (Some(rrt), _) => self.plan_rrt(ctx, rrt, &step, &state, goal).await?,
            (None, Some(cg)) => self.plan_cg(ctx, cg, &step, &state, goal).await?,
            (None, None) => self.plan_free(ctx, walk, &step, &state, goal).await?,
        };
        let Some((plan, elapsed)) = planned else {
            return Ok(());
        };
        if let Some(walk) = walk
            && self.walks.is_stale(walk, step.step)
        {
            return Ok(());
        }
        let mut previous = step.after.map(TaskRef::Message);
        let mut last = None;
        let mut footholds = Vec::new();
        for action in &plan.actions {
            let constraints =
                previous.map(|p| ConstraintSpec::sequential_achievement(p, TaskRef::This));
            let task = match action {
                Action::Swing {
                    leg,
                    waypoints,
                    foothold,
                } => {
                    let name = self
                        .model
                        .legs()
                        .get(*leg)
                        .map(|l| l.name().to_string())
                        .ok_or_else(|| {
                            HandlerError::new(format!(
                                "the plan names leg {leg}, which the robot does not have"
                            ))
                        })?;
                    footholds.push((name.clone(), to_world(foothold)));
                    ctx.send_task(
                        &LegMove {
                            leg: name,
                            waypoints: waypoints.clone(),
                            transition: true,
                        },
                        constraints,
                    )?
                }
                Action::Reach { leg, waypoints } => {
                    let name = self
                        .model
                        .legs()
                        .get(*leg)
                        .map(|l| l.name().to_string())
                        .ok_or_else(|| {
                            HandlerError::new(format!(
                                "the plan names leg {leg}, which the robot does not have"
                            ))
                        })?;
                    ctx.send_task(
                        &LegMove {
                            leg: name,
                            waypoints: waypoints.clone(),
                            transition: false,
                        },
                        constraints,
                    )?
                }
                Action::Body { target } => ctx.send_task(
                    &BodyMove {
                        target: isometry_to_pose(target),
                    },
                    constraints,
                )?,
            };
            previous = Some(task.task_ref());
            last = Some(task);
        }
        if let Err(e) = ctx.inform(&StepPlanned {
            step: step.step,
            footholds,
            body_target: isometry_to_pose(&plan.end.body),
            min_margin_m: plan.min_margin_m,
            planning_ms: elapsed.as_secs_f64() * 1e3,
        }) {
            tracing::warn!(%e, "stepPlanned not sent");
        }
        let Some(walk) = walk else {
            return Ok(());
        };
        let walk_ctx = ctx.in_context(Some(walk));
        let next_number = step.step + 1;
        self.walks.step_sent(walk, next_number);
        let (start, after, constraint) = match (&last, step.concurrent) {
            (Some(last), true) => (
                Some(to_planned(&plan.end)),
                Some(last.id()),
                step.after
                    .map(|p| ConstraintSpec::delay_planning(TaskRef::Message(p), TaskRef::This)),
            ),
            (Some(last), false) => (
                None,
                None,
                Some(ConstraintSpec::delay_planning(
                    last.task_ref(),
                    TaskRef::This,
                )),
            ),
            // Nothing to move: look again from where the robot is.
            (None, _) => (None, step.after, None),
        };
        walk_ctx.send_task(
            &GaitStep {
                step: next_number,
                start,
                after,
                ..step
            },
            constraint,
        )?;
        Ok(())
    }

    /// The free gait's step from `state` on the map around the body; `None` at the goal.
    async fn plan_free(
        &self,
        ctx: &Context,
        walk: Option<tca_messages::NodeId>,
        step: &GaitStep,
        state: &GaitState,
        goal: Point2<f64>,
    ) -> Result<Option<(StepPlan, std::time::Duration)>, HandlerError> {
        let at = Point2::new(state.body.translation.x, state.body.translation.y);
        if let (Some(walk), None) = (walk, &step.start) {
            self.walks
                .step_starts_at(walk, (at - goal).norm())
                .map_err(HandlerError::new)?;
        }
        // The map is of the region around where the step starts; the scanner images from
        // where the body stands now.
        let view = self.maps(ctx, at).await?;
        let began = Instant::now();
        let gait = self.gait.clone();
        let planning_state = state.clone();
        let (plan, view) = tokio::task::spawn_blocking(move || {
            let plan = gait.plan_step(&planning_state, &view, goal);
            (plan, view)
        })
        .await
        .map_err(|e| HandlerError::new(format!("the planning task ended abnormally: {e}")))?;
        let elapsed = began.elapsed();
        if ctx.simulated_time() {
            ctx.spend(ComputeTime::Measured.charged(elapsed));
        }
        match plan {
            Ok(p) => Ok(Some((p, elapsed))),
            Err(GaitError::GoalReached { .. }) => {
                tracing::info!(step = step.step, "the free gait finds the body at the goal");
                Ok(None)
            }
            Err(e) => {
                let known = view.known_share(at, self.config.map_half_side_m * 0.5);
                Err(HandlerError::new(format!(
                    "step {} from ({:.2}, {:.2}) cannot be planned: {e} ({:.0}% of the map near the body is known)",
                    step.step,
                    at.x,
                    at.y,
                    known * 100.0
                )))
            }
        }
    }

    /// The RRT-Connect plan's next step from `state` (planning the walk when the robot is
    /// not where the plan expects it); `None` when the plan has no step left.
    async fn plan_rrt(
        &self,
        ctx: &Context,
        rrt: &Arc<RrtSteps>,
        step: &GaitStep,
        state: &GaitState,
        goal: Point2<f64>,
    ) -> Result<Option<(StepPlan, std::time::Duration)>, HandlerError> {
        let began = Instant::now();
        let (rrt, planning_state) = (rrt.clone(), state.clone());
        let next = tokio::task::spawn_blocking(move || rrt.next_step(&planning_state, goal))
            .await
            .map_err(|e| HandlerError::new(format!("the planning task ended abnormally: {e}")))?;
        let elapsed = began.elapsed();
        if ctx.simulated_time() {
            ctx.spend(ComputeTime::Measured.charged(elapsed));
        }
        let at = state.body.translation;
        let next = next.map_err(|e| {
            HandlerError::new(format!(
                "step {} from ({:.2}, {:.2}) cannot be planned: {e}",
                step.step, at.x, at.y
            ))
        })?;
        let Some(next) = next else {
            tracing::info!(step = step.step, "the RRT-Connect plan has no step left");
            return Ok(None);
        };
        if let Some(plan) = &next.new_plan {
            let route = RoutePlanned::of(step.step, plan, elapsed);
            tracing::info!(
                step = step.step,
                postures = plan.postures.len(),
                nodes = plan.stats.nodes,
                ms = route.planning_ms,
                "RRT-Connect planned the walk"
            );
            if let Err(e) = ctx.inform(&route) {
                tracing::warn!(%e, "routePlanned not sent");
            }
        }
        Ok(Some((next.step, elapsed)))
    }

    /// The CG-space plan's next step from `state` (planning the walk when the robot is not
    /// where the plan expects it); `None` when the plan has no step left.
    async fn plan_cg(
        &self,
        ctx: &Context,
        cg: &Arc<CgSteps>,
        step: &GaitStep,
        state: &GaitState,
        goal: Point2<f64>,
    ) -> Result<Option<(StepPlan, std::time::Duration)>, HandlerError> {
        let began = Instant::now();
        let (cg, planning_state) = (cg.clone(), state.clone());
        // Joins on workers are asked as this handler's own queries (see
        // `DistributedJoiner::ask_as`).
        let asker = ctx.module().clone();
        let tolerance_m = step.tolerance_m;
        let next = tokio::task::spawn_blocking(move || {
            cg.next_step(&planning_state, goal, tolerance_m, asker)
        })
        .await
        .map_err(|e| HandlerError::new(format!("the planning task ended abnormally: {e}")))?;
        let elapsed = began.elapsed();
        if ctx.simulated_time() {
            ctx.spend(ComputeTime::Measured.charged(elapsed));
        }
        let at = state.body.translation;
        let next = next.map_err(|e| {
            HandlerError::new(format!(
                "step {} from ({:.2}, {:.2}) cannot be planned: {e}",
                step.step, at.x, at.y
            ))
        })?;
        let Some(next) = next else {
            tracing::info!(step = step.step, "the CG-space plan has no step left");
            return Ok(None);
        };
        if let Some(plan) = &next.new_plan {
            let route = RoutePlanned::of_cg_space(step.step, plan, elapsed);
            tracing::info!(
                step = step.step,
                cells = plan.route.len(),
                nodes = plan.nodes,
                ms = route.planning_ms,
                "CG-space planned the walk"
            );
            if let Err(e) = ctx.inform(&route) {
                tracing::warn!(%e, "routePlanned not sent");
            }
        }
        Ok(Some((next.step, elapsed)))
    }

    async fn replan(
        &self,
        ctx: &Context,
        failure: MoveFailed,
        max_replans: u32,
    ) -> Result<(), HandlerError> {
        let walk = ctx
            .node()
            .ok_or_else(|| HandlerError::new("legged.moveFailed delivered outside a walk"))?;
        let (state, old_steps) = {
            let mut all = self.walks.lock();
            let Some(state) = all.get_mut(&walk) else {
                return Err(HandlerError::new(format!(
                    "a move failed in a walk this module does not know: {}",
                    failure.detail
                )));
            };
            state.replans += 1;
            state.steps_sent += 1;
            state.first_live_step = state.steps_sent;
            (state.clone(), std::mem::take(&mut state.live_steps))
        };
        tracing::info!(command = %failure.command, kind = ?failure.kind, detail = %failure.detail, replans = state.replans, "a move failed; planning again from where the robot is");
        if state.replans > max_replans {
            return Err(HandlerError::new(format!(
                "{} moves failed in this walk (limit {max_replans}); the last: {}{} {:?}: {}",
                state.replans,
                failure.command,
                failure.leg.map(|l| format!(" of {l}")).unwrap_or_default(),
                failure.kind,
                failure.detail
            )));
        }
        ctx.goal(&GaitStep {
            step: state.steps_sent,
            goal_x_m: state.goal[0],
            goal_y_m: state.goal[1],
            tolerance_m: state.tolerance_m,
            concurrent: state.concurrent,
            start: None,
            after: None,
        })?;
        for step in old_steps.into_iter().rev() {
            if let Err(e) = ctx.kill(step).await {
                tracing::debug!(%step, %e, "step already finished");
            }
        }
        Ok(())
    }
}
