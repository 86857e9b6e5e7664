//! The Leg Recovery Planner on the bus: `recoverLeg` (goal) and `legReachability` (query)
//! over a shared [`LegRecoveryPlanner`].
//!
//! Both ask the LTM Manager (`mapRegion`) for the elevation map of the leg's whole reach
//! around the carriage and the Controller (`jointLegPosition`, `bodyPosition`) for where the
//! leg is; `recoverLeg` then sends the planned `legMove` as a child command. A planning
//! failure ends the goal with failure and raises `moveFailed` (kind `Refused`, command
//! `recoverLeg`) in its context, so the walk's exception handler can replan the step.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use nalgebra::{Point2, Point3};
use tca_module::{ComputeTime, Connector, Context, HandlerError, Module, ModuleError};
use tca_robot::{CarriagePose, JointPosition, LegKinematics, LegParams};
use tca_single_leg_messages::{
    BodyPosition, ElbowSide, JointLegPosition, Joints, LegReachability, MapCell, MapGrid, MapKind,
    MapRegion, MoveFailed, MoveFailureKind, RecoverLeg, WorldPoint,
};

use crate::params::LrpParams;
use crate::picture::cspace_picture;
use crate::planner::LegRecoveryPlanner;
use crate::polygon::{rectangle, region_grid};
use crate::terrain_grid::TerrainGrid;

/// The module's default name.
pub const DEFAULT_MODULE_NAME: &str = "lrp";

/// How the Leg Recovery Planner module runs.
#[derive(Debug, Clone, PartialEq)]
pub struct LrpConfig {
    /// The module's name (default `lrp`).
    pub module_name: String,
    /// The leg's parameters.
    pub leg: LegParams,
    /// The planner's parameters.
    pub params: LrpParams,
    /// Resolution of the elevation map asked of the LTM Manager, metres.
    pub map_resolution_m: f64,
    /// Write a picture of the configuration space and the search of every `recoverLeg`
    /// here (`recover-leg-<n>.png`), for the PDM or people to look at.
    pub picture_dir: Option<PathBuf>,
    /// Stamp messages with simulated time and charge the planning's wall-clock time to it
    /// (run with a simulated Controller).
    pub simulated_time: bool,
    /// What planning a leg move (`recoverLeg`) charges to simulated time: the measured
    /// computing time, or a modeled one (the 1990 LRP took about 12 s a step, §7.2).
    pub compute_time: ComputeTime,
    /// What a reachability map (`legReachability`) charges to simulated time.
    pub reachability_compute_time: ComputeTime,
}

impl Default for LrpConfig {
    fn default() -> Self {
        Self {
            module_name: DEFAULT_MODULE_NAME.into(),
            leg: LegParams::default(),
            params: LrpParams::default(),
            map_resolution_m: 0.05,
            picture_dir: None,
            simulated_time: false,
            compute_time: ComputeTime::Measured,
            reachability_compute_time: ComputeTime::Measured,
        }
    }
}

/// State shared by the handlers.
#[derive(Debug, Clone)]
struct Shared {
    planner: Arc<LegRecoveryPlanner>,
    kin: Arc<LegKinematics>,
    map_resolution_m: f64,
    picture_dir: Option<PathBuf>,
    pictures: Arc<AtomicU64>,
    compute_time: ComputeTime,
    reachability_compute_time: ComputeTime,
}

/// Connects the Leg Recovery Planner to central under `config.module_name` and serves
/// [`RecoverLeg`] and [`LegReachability`] until the returned [`Module`] is dropped or
/// closed. Bad parameters are a [`ModuleError::Config`] saying what to fix.
pub async fn connect(connector: &Connector, config: LrpConfig) -> Result<Module, ModuleError> {
    if !(config.map_resolution_m.is_finite() && config.map_resolution_m > 0.0) {
        return Err(ModuleError::Config(format!(
            "lrp map resolution {} m must be a finite number above 0",
            config.map_resolution_m
        )));
    }
    let planner = LegRecoveryPlanner::new(config.leg.clone(), config.params)
        .map_err(|e| ModuleError::Config(format!("lrp configuration: {e}")))?;
    let shared = Shared {
        planner: Arc::new(planner),
        kin: Arc::new(LegKinematics::new(&config.leg)),
        map_resolution_m: config.map_resolution_m,
        picture_dir: config.picture_dir.clone(),
        pictures: Arc::new(AtomicU64::new(0)),
        compute_time: config.compute_time,
        reachability_compute_time: config.reachability_compute_time,
    };
    tracing::info!(module = %config.module_name, "leg recovery planner starting");
    Module::builder(config.module_name.clone())
        .simulated_time(config.simulated_time)
        // A module that dies while answering one of our queries is restarted; ask again.
        .requery_after_crash(tca_module::REQUERIES_AFTER_CRASH)
        .handle({
            let shared = shared.clone();
            move |ctx: Context, goal: RecoverLeg| {
                let shared = shared.clone();
                async move { shared.recover_leg(&ctx, goal).await }
            }
        })
        .handle(move |ctx: Context, query: LegReachability| {
            let shared = shared.clone();
            async move { shared.reachability(&ctx, query).await }
        })
        .connect(connector)
        .await
}

