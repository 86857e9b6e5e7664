//! Helpers of the bus tests: an in-process central, bounded waits, a client module that
//! sends the Controller's commands from a goal and handles their exceptions, and
//! configurations.

#![allow(dead_code, unreachable_pub)]

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};
use tca_controller_sim::sim::StartPose;
use tca_controller_sim::{ControllerConfig, SpeedFactor};
use tca_messages::NodeId;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, HandlerError, Module};
use tca_robot::{CarriagePose, ElbowBranch, HeightField, LegKinematics, LegParams};
use tca_single_leg_messages::{BodyMove, HardwareFault, LegMove, MoveFailed, SetTransForce};
use tokio::sync::mpsc;

pub use tca_testkit::{in_process_central as central, within};

/// A command for the Controller, sent by the client's [`Attempt`] goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// `legMove`.
    Leg(LegMove),
    /// `bodyMove`.
    Body(BodyMove),
    /// `setTransForce`.
    Force(SetTransForce),
}

impl From<LegMove> for Command {
    fn from(m: LegMove) -> Self {
        Command::Leg(m)
    }
}

impl From<BodyMove> for Command {
    fn from(m: BodyMove) -> Self {
        Command::Body(m)
    }
}

impl From<SetTransForce> for Command {
    fn from(m: SetTransForce) -> Self {
        Command::Force(m)
    }
}

/// The client's own goal: attach exception handlers at its node, send one command to the
/// Controller as its child, report how the command ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Attempt {
    /// The command.
    pub command: Command,
}
tca_messages::message!(Attempt: goal "test-attempt");

/// An exception the client handled, with where it was raised.
#[derive(Clone, Debug, PartialEq)]
pub struct Caught<E> {
    /// The exception.
    pub exception: E,
    /// The node it was raised at (the Controller's command).
    pub raised_at: Option<NodeId>,
    /// The node the client's handler was attached at (its `Attempt` goal).
    pub attached_at: Option<NodeId>,
}

/// A client module (the walking system's side) that sends the Controller's commands from a
/// goal of its own and handles the exceptions they raise, as the Gait Planner does.
pub struct Client {
    pub module: Module,
    moves: mpsc::UnboundedReceiver<Caught<MoveFailed>>,
    faults: mpsc::UnboundedReceiver<Caught<HardwareFault>>,
    outcomes: mpsc::UnboundedReceiver<TaskOutcome>,
}

impl Client {
    pub async fn connect(connector: &Connector, name: &str) -> Client {
        let (move_tx, moves) = mpsc::unbounded_channel();
        let (fault_tx, faults) = mpsc::unbounded_channel();
        let (outcome_tx, outcomes) = mpsc::unbounded_channel();
        let module = within(
            "client connects",
            Module::builder(name)
                .handle(move |ctx, exception: MoveFailed| {
                    let _ = move_tx.send(Caught {
                        exception,
                        raised_at: ctx.origin(),
                        attached_at: ctx.node(),
                    });
                    async { Ok(()) }
                })
                .handle(move |ctx, exception: HardwareFault| {
                    let _ = fault_tx.send(Caught {
                        exception,
                        raised_at: ctx.origin(),
                        attached_at: ctx.node(),
                    });
                    async { Ok(()) }
                })
                .handle(move |ctx, attempt: Attempt| {
                    let outcome_tx = outcome_tx.clone();
                    async move {
                        let node = ctx
                            .node()
                            .ok_or_else(|| HandlerError::new("a goal has a node"))?;
                        ctx.on_exception::<MoveFailed>(node).await?;
                        ctx.on_exception::<HardwareFault>(node).await?;
                        let task = match &attempt.command {
                            Command::Leg(m) => ctx.send_watched(m, []),
                            Command::Body(m) => ctx.send_watched(m, []),
                            Command::Force(m) => ctx.send_watched(m, []),
                        }?;
                        // Wait for the outcome outside the handler: a failed child fails this
                        // goal too, and central then cancels a handler still running.
                        tokio::spawn(async move {
                            if let Ok(outcome) = task.outcome().await {
                                let _ = outcome_tx.send(outcome);
                            }
                        });
                        Ok(())
                    }
                })
                .connect(connector),
        )
        .await
        .expect("client connects");
        Client {
            module,
            moves,
            faults,
            outcomes,
        }
    }

    /// Sends `command` to the Controller from an [`Attempt`] goal and waits for how the
    /// command ends.
    pub async fn run(&mut self, command: impl Into<Command>) -> TaskOutcome {
        let attempt = Attempt {
            command: command.into(),
        };
        self.module.goal(&attempt).expect("goal sent");
        within("the command ends", self.outcomes.recv())
            .await
            .expect("outcome channel open")
    }

    /// Like [`run`](Self::run), expecting a failure; returns its reason.
    pub async fn fails(&mut self, command: impl Into<Command>) -> String {
        match self.run(command).await {
            TaskOutcome::Failed(reason) => reason,
            other => panic!("expected the command to fail, got {other:?}"),
        }
    }

    pub async fn next_move_failure(&mut self) -> MoveFailed {
        let caught = within("a moveFailed exception", self.moves.recv())
            .await
            .expect("exception channel open");
        assert_raised_below(caught.raised_at, caught.attached_at);
        caught.exception
    }

    pub async fn next_hardware_fault(&mut self) -> HardwareFault {
        let caught = within("a hardwareFault exception", self.faults.recv())
            .await
            .expect("exception channel open");
        assert_raised_below(caught.raised_at, caught.attached_at);
        caught.exception
    }

    /// No exception arrived so far.
    pub fn no_exceptions(&mut self) -> bool {
        self.moves.try_recv().is_err() && self.faults.try_recv().is_err()
    }
}

/// The exception came from the command's node, below the goal it was attached at.
fn assert_raised_below(raised_at: Option<NodeId>, attached_at: Option<NodeId>) {
    assert!(raised_at.is_some(), "raised in a task node");
    assert!(attached_at.is_some(), "delivered at the attachment node");
    assert_ne!(
        raised_at, attached_at,
        "raised by the command, not the goal"
    );
}

/// Flat ground at z = 0 over the whole pit.
pub fn flat() -> HeightField {
    HeightField::flat(Point2::origin(), Point2::new(6.0, 11.0), 0.02, 0.0).expect("flat ground")
}

/// Flat ground, the carriage at y = 2 m and the foot in the air at world `foot`.
pub fn in_air(foot: Point3<f64>, speed: SpeedFactor) -> ControllerConfig {
    let params = LegParams::default();
    let joints = LegKinematics::new(&params)
        .inverse_world(&CarriagePose::level(2.0), &foot, ElbowBranch::Positive)
        .expect("reachable start");
    ControllerConfig::new(
        flat(),
        StartPose::Joints {
            carriage_y_m: 2.0,
            joints,
        },
    )
    .with_speed(speed)
}

/// The built-in configuration (course 1, foot planted at (3.8, 1.2) m), as fast as possible.
pub fn builtin_fast() -> ControllerConfig {
    ControllerConfig::builtin()
        .expect("built-in configuration")
        .with_speed(SpeedFactor::AsFastAsPossible)
}
