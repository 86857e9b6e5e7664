//! The base's Controller on the bus (`controller`): the simulated differential-drive base
//! obeying `nav.drive`, and the simulation's truth for simulated sensors and for judging a
//! run.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use tca_module::{Connector, HandlerError, Module, ModuleError};
use tca_nav_messages::{Drive, Driven, PlanarPose, SimStatus, SimStatusReply, TruePose};
use tca_nav_navigator::{Base, Pose2, WheeledBase, WheeledParams};
use tca_robot::HeightField;

use crate::convert::pose_msg;

/// How the simulated base runs.
#[derive(Debug, Clone)]
pub struct ControllerConfig {
    /// The module's name.
    pub module_name: String,
    /// The true terrain.
    pub terrain: Arc<HeightField>,
    /// Where the base starts.
    pub start: Pose2,
    /// The base.
    pub wheeled: WheeledParams,
    /// Longest drive accepted, s.
    pub max_duration_s: f64,
}

#[derive(Debug, Default)]
struct State {
    pose: Pose2,
    poses: Vec<PlanarPose>,
    distance_m: f64,
    collisions: u64,
    falls: u64,
}

/// Connects the simulated base's Controller.
pub async fn connect(
    connector: &Connector,
    config: ControllerConfig,
) -> Result<Module, ModuleError> {
    let state = Arc::new(Mutex::new(State {
        pose: config.start,
        ..State::default()
    }));
    let config = Arc::new(config);
    let (s1, s2, s3) = (state.clone(), state.clone(), state);
    let c1 = config.clone();
    Module::builder(config.module_name.clone())
        .simulated_time(true)
        .handle(move |ctx, d: Drive| {
            let (c, s) = (c1.clone(), s1.clone());
            async move {
                let reply = drive(&c, &s, &d)?;
                ctx.spend(Duration::from_secs_f64(d.duration_s));
                Ok(reply)
            }
        })
        .handle(move |_ctx, _q: TruePose| {
            let p = lock(&s2).pose;
            async move { Ok(pose_msg(&p)) }
        })
        .handle(move |_ctx, _q: SimStatus| {
            let s = lock(&s3);
            let reply = SimStatusReply {
                pose: pose_msg(&s.pose),
                poses: s.poses.clone(),
                distance_m: s.distance_m,
                collisions: s.collisions,
                falls: s.falls,
            };
            async move { Ok(reply) }
        })
        .connect(connector)
        .await
}

fn drive(
    config: &ControllerConfig,
    state: &Mutex<State>,
    d: &Drive,
) -> Result<Driven, HandlerError> {
    check_drive(d, config.max_duration_s)?;
    let mut s = lock(state);
    let mut base = WheeledBase::new(config.wheeled, &config.terrain, s.pose);
    let m = base.drive(d.forward_mps, d.turn_rps, d.duration_s);
    let before = s.pose;
    s.poses.push(pose_msg(&before));
    s.distance_m += before.distance(&m.pose);
    s.collisions += u64::from(m.collided);
    s.falls += u64::from(m.fell);
    s.pose = m.pose;
    Ok(Driven {
        collided: m.collided,
        fell: m.fell,
    })
}

/// Refuses speeds that are not numbers and durations outside (0, `max_duration_s`].
pub(crate) fn check_drive(d: &Drive, max_duration_s: f64) -> Result<(), HandlerError> {
    if !(d.forward_mps.is_finite() && d.turn_rps.is_finite()) {
        return Err(HandlerError::new(format!(
            "nav.drive: the speeds must be finite numbers (got forward {} m/s, turn {} rad/s)",
            d.forward_mps, d.turn_rps
        )));
    }
    if !(d.duration_s.is_finite() && d.duration_s > 0.0 && d.duration_s <= max_duration_s) {
        return Err(HandlerError::new(format!(
            "nav.drive: duration_s {} is not valid; give more than 0 and at most {} s",
            d.duration_s, max_duration_s
        )));
    }
    Ok(())
}

fn lock(s: &Mutex<State>) -> std::sync::MutexGuard<'_, State> {
    s.lock().unwrap_or_else(|p| p.into_inner())
}
