//! The ISM on the bus (`ism`): the simulated stereo camera and visual odometry. Each
//! `nav.acquireDepth` asks the simulated Controller where the base really is (a simulated
//! camera must be placed there), moves the drifting odometry by the motion since the last
//! frame, and answers with the depth image and the odometry's estimate.

use std::sync::{Arc, Mutex};

use tca_module::{Connector, HandlerError, Module, ModuleError};
use tca_nav_messages::{AcquireDepth, DepthFrame, TruePose};
use tca_nav_navigator::Pose2;
use tca_nav_sensing::{CameraMount, CameraParams, DepthCamera, DriftingOdometry};
use tca_robot::HeightField;

use crate::convert::{depth_msg, pose_msg, pose_of};

/// How the ISM runs.
#[derive(Debug, Clone)]
pub struct IsmConfig {
    /// The module's name.
    pub module_name: String,
    /// The scene the camera sees (the true terrain).
    pub terrain: Arc<HeightField>,
    /// The camera.
    pub camera: CameraParams,
    /// Where it sits on the base.
    pub mount: CameraMount,
    /// Where the base starts (the odometry's origin).
    pub start: Pose2,
    /// Odometry drift, fraction of the distance travelled.
    pub drift: f64,
    /// Seed of the camera's and the odometry's noise.
    pub seed: u64,
}

struct State {
    camera: DepthCamera,
    odometry: DriftingOdometry,
    last_true: Option<Pose2>,
    frames: u64,
}

/// Connects the ISM; refuses a camera whose parameters are not valid.
pub async fn connect(connector: &Connector, config: IsmConfig) -> Result<Module, ModuleError> {
    let camera = DepthCamera::new(config.camera.clone(), config.seed)
        .map_err(|e| ModuleError::Config(format!("the ISM's camera: {e}")))?;
    let state = Arc::new(Mutex::new(State {
        camera,
        odometry: DriftingOdometry::new(config.start, config.drift, config.seed),
        last_true: None,
        frames: 0,
    }));
    let config = Arc::new(config);
    Module::builder(config.module_name.clone())
        .simulated_time(true)
        .handle(move |ctx, _q: AcquireDepth| {
            let (c, s) = (config.clone(), state.clone());
            async move {
                let truth = pose_of(&ctx.query(&TruePose).await.map_err(|e| {
                    HandlerError::new(format!(
                        "nav.acquireDepth: the Controller did not say where the base is: {e}"
                    ))
                })?);
                Ok(acquire(&c, &s, truth))
            }
        })
        .connect(connector)
        .await
}

fn acquire(config: &IsmConfig, state: &Mutex<State>, truth: Pose2) -> DepthFrame {
    let mut s = state.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(last) = s.last_true {
        s.odometry.update(&last, &truth);
    }
    s.last_true = Some(truth);
    let ground = config.terrain.height_at(truth.x, truth.y);
    let image = s
        .camera
        .capture(&config.terrain, &config.mount.camera_pose(&truth, ground));
    let (width, height, depth_m) = depth_msg(&image);
    let frame = s.frames;
    s.frames += 1;
    DepthFrame {
        frame,
        width,
        height,
        depth_m,
        estimate: pose_msg(&s.odometry.estimate()),
        ground_m: ground,
    }
}