impl Shared {
    /// The elevation map of the leg's reach around the carriage, and where the leg is.
    async fn inputs(
        &self,
        ctx: &Context,
        body_y_m: f64,
        start_foot: Option<WorldPoint>,
    ) -> Result<(TerrainGrid, JointPosition), HandlerError> {
        let leg = self.planner.leg_params();
        let reach = leg.leg.upper_link_m + leg.leg.lower_link_m + 0.5;
        let x = leg.carriage.x_m;
        let region = MapRegion {
            kind: MapKind::Elevation,
            polygon: rectangle(
                Point2::new(x - reach, body_y_m - reach),
                Point2::new(x + reach, body_y_m + reach),
            ),
            resolution_m: self.map_resolution_m,
            refresh: false,
        };
        let map = ctx.query(&region).await?;
        let map = TerrainGrid::from_map_grid(&map)?;
        let joints = joints_from_message(&ctx.query(&JointLegPosition).await?);
        let start = match start_foot {
            // Planned ahead: the leg as it will be, on the elbow branch it is on now.
            Some(foot) => self
                .kin
                .inverse_world(
                    &CarriagePose::level(body_y_m),
                    &Point3::new(foot.x_m, foot.y_m, foot.z_m),
                    tca_robot::ElbowBranch::of(&joints),
                )
                .map_err(|e| HandlerError::new(format!("the planned start foot: {e}")))?,
            None => joints,
        };
        Ok((map, start))
    }

    async fn recover_leg(&self, ctx: &Context, goal: RecoverLeg) -> Result<(), HandlerError> {
        let body = ctx.query(&BodyPosition).await?;
        if (body.y_m - goal.body_y_m).abs() > 0.05 {
            tracing::debug!(
                now_m = body.y_m,
                planned_m = goal.body_y_m,
                "recoverLeg planned for another carriage position than the current one"
            );
        }
        let (map, start) = self.inputs(ctx, goal.body_y_m, goal.start_foot).await?;
        let footfall = Point3::new(goal.footfall.x_m, goal.footfall.y_m, goal.footfall.z_m);
        let began = Instant::now();
        let planner = self.planner.clone();
        let body_y = goal.body_y_m;
        let elbow = goal.elbow.map(|side| match side {
            ElbowSide::Positive => tca_robot::ElbowBranch::Positive,
            ElbowSide::Negative => tca_robot::ElbowBranch::Negative,
        });
        let planned = tokio::task::spawn_blocking(move || {
            let cs = planner.cspace(&map, body_y)?;
            let plan = planner.plan_on_branch(&cs, &start, &footfall, elbow)?;
            Ok::<_, crate::PlanError>((cs, plan))
        })
        .await
        .map_err(|e| HandlerError::new(format!("the planning task ended abnormally: {e}")))?;
        if ctx.simulated_time() {
            ctx.spend(self.compute_time.charged(began.elapsed()));
        }
        match planned {
            Ok((cs, plan)) => {
                tracing::debug!(
                    waypoints = plan.waypoints.len(),
                    time_s = plan.motion.time_s,
                    "leg trajectory planned"
                );
                ctx.command(&plan.to_leg_move())?;
                if let Some(dir) = &self.picture_dir {
                    let n = self.pictures.fetch_add(1, Ordering::Relaxed) + 1;
                    let path = dir.join(format!("recover-leg-{n}.png"));
                    if let Err(e) = cspace_picture(&cs, Some(&plan)).write_png(&path) {
                        tracing::warn!(%e, "C-space picture not written");
                    }
                }
                Ok(())
            }
            Err(e) => {
                let foot = self
                    .kin
                    .forward_world(&CarriagePose::level(goal.body_y_m), &start);
                ctx.raise(&MoveFailed {
                    command: "recoverLeg".into(),
                    kind: MoveFailureKind::Refused,
                    detail: e.to_string(),
                    foot: WorldPoint {
                        x_m: foot.x,
                        y_m: foot.y,
                        z_m: foot.z,
                    },
                })?;
                Err(HandlerError::new(e.to_string()))
            }
        }
    }

    async fn reachability(
        &self,
        ctx: &Context,
        query: LegReachability,
    ) -> Result<MapGrid, HandlerError> {
        let cells = region_grid(&query.polygon, query.resolution_m)?;
        let (map, start) = self.inputs(ctx, query.body_y_m, query.start_foot).await?;
        let planner = self.planner.clone();
        let body_y = query.body_y_m;
        let began = Instant::now();
        let answer = tokio::task::spawn_blocking(move || {
            let cs = planner.cspace(&map, body_y)?;
            let reach = planner.reachability(&cs, &start)?;
            Ok::<_, crate::PlanError>(reachability_map(&cells, |p| reach.reaches(p)))
        })
        .await
        .map_err(|e| HandlerError::new(format!("the reachability task ended abnormally: {e}")))?;
        if ctx.simulated_time() {
            ctx.spend(self.reachability_compute_time.charged(began.elapsed()));
        }
        Ok(answer?)
    }
}

/// The `legReachability` answer over a region grid (`true` = inside the polygon): value 1
/// where the foot can reach, 0 where it cannot, unknown outside the polygon; map kind
/// [`MapKind::Reachability`].
pub fn reachability_map(
    cells: &tca_robot::Grid<bool>,
    reaches: impl Fn(Point2<f64>) -> bool,
) -> MapGrid {
    let o = cells.origin();
    MapGrid {
        kind: MapKind::Reachability,
        origin_x_m: o.x,
        origin_y_m: o.y,
        resolution_m: cells.resolution_m(),
        nx: u32::try_from(cells.nx()).unwrap_or(u32::MAX),
        ny: u32::try_from(cells.ny()).unwrap_or(u32::MAX),
        cells: cells
            .iter()
            .map(|(c, &inside)| {
                if inside {
                    MapCell::Known {
                        value: if reaches(cells.cell_center(c)) {
                            1.0
                        } else {
                            0.0
                        },
                        sigma_m: 0.0,
                    }
                } else {
                    MapCell::Unknown
                }
            })
            .collect(),
    }
}

fn joints_from_message(j: &Joints) -> JointPosition {
    JointPosition::new(j.shoulder_rad, j.elbow_rad, j.vertical_m)
}
