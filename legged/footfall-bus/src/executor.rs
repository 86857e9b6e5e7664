//! The robot-side executor: it carries a FootFall plan out on the robot's Controller, after
//! checking that the plan still fits the robot as it stands (plans made on the ground may
//! arrive long after, through a delayed link).

use tca_footfall::plan::FootfallPlan;
use tca_legged_messages::{BodyPose, LegMove, LegState, RobotModel as RobotModelQuery};
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Context, HandlerError, Module, ModuleError};

use crate::messages::FootfallExecute;

/// The executor module's name unless told otherwise.
pub const EXECUTOR_MODULE: &str = "footfall-exec";

/// How far the leg's joints may be from the plan's start, radians.
pub const START_TOLERANCE_RAD: f64 = 0.01;
/// How far the body may be from where the plan was made, metres.
pub const BODY_TOLERANCE_M: f64 = 0.05;

/// Why a plan does not fit the robot as it stands, or `None`.
async fn stale(ctx: &Context, plan: &FootfallPlan) -> Result<Option<String>, HandlerError> {
    let robot = ctx
        .query(&RobotModelQuery)
        .await
        .map_err(|e| HandlerError::new(format!("cannot ask the robot's description: {e}")))?;
    if robot.name != plan.robot {
        return Ok(Some(format!(
            "the plan is for robot {}, this is {}",
            plan.robot, robot.name
        )));
    }
    let state = ctx
        .query(&LegState {
            leg: plan.leg.clone(),
        })
        .await
        .map_err(|e| HandlerError::new(format!("cannot ask leg {}'s state: {e}", plan.leg)))?;
    if !state.stance {
        return Ok(Some(format!("leg {} is not standing", plan.leg)));
    }
    let off = state
        .joints
        .iter()
        .zip(&plan.start_joints)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    if state.joints.len() != plan.start_joints.len() || off > START_TOLERANCE_RAD {
        return Ok(Some(format!(
            "leg {} has moved since the plan was made (a joint {off:.3} rad from the plan's \
             start; at most {START_TOLERANCE_RAD} rad): plan again",
            plan.leg
        )));
    }
    let pose = ctx
        .query(&BodyPose)
        .await
        .map_err(|e| HandlerError::new(format!("cannot ask the body's pose: {e}")))?;
    let d = ((pose.x_m - plan.body_position[0]).powi(2)
        + (pose.y_m - plan.body_position[1]).powi(2)
        + (pose.z_m - plan.body_position[2]).powi(2))
    .sqrt();
    if d > BODY_TOLERANCE_M {
        return Ok(Some(format!(
            "the body has moved {d:.2} m since the plan was made (at most \
             {BODY_TOLERANCE_M} m): plan again"
        )));
    }
    Ok(None)
}

/// Connects the executor and serves until it is dropped or closed.
pub async fn connect_executor(connector: &Connector, name: &str) -> Result<Module, ModuleError> {
    Module::builder(name.to_owned())
        .replace(true)
        .handle(|ctx: Context, m: FootfallExecute| async move {
            let plan = m.plan;
            if let Some(why) = stale(&ctx, &plan).await? {
                tracing::warn!(leg = %plan.leg, %why, "a plan refused");
                return Err(HandlerError::new(format!("plan refused: {why}")));
            }
            tracing::info!(leg = %plan.leg, waypoints = plan.waypoints.len(), "carrying a plan out");
            let task = ctx
                .send_watched(
                    &LegMove {
                        leg: plan.leg.clone(),
                        waypoints: plan.leg_move_waypoints(),
                        transition: true,
                    },
                    [],
                )
                .map_err(|e| HandlerError::new(format!("cannot send the leg move: {e}")))?;
            match task.outcome().await {
                Ok(TaskOutcome::Achieved) => Ok(()),
                Ok(TaskOutcome::Failed(why)) => {
                    Err(HandlerError::new(format!("the leg move failed: {why}")))
                }
                Ok(TaskOutcome::Killed) => Err(HandlerError::new("the leg move was killed")),
                Err(e) => Err(HandlerError::new(format!("the leg move was lost: {e}"))),
            }
        })
        .connect(connector)
        .await
}
