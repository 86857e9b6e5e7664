//! A walking robot's body-level Controller on the bus (`controller`, beside the legged
//! Controller `legged-controller`): it answers the same `nav.drive`, `nav.truePose` and
//! `nav.simStatus` as the wheeled base's, so the navigator does not know which it drives.
//!
//! Each `nav.drive` reads the robot from the legged Controller (`legged.bodyPose` and
//! `legged.legState` of every leg), has the [`Stepper`] plan checked free-gait moves toward
//! the body target the speeds give, and sends them one at a time as `legged.legMove` and
//! `legged.bodyMove` commands, each achieved before the next (a failed move: the robot is
//! read again and the walk planned on from where it is). Collisions and falls are the
//! legged simulator's, read from `legged.controllerStatus` before and after.

use std::sync::{Arc, Mutex};

use tca_legged_messages::{
    BodyMove, BodyPose, LegMove, LegState, LegStateReply, LeggedStatus, LeggedStatusReply,
};
use tca_legged_sim::isometry_to_pose;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Context, HandlerError, Module, ModuleError};
use tca_nav_hexapod::{Stepper, WalkEnd, gait_state, split_pose};
use tca_nav_messages::{Drive, Driven, PlanarPose, SimStatus, SimStatusReply, TruePose};
use tca_nav_navigator::Pose2;

use crate::convert::pose_msg;

/// How the walking base's Controller runs.
#[derive(Debug, Clone)]
pub struct WalkingConfig {
    /// The module's name.
    pub module_name: String,
    /// What plans the moves (the robot, the terrain it plans footholds on, how it walks).
    pub stepper: Arc<Stepper>,
    /// Longest drive accepted, s.
    pub max_duration_s: f64,
}

#[derive(Debug, Default)]
struct State {
    poses: Vec<PlanarPose>,
    distance_m: f64,
    stalls: u64,
}

/// Connects the walking base's Controller.
pub async fn connect(connector: &Connector, config: WalkingConfig) -> Result<Module, ModuleError> {
    let state = Arc::new(Mutex::new(State::default()));
    let config = Arc::new(config);
    let (s1, s2) = (state.clone(), state);
    Module::builder(config.module_name.clone())
        .simulated_time(true)
        .handle(move |ctx, d: Drive| {
            let (c, s) = (config.clone(), s1.clone());
            async move { drive(&ctx, &c, &s, &d).await }
        })
        .handle(|ctx, _q: TruePose| async move {
            let body = ctx.query(&BodyPose).await.map_err(not_told)?;
            Ok(pose_msg(&split_pose(&body).0))
        })
        .handle(move |ctx, _q: SimStatus| {
            let s = s2.clone();
            async move {
                let body = ctx.query(&BodyPose).await.map_err(not_told)?;
                let status = ctx.query(&LeggedStatus).await.map_err(not_told)?;
                let s = lock(&s);
                Ok(SimStatusReply {
                    pose: pose_msg(&split_pose(&body).0),
                    poses: s.poses.clone(),
                    distance_m: s.distance_m,
                    collisions: u64::from(status.collisions),
                    falls: u64::from(status.falls),
                })
            }
        })
        .connect(connector)
        .await
}

fn not_told(e: tca_module::ModuleError) -> HandlerError {
    HandlerError::new(format!(
        "the legged Controller did not say where the robot is: {e}"
    ))
}

fn lock(s: &Mutex<State>) -> std::sync::MutexGuard<'_, State> {
    s.lock().unwrap_or_else(|p| p.into_inner())
}

/// The robot as the legged Controller reports it, with its planar pose.
async fn read(
    ctx: &Context,
    stepper: &Stepper,
) -> Result<(Pose2, tca_free_gait::GaitState), HandlerError> {
    let body = ctx.query(&BodyPose).await.map_err(not_told)?;
    let mut legs: Vec<LegStateReply> = Vec::with_capacity(stepper.model().legs().len());
    for leg in stepper.model().legs() {
        legs.push(
            ctx.query(&LegState {
                leg: leg.name().to_string(),
            })
            .await
            .map_err(not_told)?,
        );
    }
    Ok((split_pose(&body).0, gait_state(&body, &legs)))
}

async fn status(ctx: &Context) -> Result<LeggedStatusReply, HandlerError> {
    ctx.query(&LeggedStatus).await.map_err(not_told)
}

/// Sends one move and waits for it: whether it was achieved.
async fn execute(
    ctx: &Context,
    stepper: &Stepper,
    action: &tca_free_gait::Action,
) -> Result<bool, HandlerError> {
    use tca_free_gait::Action;
    let task = match action {
        Action::Swing { leg, waypoints, .. } | Action::Reach { leg, waypoints } => {
            let name = stepper.model().legs()[*leg].name().to_string();
            ctx.send_watched(
                &LegMove {
                    leg: name,
                    waypoints: waypoints.clone(),
                    transition: matches!(action, Action::Swing { .. }),
                },
                [],
            )?
        }
        Action::Body { target } => ctx.send_watched(
            &BodyMove {
                target: isometry_to_pose(target),
            },
            [],
        )?,
    };
    match task.outcome().await? {
        TaskOutcome::Achieved => Ok(true),
        TaskOutcome::Failed(reason) => {
            tracing::debug!(%reason, "a move failed; planning again from where the robot is");
            Ok(false)
        }
        TaskOutcome::Killed => Err(HandlerError::new(
            "nav.drive: a move of the walking base was killed",
        )),
    }
}

async fn drive(
    ctx: &Context,
    config: &WalkingConfig,
    state: &Mutex<State>,
    d: &Drive,
) -> Result<Driven, HandlerError> {
    crate::controller::check_drive(d, config.max_duration_s)?;
    let stepper = &config.stepper;
    let before = status(ctx).await?;
    let (from, start) = read(ctx, stepper).await?;
    let mut walk = stepper.walk(&start, d.forward_mps, d.turn_rps, d.duration_s);
    let (mut to, mut now) = (from, start);
    while let Some(actions) = walk.next(stepper, &now) {
        for action in &actions {
            if !execute(ctx, stepper, action).await? {
                walk.failed();
                break;
            }
        }
        (to, now) = read(ctx, stepper).await?;
    }
    let after = status(ctx).await?;
    let mut s = lock(state);
    if let Some(WalkEnd::Stuck(why)) = walk.end() {
        s.stalls += 1;
        tracing::warn!(%why, "the walking base found no move toward its target");
    }
    s.poses.push(pose_msg(&from));
    s.distance_m += from.distance(&to);
    Ok(Driven {
        collided: after.collisions > before.collisions,
        fell: after.falls > before.falls,
    })
}
