//! The ISM on the bus (`ism`): the simulated stereo camera and visual odometry. Each
//! `nav.acquireDepth` asks the simulated Controller where the base really is (a simulated
//! camera must be placed there: `nav.truePose` of a wheeled base, over the terrain under
//! it; `legged.bodyPose` of a legged robot, whose body carries the camera), moves the
//! drifting odometry by the planar motion since the last frame, and answers with the depth
//! image, the odometry's estimate and the base's height and tilt.

use std::sync::{Arc, Mutex};

use tca_legged_messages::BodyPose;
use tca_module::{Connector, HandlerError, Module, ModuleError};
use tca_nav_messages::{AcquireDepth, DepthFrame, TruePose};
use tca_nav_navigator::Pose2;
use tca_nav_sensing::{Attitude, CameraMount, CameraParams, DepthCamera, DriftingOdometry};
use tca_robot::HeightField;

use crate::convert::{body_pose_of, depth_msg, pose_msg, pose_of};

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
    /// Where the true pose comes from.
    pub pose_source: PoseSource,
}

/// Which Controller tells the simulated camera where it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PoseSource {
    /// A base on the ground: `nav.truePose`, the camera over the terrain under the base's
    /// centre, level (stabilised in roll and pitch).
    #[default]
    Planar,
    /// A legged robot: `legged.bodyPose`, the camera fixed to the body.
    LeggedBody,
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
                let said = |e| {
                    HandlerError::new(format!(
                        "nav.acquireDepth: the Controller did not say where the base is: {e}"
                    ))
                };
                let (truth, attitude) = match c.pose_source {
                    PoseSource::Planar => {
                        let p = pose_of(&ctx.query(&TruePose).await.map_err(said)?);
                        (p, Attitude::level(c.terrain.height_at(p.x, p.y)))
                    }
                    PoseSource::LeggedBody => {
                        body_pose_of(&ctx.query(&BodyPose).await.map_err(said)?)
                    }
                };
                Ok(acquire(&c, &s, truth, attitude))
            }
        })
        .connect(connector)
        .await
}

fn acquire(
    config: &IsmConfig,
    state: &Mutex<State>,
    truth: Pose2,
    attitude: Attitude,
) -> DepthFrame {
    let mut s = state.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(last) = s.last_true {
        s.odometry.update(&last, &truth);
    }
    s.last_true = Some(truth);
    let image = s.camera.capture(
        &config.terrain,
        &config.mount.camera_pose(&truth, &attitude),
    );
    let (width, height, depth_m) = depth_msg(&image);
    let frame = s.frames;
    s.frames += 1;
    DepthFrame {
        frame,
        width,
        height,
        depth_m,
        estimate: pose_msg(&s.odometry.estimate()),
        base_z_m: attitude.z_m,
        base_roll_rad: attitude.roll_rad,
        base_pitch_rad: attitude.pitch_rad,
    }
}
