//! The Gait Planner on the bus: the `planStep` goal (§6.2.1, Figure 5).
//!
//! For one step it asks the Controller where the carriage and the foot are
//! (`bodyPosition`, `globalLegPosition`), the LTM Manager for the footfall and elevation
//! maps of the region (`mapRegion`; a fresh image when walking forward), and the Leg
//! Recovery Planner which cells the foot can reach (`legReachability`); chooses the footfall
//! and the body move; sends `recoverLeg` (goal) and `bodyMove` (command) as children, the
//! body move constrained to start only after the leg move is achieved; and informs
//! `stepPlanned`; inside a walk it then sends the next step (see [`crate::walk`]). A step
//! that cannot be planned ends the goal with failure, its reason saying why (the walk fails
//! with it); a step at the goal does nothing and succeeds.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::Point2;
use tca_lrp::TerrainGrid;
use tca_module::{
    ComputeTime, Connector, ConstraintSpec, Context, HandlerError, Module, ModuleError, TaskRef,
};
use tca_robot::LegParams;
use tca_single_leg_messages::{
    BodyMove, BodyPosition, ElbowSide, GlobalLegPosition, LegReachability, MapKind, MapRegion,
    PlanStep, RecoverLeg, StepPlanned, WalkMode, WorldPoint,
};

use crate::error::GaitError;
use crate::params::GaitParams;
use crate::picture::cost_maps_picture;
use crate::planner::{AT_GOAL_M, GaitMaps, GaitPlanner, StepPlan};
use crate::region::WalkDirection;

/// The module's default name.
pub const DEFAULT_MODULE_NAME: &str = "gait";

/// How the Gait Planner module runs.
#[derive(Debug, Clone, PartialEq)]
pub struct GaitConfig {
    /// The module's name (default `gait`).
    pub module_name: String,
    /// The leg's parameters.
    pub leg: LegParams,
    /// The planner's parameters (`params/gait.toml`).
    pub params: GaitParams,
    /// Write a picture of every step's cost maps here (`step-<n>.png`).
    pub picture_dir: Option<PathBuf>,
    /// Stamp messages with simulated time and charge each step's planning to it.
    pub simulated_time: bool,
    /// What a step's planning charges to simulated time: the measured computing time, or a
    /// modeled one (the 1990 Gait Planner took about 2 s a step, §7.2).
    pub compute_time: ComputeTime,
    /// How many goals central may hand the module at once (more than 1 lets the next step
    /// be planned while the Walk goal is still being handled, for concurrent walking).
    pub capacity: u32,
    /// How many times in a row a failed leg or body move is re-planned before the walk gives
    /// up.
    pub max_replans: u32,
}

impl Default for GaitConfig {
    fn default() -> Self {
        Self {
            module_name: DEFAULT_MODULE_NAME.into(),
            leg: LegParams::default(),
            params: GaitParams::default(),
            picture_dir: None,
            simulated_time: false,
            compute_time: ComputeTime::Measured,
            capacity: 4,
            max_replans: 5,
        }
    }
}

#[derive(Debug, Clone)]
struct Shared {
    planner: Arc<GaitPlanner>,
    picture_dir: Option<PathBuf>,
    compute_time: ComputeTime,
    walks: crate::walk::Walks,
}

/// Connects the Gait Planner to central under `config.module_name` and serves
/// [`PlanStep`] until the returned [`Module`] is dropped or closed. Bad parameters are a
/// [`ModuleError::Config`] saying what to fix.
pub async fn connect(connector: &Connector, config: GaitConfig) -> Result<Module, ModuleError> {
    let planner = GaitPlanner::new(config.leg.clone(), config.params)
        .map_err(|e| ModuleError::Config(format!("gait planner configuration: {e}")))?;
    let walks = crate::walk::Walks::default();
    let shared = Shared {
        planner: Arc::new(planner),
        picture_dir: config.picture_dir.clone(),
        compute_time: config.compute_time,
        walks: walks.clone(),
    };
    tracing::info!(module = %config.module_name, "gait planner starting");
    let builder = Module::builder(config.module_name.clone())
        .capacity(config.capacity)
        .simulated_time(config.simulated_time)
        // A module that dies while answering one of our queries is restarted; ask again.
        .requery_after_crash(tca_module::REQUERIES_AFTER_CRASH)
        .handle(move |ctx: Context, step: PlanStep| {
            let shared = shared.clone();
            async move { shared.plan_step(&ctx, step).await }
        });
    crate::walk::register(builder, walks, config.max_replans, config.leg.rails)
        .connect(connector)
        .await
}

