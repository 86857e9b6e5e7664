//! The Gait Planner on the bus: the `planStep` goal (§6.2.1, Figure 5).
//!
//! For one step it asks the Controller where the carriage and the foot are
//! (`bodyPosition`, `globalLegPosition`), the LTM Manager for the footfall and elevation
//! maps of the region (`mapRegion`; a fresh image when walking forward), and the Leg
//! Recovery Planner which cells the foot can reach (`legReachability`); chooses the footfall
//! and the body move; sends `recoverLeg` (goal) and `bodyMove` (command) as children, the
//! body move constrained to start only after the leg move is achieved; and informs
//! `stepPlanned`. A step that cannot be planned ends the goal with failure, its reason
//! saying why (the `walk` goal's handler decides what to do). The `walk` goal itself is the
//! integrator's.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::Point2;
use tca_lrp::TerrainMap;
use tca_messages::walking::{
    BodyMove, BodyPosition, GlobalLegPosition, LegReachability, MapKind, MapRegion, PlanStep,
    RecoverLeg, StepPlanned, WorldPoint,
};
use tca_module::{
    Connector, ConstraintSpec, Context, HandlerError, Module, ModuleError, SendOptions, TaskRef,
};
use tca_robot::LegParams;

use crate::params::GaitParams;
use crate::picture::cost_maps_picture;
use crate::planner::{GaitMaps, GaitPlanner, StepPlan};
use crate::region::Direction;

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
    /// Stamp messages with simulated time and charge the planning's wall-clock time to it.
    pub simulated_time: bool,
    /// How many goals central may hand the module at once (more than 1 lets the next step
    /// be planned while the Walk goal is still being handled, for concurrent walking).
    pub capacity: u32,
}

impl Default for GaitConfig {
    fn default() -> Self {
        Self {
            module_name: DEFAULT_MODULE_NAME.into(),
            leg: LegParams::default(),
            params: GaitParams::default(),
            picture_dir: None,
            simulated_time: false,
            capacity: 2,
        }
    }
}

#[derive(Debug, Clone)]
struct Shared {
    planner: Arc<GaitPlanner>,
    picture_dir: Option<PathBuf>,
}

/// Connects the Gait Planner to central under `config.module_name` and serves
/// [`PlanStep`] until the returned [`Module`] is dropped or closed. Bad parameters are a
/// [`ModuleError::Usage`] saying what to fix.
pub async fn connect(connector: &Connector, config: GaitConfig) -> Result<Module, ModuleError> {
    let planner = GaitPlanner::new(config.leg.clone(), config.params)
        .map_err(|e| ModuleError::Usage(format!("gait planner configuration: {e}")))?;
    let shared = Shared {
        planner: Arc::new(planner),
        picture_dir: config.picture_dir.clone(),
    };
    tracing::info!(module = %config.module_name, "gait planner starting");
    Module::builder(config.module_name.clone())
        .capacity(config.capacity)
        .simulated_time(config.simulated_time)
        .handle(move |ctx: Context, step: PlanStep| {
            let shared = shared.clone();
            async move { shared.plan_step(&ctx, step).await }
        })
        .connect(connector)
        .await
}

impl Shared {
    async fn plan_step(&self, ctx: &Context, step: PlanStep) -> Result<(), HandlerError> {
        let body = ctx.query(&BodyPosition).await?;
        let foot = ctx.query(&GlobalLegPosition).await?;
        tracing::debug!(
            step = step.step,
            body_y_m = body.y_m,
            foot_y_m = foot.y_m,
            "planning a step"
        );
        let planner = &self.planner;
        let region = planner.region(body.y_m, step.goal_y_m)?;
        let polygon = planner.map_polygon(&region);
        let resolution_m = planner.params().grid.resolution_m;
        let footfall = ctx
            .query(&MapRegion {
                kind: MapKind::Footfall,
                polygon: polygon.clone(),
                resolution_m,
                // The scanner looks forward only; walking backward uses the LTM's memory.
                refresh: region.direction == Direction::Forward,
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
                body_y_m: body.y_m,
            })
            .await?;
        let footfall = TerrainMap::from_map_grid(&footfall)?;
        let elevation = TerrainMap::from_map_grid(&elevation)?;
        let reachability = TerrainMap::from_map_grid(&reachability)?;
        let began = Instant::now();
        let planner = self.planner.clone();
        let (body_y, goal_y) = (body.y_m, step.goal_y_m);
        let plan: StepPlan = tokio::task::spawn_blocking(move || {
            let reachable =
                |p: Point2<f64>| reachability.value_at(p).known().is_some_and(|v| v >= 0.5);
            planner.plan(
                body_y,
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
            ctx.spend(began.elapsed());
        }
        let footfall = WorldPoint {
            x_m: plan.footfall.x,
            y_m: plan.footfall.y,
            z_m: plan.footfall.z,
        };
        let leg = ctx.goal(&RecoverLeg {
            footfall,
            body_y_m: body.y_m,
        })?;
        ctx.send_task(
            &BodyMove {
                target_y_m: plan.body_target_y_m,
            },
            SendOptions {
                constraints: vec![ConstraintSpec::sequential_achievement(
                    leg.task_ref(),
                    TaskRef::This,
                )],
                ..SendOptions::default()
            },
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
        Ok(())
    }
}
