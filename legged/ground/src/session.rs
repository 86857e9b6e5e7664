//! An operator's session from the ground: steps planned from the robot's state as it came
//! across, then sent one at a time as `legged.legMove` commands, each waited for.
//!
//! Each step moves one leg's foot `stride_m` along the body's x axis: up `lift_m` from where
//! it stands, over the target at that height, then down until it touches the ground (the
//! move's last segment ends at contact). The legs take turns in the description's order;
//! a leg's second turn brings it back, its third takes it forward again, so the robot stays
//! where it stands. All steps are planned at the start from one round of `legged.legState`
//! queries (the operator plans ahead instead of asking again before each step), on level
//! ground.

use std::time::Duration;

use nalgebra::{Point3, Vector3};
use serde::Serialize;
use tca_legged_messages::{LegMove, LegState, LegStateReply, RobotModel as AskModel};
use tca_legged_model::{IkOptions, RobotModel};
use tca_messages::control::TaskOutcome;
use tca_messages::now_ns;
use tca_module::Module;

use crate::error::GroundError;

/// How a session goes.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionOptions {
    /// Steps to take.
    pub steps: usize,
    /// How far each step moves a foot along the body's x axis, metres.
    pub stride_m: f64,
    /// How high a foot is lifted, metres.
    pub lift_m: f64,
    /// How long the first queries may take (across the bridge: twice the delay and more).
    pub query_timeout: Duration,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            steps: 10,
            stride_m: 0.10,
            lift_m: 0.20,
            query_timeout: Duration::from_secs(30),
        }
    }
}

/// One step as the operator saw it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepRecord {
    /// Its number, from 1.
    pub step: usize,
    /// The leg it moved.
    pub leg: String,
    /// When it was sent, nanoseconds since the UNIX epoch.
    pub sent_ns: u64,
    /// When its outcome came, nanoseconds since the UNIX epoch.
    pub ended_ns: u64,
    /// Whether it was achieved.
    pub achieved: bool,
    /// `achieved`, or why not.
    pub outcome: String,
}

impl StepRecord {
    /// From sending to the outcome, seconds.
    pub fn round_trip_s(&self) -> f64 {
        self.ended_ns.saturating_sub(self.sent_ns) as f64 / 1e9
    }
}

/// What a session did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SessionReport {
    /// The robot.
    pub robot: String,
    /// Every step.
    pub steps: Vec<StepRecord>,
    /// Steps achieved.
    pub achieved: usize,
}

/// The leg moves of a session, planned from the legs' states.
pub fn plan_steps(
    model: &RobotModel,
    states: &[LegStateReply],
    options: &SessionOptions,
) -> Result<Vec<LegMove>, GroundError> {
    if !(options.stride_m.is_finite() && options.lift_m.is_finite() && options.lift_m > 0.0) {
        return Err(GroundError::Setup(format!(
            "a stride of {} m and a lift of {} m: give finite distances, the lift above 0",
            options.stride_m, options.lift_m
        )));
    }
    let legs = model.legs();
    if legs.is_empty() {
        return Err(GroundError::Setup("the robot has no legs".into()));
    }
    let mut joints: Vec<Vec<f64>> = Vec::with_capacity(legs.len());
    for leg in legs {
        let state = states
            .iter()
            .find(|s| s.leg == leg.name())
            .ok_or_else(|| GroundError::Setup(format!("no state came for leg {}", leg.name())))?;
        joints.push(state.joints.clone());
    }
    let mut moves = Vec::with_capacity(options.steps);
    for step in 0..options.steps {
        let i = step % legs.len();
        let leg = &legs[i];
        let forward = (step / legs.len()).is_multiple_of(2);
        let dx = if forward {
            options.stride_m
        } else {
            -options.stride_m
        };
        let q = &joints[i];
        let foot = leg
            .foot_position(q)
            .map_err(|e| GroundError::Setup(e.to_string()))?;
        let solve = |target: Point3<f64>, from: &[f64]| {
            leg.inverse_kinematics(&target, &IkOptions::starting_at(from))
                .map(|s| s.joints)
                .map_err(|e| {
                    GroundError::Setup(format!(
                        "step {}: leg {} cannot reach ({:.3}, {:.3}, {:.3}) in the body frame: {e}",
                        step + 1,
                        leg.name(),
                        target.x,
                        target.y,
                        target.z
                    ))
                })
        };
        let up = Vector3::z() * options.lift_m;
        let ahead = Vector3::x() * dx;
        let lifted = solve(foot + up, q)?;
        let over = solve(foot + ahead + up, &lifted)?;
        // A little below the ground: the move ends where the foot touches it.
        let down = solve(foot + ahead - Vector3::z() * 0.05, &over)?;
        let placed = solve(foot + ahead, &over)?;
        moves.push(LegMove {
            leg: leg.name().to_owned(),
            waypoints: vec![lifted, over, down],
            transition: true,
        });
        joints[i] = placed;
    }
    Ok(moves)
}

/// Runs a session from `operator`, a module on the ground side: asks the robot's model and
/// legs, plans the steps, then sends each and waits for its outcome; `progress` hears of each
/// step as it ends. A step that fails ends the session there.
pub async fn run_session(
    operator: &Module,
    options: &SessionOptions,
    progress: impl Fn(&StepRecord),
) -> Result<SessionReport, GroundError> {
    let description = operator
        .query_with_timeout(&AskModel, options.query_timeout)
        .await?;
    let model = RobotModel::from_urdf_str(&description.urdf)
        .map_err(|e| GroundError::Setup(format!("the robot's description: {e}")))?;
    // One round trip for every leg's state.
    let queries: Vec<LegState> = description
        .legs
        .iter()
        .map(|leg| LegState { leg: leg.clone() })
        .collect();
    let asks = queries
        .iter()
        .map(|q| operator.query_with_timeout(q, options.query_timeout));
    let mut states = Vec::new();
    for s in futures::future::join_all(asks).await {
        states.push(s?);
    }
    let moves = plan_steps(&model, &states, options)?;
    let mut steps = Vec::with_capacity(moves.len());
    for (k, m) in moves.iter().enumerate() {
        let sent_ns = now_ns();
        let outcome = operator.send_watched(m, [])?.outcome().await?;
        let (achieved, outcome) = match outcome {
            TaskOutcome::Achieved => (true, "achieved".to_owned()),
            TaskOutcome::Failed(reason) => (false, reason),
            TaskOutcome::Killed => (false, "killed".to_owned()),
        };
        let record = StepRecord {
            step: k + 1,
            leg: m.leg.clone(),
            sent_ns,
            ended_ns: now_ns(),
            achieved,
            outcome,
        };
        progress(&record);
        steps.push(record);
        if !achieved {
            break;
        }
    }
    Ok(SessionReport {
        robot: description.name,
        achieved: steps.iter().filter(|s| s.achieved).count(),
        steps,
    })
}
