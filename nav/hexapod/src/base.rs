//! The walking robot as a [`Base`] in one process: the stepper's moves carried out on the
//! quasi-static legged simulator directly, as the legged Controller would carry them out.

use std::sync::Arc;

use tca_free_gait::{Action, GaitState, LegGaitState};
use tca_legged_messages::{LegStateReply, Pose};
use tca_legged_model::RobotModel;
use tca_legged_sim::{
    LeggedSim, MoveError, SimParams, StartPose, isometry_to_pose, pose_to_isometry,
};
use tca_nav_navigator::{Base, Motion};
use tca_nav_sensing::{Attitude, Pose2};
use tca_robot::HeightField;

use crate::stepper::{Stepper, StepperParams, WalkEnd};

/// Why a walking base could not be made.
#[derive(Debug, thiserror::Error)]
pub enum HexapodError {
    /// The robot cannot stand at the start.
    #[error("the robot cannot stand at the start: {0}")]
    Start(#[from] tca_legged_sim::SimError),
}

/// The simulator's settings for a navigating walking robot: its own defaults, except that
/// a move that would leave it unstable is carried out and tips it over rather than being
/// refused, so that a fall is a fall.
pub fn nav_sim_params(model: &RobotModel) -> SimParams {
    SimParams {
        refuse_unstable_moves: false,
        ..SimParams::for_model(model)
    }
}

/// The state the stepper plans from, made from what the Controller reports: the body's
/// pose and each leg's state (exactly what `legged.bodyPose` and `legged.legState` carry).
pub fn gait_state(body: &Pose, legs: &[LegStateReply]) -> GaitState {
    GaitState {
        body: pose_to_isometry(body),
        legs: legs
            .iter()
            .map(|l| LegGaitState {
                joints: l.joints.clone(),
                stance: l.stance,
                foot: nalgebra::Point3::new(l.foot.x_m, l.foot.y_m, l.foot.z_m),
            })
            .collect(),
    }
}

/// A body pose as its planar pose and its height and tilt.
pub fn split_pose(p: &Pose) -> (Pose2, Attitude) {
    (
        Pose2::new(p.x_m, p.y_m, p.yaw_rad),
        Attitude {
            z_m: p.z_m,
            roll_rad: p.roll_rad,
            pitch_rad: p.pitch_rad,
        },
    )
}

/// A walking robot driven by forward and turn speeds, on the legged simulator.
#[derive(Debug, Clone)]
pub struct HexapodBase {
    name: String,
    sim: LeggedSim,
    stepper: Arc<Stepper>,
    stalls: u64,
}

impl HexapodBase {
    /// The robot `model` stood up at `start` on `terrain`, walking with `params`.
    pub fn new(
        model: Arc<RobotModel>,
        terrain: Arc<HeightField>,
        start: Pose2,
        params: StepperParams,
    ) -> Result<Self, HexapodError> {
        let sim = LeggedSim::new(
            model.clone(),
            terrain.clone(),
            StartPose {
                x_m: start.x,
                y_m: start.y,
                yaw_rad: start.yaw,
            },
            nav_sim_params(&model),
        )?;
        Ok(Self {
            name: model.name().to_string(),
            stepper: Arc::new(Stepper::new(model, terrain, params)),
            sim,
            stalls: 0,
        })
    }

    /// The simulator (its clock, counters and state).
    pub fn sim(&self) -> &LeggedSim {
        &self.sim
    }

    /// Drive commands whose walk ended short of its target because no move could be
    /// found.
    pub fn stalls(&self) -> u64 {
        self.stalls
    }

    /// The body pose as the Controller reports it.
    fn body(&self) -> Pose {
        isometry_to_pose(&self.sim.body())
    }

    /// The state as the Controller reports it.
    fn state(&self) -> GaitState {
        let legs: Vec<LegStateReply> = self
            .sim
            .model()
            .legs()
            .iter()
            .filter_map(|l| self.sim.leg_state(l.name()).ok())
            .collect();
        gait_state(&self.body(), &legs)
    }

    /// Carries out one move as the Controller would (the body's target through the bus's
    /// pose, as `legged.bodyMove` carries it).
    fn execute(&mut self, action: &Action) -> Result<(), MoveError> {
        match action {
            Action::Swing { leg, waypoints, .. } | Action::Reach { leg, waypoints } => {
                let name = self.sim.model().legs()[*leg].name().to_string();
                let transition = matches!(action, Action::Swing { .. });
                self.sim.leg_move(&name, waypoints, transition).map(|_| ())
            }
            Action::Body { target } => {
                let target = pose_to_isometry(&isometry_to_pose(target));
                self.sim.body_move(&target).map(|_| ())
            }
        }
    }
}

impl Base for HexapodBase {
    fn name(&self) -> &str {
        &self.name
    }

    fn true_pose(&self) -> Pose2 {
        split_pose(&self.body()).0
    }

    fn attitude(&self) -> Attitude {
        split_pose(&self.body()).1
    }

    fn drive(&mut self, forward_mps: f64, turn_rps: f64, dt_s: f64) -> Motion {
        let before = self.sim.counters();
        let stepper = self.stepper.clone();
        let mut walk = stepper.walk(&self.state(), forward_mps, turn_rps, dt_s);
        while let Some(actions) = walk.next(&stepper, &self.state()) {
            for action in &actions {
                if let Err(e) = self.execute(action) {
                    tracing::debug!(error = %e, "a move failed; planning again from where the robot is");
                    walk.failed();
                    break;
                }
            }
        }
        if let Some(WalkEnd::Stuck(why)) = walk.end() {
            self.stalls += 1;
            tracing::warn!(%why, "the walking base found no move toward its target");
        }
        let after = self.sim.counters();
        Motion {
            pose: self.true_pose(),
            collided: after.collisions > before.collisions,
            fell: after.falls > before.falls,
        }
    }
}
