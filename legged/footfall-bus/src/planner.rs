//! The ground-side planner module: it holds the terrain (the ground's digital elevation
//! model), reads the robot's state from the Controller's telemetry at each request and
//! answers `footfall.maps` and `footfall.plan`.

use std::sync::{Arc, Mutex};

use tca_footfall::Scene;
use tca_footfall::maps::{LegMaps, leg_maps};
use tca_footfall::plan::{FootfallPlan, PlanOptions, StepPlanner};
use tca_legged_messages::{BodyPose, LegState, RobotModel as RobotModelQuery};
use tca_legged_model::RobotModel;
use tca_legged_sim::pose_to_isometry;
use tca_module::{Connector, Context, HandlerError, Module, ModuleError};
use tca_robot::HeightField;

use crate::messages::{FootfallMaps, FootfallPlanStep};

/// The planner module's name unless told otherwise.
pub const PLANNER_MODULE: &str = "footfall-planner";

/// What the planner module plans with.
#[derive(Clone, Debug)]
pub struct PlannerConfig {
    /// The terrain.
    pub terrain: Arc<HeightField>,
    /// How steps are planned (the request chooses the planner and the heuristics).
    pub options: PlanOptions,
    /// Its name on the bus.
    pub module_name: String,
}

/// The last scene and its step planner, kept while the robot does not move (the terrain
/// meshes are made once per scene).
#[derive(Default)]
struct Cache {
    planner: Option<Arc<StepPlanner>>,
    model: Option<Arc<RobotModel>>,
}

/// The robot's state now, from the Controller's telemetry (`legged.robotModel` when
/// `model` is not known yet, `legged.bodyPose`, `legged.legState` of every leg), on
/// `terrain`.
pub async fn scene_from_telemetry(
    module: &Module,
    terrain: &Arc<HeightField>,
    model: Option<Arc<RobotModel>>,
) -> Result<Scene, String> {
    let model = match model {
        Some(m) => m,
        None => {
            let d = module
                .query(&RobotModelQuery)
                .await
                .map_err(|e| format!("cannot ask the robot's description: {e}"))?;
            Arc::new(
                RobotModel::from_urdf_str(&d.urdf)
                    .map_err(|e| format!("the robot's description does not read: {e}"))?,
            )
        }
    };
    // Asked all at once: across a delaying bridge the answers come back together, one round
    // trip for the lot rather than one per question, and nearer one moment of the robot.
    let legs = model.legs().iter().map(|leg| async move {
        module
            .query(&LegState {
                leg: leg.name().to_owned(),
            })
            .await
            .map_err(|e| format!("cannot ask leg {}'s state: {e}", leg.name()))
    });
    let (pose, legs) =
        futures::future::join(module.query(&BodyPose), futures::future::join_all(legs)).await;
    let pose = pose.map_err(|e| format!("cannot ask the body's pose: {e}"))?;
    let mut posture = Vec::new();
    let mut stance = Vec::new();
    for s in legs {
        let s = s?;
        posture.push(s.joints);
        stance.push(s.stance);
    }
    let scene = Scene {
        model,
        terrain: terrain.clone(),
        body: pose_to_isometry(&pose),
        posture,
        stance,
    };
    scene.check().map_err(|e| e.to_string())?;
    Ok(scene)
}

/// The robot's state now, the model cached.
async fn scene_now(
    ctx: &Context,
    terrain: &Arc<HeightField>,
    cache: &Mutex<Cache>,
) -> Result<Scene, HandlerError> {
    let known = cache
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .model
        .clone();
    let scene = scene_from_telemetry(ctx, terrain, known)
        .await
        .map_err(HandlerError::new)?;
    cache.lock().unwrap_or_else(|p| p.into_inner()).model = Some(scene.model.clone());
    Ok(scene)
}

/// A step planner for `scene`: the cached one when the robot has not moved.
fn planner_for(
    scene: Scene,
    options: &PlanOptions,
    cache: &Mutex<Cache>,
) -> Result<Arc<StepPlanner>, HandlerError> {
    let mut c = cache.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(p) = &c.planner {
        let s = p.scene();
        if s.body == scene.body && s.posture == scene.posture && s.stance == scene.stance {
            return Ok(p.clone());
        }
    }
    let p = Arc::new(
        StepPlanner::new(Arc::new(scene), options.clone())
            .map_err(|e| HandlerError::new(e.to_string()))?,
    );
    c.planner = Some(p.clone());
    Ok(p)
}

/// Connects the planner module and serves until it is dropped or closed.
pub async fn connect_planner(
    connector: &Connector,
    config: PlannerConfig,
) -> Result<Module, ModuleError> {
    let cache = Arc::new(Mutex::new(Cache::default()));
    let config = Arc::new(config);
    Module::builder(config.module_name.clone())
        .replace(true)
        .handle({
            let (cache, config) = (cache.clone(), config.clone());
            move |ctx: Context, q: FootfallMaps| {
                let (cache, config) = (cache.clone(), config.clone());
                async move {
                    let scene = scene_now(&ctx, &config.terrain, &cache).await?;
                    let leg = scene
                        .leg_index(&q.leg)
                        .map_err(|e| HandlerError::new(e.to_string()))?;
                    let mut params = config.options.map.clone();
                    if let Some(p) = q.polygon {
                        params.polygon = p;
                    }
                    if let Some(r) = q.resolution_m {
                        params.resolution_m = r;
                    }
                    tokio::task::spawn_blocking(move || -> Result<LegMaps, HandlerError> {
                        leg_maps(&scene, leg, &params).map_err(|e| HandlerError::new(e.to_string()))
                    })
                    .await
                    .map_err(|e| HandlerError::new(format!("the maps stopped: {e}")))?
                }
            }
        })
        .handle(move |ctx: Context, q: FootfallPlanStep| {
            let (cache, config) = (cache.clone(), config.clone());
            async move {
                let scene = scene_now(&ctx, &config.terrain, &cache).await?;
                let leg = scene
                    .leg_index(&q.leg)
                    .map_err(|e| HandlerError::new(e.to_string()))?;
                let mut options = config.options.clone();
                options.planner = q.planner;
                if !q.heuristics {
                    options.heuristics = None;
                }
                let planner = planner_for(scene, &config.options, &cache)?;
                let target = nalgebra::Point2::new(q.target[0], q.target[1]);
                tokio::task::spawn_blocking(move || -> Result<FootfallPlan, HandlerError> {
                    planner
                        .plan_with(leg, target, &options)
                        .map_err(|e| HandlerError::new(e.to_string()))
                })
                .await
                .map_err(|e| HandlerError::new(format!("the planner stopped: {e}")))?
            }
        })
        .connect(connector)
        .await
}