impl Shared {
    async fn plan_step(&self, ctx: &Context, step: PlanStep) -> Result<(), HandlerError> {
        if let (Some(walk), Some(me)) = (ctx.origin(), ctx.node()) {
            if self.walks.is_stale(walk, step.step) {
                tracing::debug!(step = step.step, "step abandoned by a replan: not planned");
                return Ok(());
            }
            self.walks.step_started(walk, me);
        }
        // Planned ahead (concurrent walking): start where the previous step will leave the
        // carriage and the foot; otherwise ask the Controller where they are.
        let (body_y_m, foot) = match step.start {
            Some(start) => (start.body_y_m, start.foot),
            None => (
                ctx.query(&BodyPosition).await?.y_m,
                ctx.query(&GlobalLegPosition).await?,
            ),
        };
        tracing::debug!(
            step = step.step,
            body_y_m,
            foot_y_m = foot.y_m,
            "planning a step"
        );
        let planner = &self.planner;
        let region = match planner.region(body_y_m, step.goal_y_m) {
            Ok(r) => r,
            Err(GaitError::AtGoal { .. }) => {
                tracing::info!(step = step.step, body_y_m, "at the goal: no step needed");
                return Ok(());
            }
            Err(e) => return Err(e.into()),
        };
        if let (Some(walk), None) = (ctx.origin(), step.start) {
            self.walks
                .step_starts_at(walk, body_y_m)
                .map_err(HandlerError::new)?;
        }
        let polygon = planner.map_polygon(&region);
        let resolution_m = planner.params().grid.resolution_m;
        let footfall = ctx
            .query(&MapRegion {
                kind: MapKind::Footfall,
                polygon: polygon.clone(),
                resolution_m,
                // The scanner looks forward only; walking backward uses the LTM's memory.
                refresh: region.direction == WalkDirection::Forward,
            })
            .await?;
        let elevation = ctx
            .query(&MapRegion {
                kind: MapKind::Elevation,
                polygon,
                resolution_m,
                refresh: false,
            })
            .await?;
        let reachability = ctx
            .query(&LegReachability {
                polygon: region.polygon(0.0),
                resolution_m,
                body_y_m,
                start_foot: step.start.map(|s| s.foot),
            })
            .await?;
        let footfall = TerrainGrid::from_map_grid(&footfall)?;
        let elevation = TerrainGrid::from_map_grid(&elevation)?;
        let reachability = TerrainGrid::from_map_grid(&reachability)?;
        let began = Instant::now();
        let planner = self.planner.clone();
        let goal_y = step.goal_y_m;
        let plan: StepPlan = tokio::task::spawn_blocking(move || {
            let reachable =
                |p: Point2<f64>| reachability.value_at(p).known().is_some_and(|v| v >= 0.5);
            planner.plan(
                body_y_m,
                goal_y,
                &GaitMaps {
                    footfall: &footfall,
                    elevation: &elevation,
                    reachable: &reachable,
                },
            )
        })
        .await
        .map_err(|e| HandlerError::new(format!("the planning task ended abnormally: {e}")))??;
        if ctx.simulated_time() {
            ctx.spend(self.compute_time.charged(began.elapsed()));
        }
        if let Some(walk) = ctx.origin()
            && self.walks.is_stale(walk, step.step)
        {
            tracing::debug!(
                step = step.step,
                "step abandoned by a replan while planning"
            );
            return Ok(());
        }
        let footfall = WorldPoint {
            x_m: plan.footfall.x,
            y_m: plan.footfall.y,
            z_m: plan.footfall.z,
        };
        // The leg move. Planned ahead (concurrent walking, §3.3), the Leg Recovery Planner
        // plans it now, from where the previous step will leave the foot, and only the move
        // itself waits for the previous body move (sequential achievement: the goal may be
        // planned meanwhile, its leg move may not start).
        let leg_constraints = step.after_body_move.map(|previous| {
            ConstraintSpec::sequential_achievement(TaskRef::Message(previous), TaskRef::This)
        });
        let start_foot = step.start.map(|s| s.foot);
        let elbow = Some(match plan.elbow {
            tca_robot::ElbowBranch::Positive => ElbowSide::Positive,
            tca_robot::ElbowBranch::Negative => ElbowSide::Negative,
        });
        let leg = ctx.send_task(
            &RecoverLeg {
                footfall,
                body_y_m,
                elbow,
                start_foot,
            },
            leg_constraints,
        )?;
        let body = ctx.send_task(
            &BodyMove {
                target_y_m: plan.body_target_y_m,
            },
            [ConstraintSpec::sequential_achievement(
                leg.task_ref(),
                TaskRef::This,
            )],
        )?;
        if let Err(e) = ctx.inform(&StepPlanned {
            step: step.step,
            footfall,
            body_target_y_m: plan.body_target_y_m,
            cost: plan.cost,
        }) {
            tracing::warn!(%e, "stepPlanned not sent");
        }
        if let Some(dir) = &self.picture_dir {
            let path = dir.join(format!("step-{}.png", step.step));
            if let Err(e) = cost_maps_picture(&plan).write_png(&path) {
                tracing::warn!(%e, "cost map picture not written");
            }
        }
        tracing::debug!(
            step = step.step,
            x_m = plan.footfall.x,
            y_m = plan.footfall.y,
            body_target_y_m = plan.body_target_y_m,
            "step planned"
        );
        // Inside a walk (the step was sent in the context of the walk node), send the next
        // step as this one's sibling, unless this one reaches the goal (Figure 5). Walking
        // sequentially, the step after the one planned to reach the goal is sent all the
        // same: it asks the Controller where the carriage is and steps again if the body
        // move fell short (or ends the walk, at the goal).
        let reaches_goal = (plan.body_target_y_m - step.goal_y_m).abs() <= AT_GOAL_M
            && step.mode == WalkMode::Concurrent;
        if let (Some(walk), false) = (ctx.origin(), reaches_goal) {
            let walk_ctx = ctx.in_context(Some(walk));
            let next = crate::walk::next_step(&step, plan.body_target_y_m, footfall, body.id());
            self.walks.step_sent(walk, next.step);
            walk_ctx.send_task(&next, crate::walk::next_step_constraints(&step, &body))?;
        }
        Ok(())
    }
}
