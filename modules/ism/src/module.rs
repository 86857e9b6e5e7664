//! The ISM as a TCA module: answers `acquireImage` ([`AcquireImage`] -> [`RangeImage`]) by
//! asking the Controller for the pose of the body the sensors are mounted on and acquiring an
//! image from the configured sensor of the kind asked for. The pose source is the
//! configuration's [`PoseSource`]: the single-leg carriage (`bodyPosition`, the default) or a
//! legged robot's body (`legged.bodyPose`, see [`crate::legged`]).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use tca_module::{Connector, HandlerError, Module, ModuleError};
use tca_robot::{HeightField, LegParams};
use tca_single_leg_messages::{AcquireImage, BodyPosition, RangeImage, SensorKind};

use crate::frames::carriage_pose;
use crate::legged::{PoseSource, world_from_body};
use crate::scanner::VirtualScanner;
use crate::sensor::RangeSensor;
use crate::spec::SensorSpec;

/// The ISM's sensors: at most one of each kind.
#[derive(Default)]
pub struct IsmConfig {
    sensors: Vec<Box<dyn RangeSensor>>,
    simulated_time: bool,
    pose_source: PoseSource,
    error: Option<String>,
}

impl std::fmt::Debug for IsmConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("IsmConfig")
            .field(
                "sensors",
                &self
                    .sensors
                    .iter()
                    .map(|s| s.spec().kind)
                    .collect::<Vec<_>>(),
            )
            .field("simulated_time", &self.simulated_time)
            .field("pose_source", &self.pose_source)
            .finish()
    }
}

impl IsmConfig {
    /// No sensors yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a sensor (a [`VirtualScanner`], a [`crate::StoredSequence`], or any other
    /// [`RangeSensor`]).
    pub fn with_sensor(mut self, sensor: impl RangeSensor + 'static) -> Self {
        self.sensors.push(Box::new(sensor));
        self
    }

    /// A virtual Erim and a virtual Perceptron looking at `terrain` from the carriage of
    /// `params`, with their default noise seeded by `seed` (the Perceptron by `seed + 1`).
    pub fn simulated(terrain: Arc<HeightField>, params: &LegParams, seed: u64) -> Self {
        Self::new()
            .with_sensor(
                VirtualScanner::new(SensorSpec::erim(), terrain.clone(), params).with_seed(seed),
            )
            .with_sensor(
                VirtualScanner::new(SensorSpec::perceptron(), terrain, params)
                    .with_seed(seed.wrapping_add(1)),
            )
    }

    /// Stamp messages with simulated time, charging each image its acquisition time (a
    /// scanner frame: half a second at the Erim's and the Perceptron's 2 frames per second,
    /// §2.2).
    pub fn with_simulated_time(mut self, on: bool) -> Self {
        self.simulated_time = on;
        self
    }

    /// Where the body pose comes from at every image (default: the single-leg carriage).
    pub fn with_pose_source(mut self, source: PoseSource) -> Self {
        self.pose_source = source;
        self
    }

    /// The pose source.
    pub fn pose_source(&self) -> PoseSource {
        self.pose_source
    }

    /// Marks the configuration as bad: [`connect`] refuses it with this reason.
    pub(crate) fn with_error(mut self, reason: String) -> Self {
        self.error = Some(reason);
        self
    }

    /// The kinds of sensor configured.
    pub fn kinds(&self) -> Vec<SensorKind> {
        self.sensors.iter().map(|s| s.spec().kind).collect()
    }
}

type SharedSensor = Arc<Mutex<Box<dyn RangeSensor>>>;

/// How long a scanner takes for one frame (both scanners acquire 2 frames per second, §2.2).
pub const FRAME_TIME: std::time::Duration = std::time::Duration::from_millis(500);

/// Connects the ISM module (`"ism"`) and serves `acquireImage`. Two sensors of one kind are a
/// configuration error.
pub async fn connect(connector: &Connector, config: IsmConfig) -> Result<Module, ModuleError> {
    if let Some(reason) = config.error {
        return Err(ModuleError::Config(reason));
    }
    let source = config.pose_source;
    let mut sensors: HashMap<SensorKind, SharedSensor> = HashMap::new();
    for sensor in config.sensors {
        let kind = sensor.spec().kind;
        if sensors.insert(kind, Arc::new(Mutex::new(sensor))).is_some() {
            return Err(ModuleError::Config(format!(
                "two {kind:?} sensors were configured for the ISM; configure one of each kind"
            )));
        }
    }
    let sensors = Arc::new(sensors);
    Module::builder("ism")
        .simulated_time(config.simulated_time)
        .handle(move |ctx, request: AcquireImage| {
            let sensors = sensors.clone();
            async move { acquire(&ctx, &sensors, request.sensor, source).await }
        })
        .connect(connector)
        .await
}

async fn acquire(
    ctx: &tca_module::Context,
    sensors: &HashMap<SensorKind, SharedSensor>,
    kind: SensorKind,
    source: PoseSource,
) -> Result<RangeImage, HandlerError> {
    let sensor = sensors
        .get(&kind)
        .cloned()
        .ok_or_else(|| HandlerError::from(crate::IsmError::NoSuchSensor(kind)))?;
    let image = match source {
        PoseSource::Carriage => {
            let pose = carriage_pose(&ctx.query(&BodyPosition).await?);
            let image = run(sensor, move |s| s.acquire(&pose)).await?;
            tracing::debug!(sensor = ?kind, sequence = image.sequence, y_m = pose.y_m, "image acquired");
            image
        }
        PoseSource::LeggedBody => {
            let pose = ctx.query(&tca_legged_messages::BodyPose).await?;
            let body = world_from_body(&pose);
            let image = run(sensor, move |s| s.acquire_from_body(&body)).await?;
            tracing::debug!(
                sensor = ?kind,
                sequence = image.sequence,
                x_m = pose.x_m,
                y_m = pose.y_m,
                yaw_rad = pose.yaw_rad,
                "image acquired from the legged body"
            );
            image
        }
    };
    ctx.spend(FRAME_TIME);
    Ok(image)
}

/// Runs an acquisition on a blocking thread.
async fn run(
    sensor: SharedSensor,
    f: impl FnOnce(&mut dyn RangeSensor) -> crate::Result<RangeImage> + Send + 'static,
) -> Result<RangeImage, HandlerError> {
    tokio::task::spawn_blocking(move || {
        let mut sensor = sensor.lock().map_err(|_| {
            HandlerError::new("the sensor's state was poisoned by an earlier panic")
        })?;
        f(sensor.as_mut()).map_err(HandlerError::from)
    })
    .await
    .map_err(|e| HandlerError::new(format!("image acquisition did not finish: {e}")))?
}
