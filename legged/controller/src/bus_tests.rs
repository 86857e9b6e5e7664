//! The legged Controller behind an in-process central, driven by another module: queries,
//! a leg move and a body move with their informs, and a bad move raising moveFailed.

use std::sync::Arc;

use crate::{LeggedControllerConfig, connect};
use nalgebra::{Point2, Vector3};
use serde::{Deserialize, Serialize};
use tca_legged_messages::{
    BodyMove, BodyPose, FootContact, Halt, HardwareFault, LegMove, LegState, LeggedStatus,
    MoveFailed, MoveFailureKind, Resume, RobotModel as RobotModelQuery, SupportState,
};
use tca_legged_model::{BUILTIN_ROBOTS, IkOptions, RobotModel};
use tca_legged_sim::StartPose;
use tca_messages::control::TaskOutcome;
use tca_module::{HandlerError, Module};
use tca_robot::HeightField;
use tca_testkit::{in_process_central, within};
use tokio::sync::mpsc;

/// A command for the Controller, sent from the client's goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
enum Command {
    Leg(LegMove),
    Body(BodyMove),
}

/// The client's goal: handle the Controller's exceptions at its node and send one command
/// as its child.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Attempt {
    command: Command,
}
tca_messages::message!(Attempt: goal "test-legged-attempt");

struct Client {
    module: Module,
    failures: mpsc::UnboundedReceiver<MoveFailed>,
    faults: mpsc::UnboundedReceiver<HardwareFault>,
    contacts: mpsc::UnboundedReceiver<FootContact>,
    states: mpsc::UnboundedReceiver<SupportState>,
    outcomes: mpsc::UnboundedReceiver<TaskOutcome>,
}

impl Client {
    async fn connect(connector: &tca_module::Connector) -> Client {
        let (ftx, failures) = mpsc::unbounded_channel();
        let (htx, faults) = mpsc::unbounded_channel();
        let (ctx_, contacts) = mpsc::unbounded_channel();
        let (stx, states) = mpsc::unbounded_channel();
        let (otx, outcomes) = mpsc::unbounded_channel();
        let module = Module::builder("walker")
            .handle(move |_ctx, e: MoveFailed| {
                let _ = ftx.send(e);
                async { Ok(()) }
            })
            .handle(move |_ctx, e: HardwareFault| {
                let _ = htx.send(e);
                async { Ok(()) }
            })
            .handle(move |_ctx, c: FootContact| {
                let _ = ctx_.send(c);
                async { Ok(()) }
            })
            .handle(move |_ctx, s: SupportState| {
                let _ = stx.send(s);
                async { Ok(()) }
            })
            .handle(move |ctx, attempt: Attempt| {
                let otx = otx.clone();
                async move {
                    let node = ctx
                        .node()
                        .ok_or_else(|| HandlerError::new("a goal has a node"))?;
                    ctx.on_exception::<MoveFailed>(node).await?;
                    ctx.on_exception::<HardwareFault>(node).await?;
                    let task = match &attempt.command {
                        Command::Leg(m) => ctx.send_watched(m, []),
                        Command::Body(m) => ctx.send_watched(m, []),
                    }?;
                    tokio::spawn(async move {
                        if let Ok(outcome) = task.outcome().await {
                            let _ = otx.send(outcome);
                        }
                    });
                    Ok(())
                }
            });
        let module = within("walker connects", module.connect(connector))
            .await
            .expect("walker connects");
        Client {
            module,
            failures,
            faults,
            contacts,
            states,
            outcomes,
        }
    }

    async fn run(&mut self, command: Command) -> TaskOutcome {
        self.module.goal(&Attempt { command }).expect("goal sent");
        within("the command ends", self.outcomes.recv())
            .await
            .expect("outcome")
    }
}

fn config() -> LeggedControllerConfig {
    let model = Arc::new(RobotModel::builtin("hexapod").unwrap());
    let urdf = BUILTIN_ROBOTS
        .iter()
        .find(|r| r.name == "hexapod")
        .unwrap()
        .urdf;
    let ground = Arc::new(
        HeightField::flat(Point2::new(-1.5, -1.5), Point2::new(1.5, 1.5), 0.02, 0.0).unwrap(),
    );
    let start = StartPose {
        x_m: 0.0,
        y_m: 0.0,
        yaw_rad: 0.0,
    };
    LeggedControllerConfig::new(model, urdf, ground, start)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn moves_send_informs_and_a_bad_move_raises_move_failed() {
    let (_central, connector) = in_process_central().await;
    let config = config();
    let model = config.model.clone();
    let _controller = within("controller connects", connect(&connector, config))
        .await
        .unwrap();
    let mut walker = Client::connect(&connector).await;

    // Queries.
    let d = walker.module.query(&RobotModelQuery).await.unwrap();
    assert_eq!(d.name, "hexapod");
    assert_eq!(d.legs.len(), 6);
    assert!(d.urdf.contains("<robot"));
    let pose = walker.module.query(&BodyPose).await.unwrap();
    assert!((pose.z_m - model.neutral_height()).abs() < 1e-9);
    let leg = walker
        .module
        .query(&LegState {
            leg: "left_front".into(),
        })
        .await
        .unwrap();
    assert!(leg.stance && leg.force_n > 0.0);
    assert!(
        walker
            .module
            .query(&LegState { leg: "tail".into() })
            .await
            .is_err()
    );

    // A transition swing of the left front leg: up 3 cm, forward 3 cm, down to contact.
    let l = &model.legs()[0];
    let mut q = leg.joints.clone();
    let foot = l.foot_position(&q).unwrap();
    let waypoints: Vec<Vec<f64>> = [
        Vector3::new(0.0, 0.0, 0.03),
        Vector3::new(0.03, 0.0, 0.03),
        Vector3::new(0.03, 0.0, -0.01),
    ]
    .iter()
    .map(|d| {
        q = l
            .inverse_kinematics(&(foot + d), &IkOptions::starting_at(&q))
            .unwrap()
            .joints;
        q.clone()
    })
    .collect();
    let swing = LegMove {
        leg: "left_front".into(),
        waypoints,
        transition: true,
    };
    assert_eq!(walker.run(Command::Leg(swing)).await, TaskOutcome::Achieved);
    // The first command's state, the lift-off's, the one after the move, and the lift-off
    // and touch-down contacts. Central here keeps wall-clock time, so the walker's inform
    // handlers run concurrently and may see these in any order: tell them apart by content.
    let mut states = Vec::new();
    for what in ["first", "second", "third"] {
        states.push(
            within(what, walker.states.recv())
                .await
                .expect("a supportState"),
        );
    }
    let mut contacts = Vec::new();
    for what in ["first contact", "second contact"] {
        contacts.push(
            within(what, walker.contacts.recv())
                .await
                .expect("a footContact"),
        );
    }
    let first = states
        .iter()
        .find(|s| s.t_s == 0.0 && s.feet.iter().all(|f| f.stance))
        .expect("the first command's state, every foot standing");
    assert_eq!(first.feet.len(), 6);
    let lifted = states
        .iter()
        .find(|s| !s.feet[0].stance)
        .expect("the lift-off state");
    assert!(lifted.feet[1..].iter().all(|f| f.stance));
    let lift = contacts
        .iter()
        .find(|c| !c.stance)
        .expect("the lift-off contact");
    assert_eq!(lift.leg, "left_front");
    let down = contacts
        .iter()
        .find(|c| c.stance)
        .expect("the touch-down contact");
    assert_eq!(down.leg, "left_front");
    assert!(down.at.z_m.abs() < 1e-3);
    assert!(
        (down.at.x_m - lift.at.x_m - 0.03).abs() < 3e-3,
        "{lift:?} -> {down:?}"
    );
    let after = states
        .iter()
        .find(|s| s.t_s > 0.0)
        .expect("the state after the swing");
    assert!(after.feet[0].stance && after.margin_m > 0.0);

    // A body move 2 cm forward.
    let mut target = walker.module.query(&BodyPose).await.unwrap();
    target.x_m += 0.02;
    assert_eq!(
        walker.run(Command::Body(BodyMove { target })).await,
        TaskOutcome::Achieved
    );
    let moved = within("supportState after the body move", walker.states.recv())
        .await
        .unwrap();
    assert!((moved.body.x_m - 0.02).abs() < 1e-9);
    assert!(moved.t_s > after.t_s);

    // A bad move: an unknown leg.
    let bad = LegMove {
        leg: "tail".into(),
        waypoints: vec![vec![0.0; 3]],
        transition: false,
    };
    let outcome = walker.run(Command::Leg(bad)).await;
    assert!(matches!(outcome, TaskOutcome::Failed(_)), "{outcome:?}");
    let failure = within("moveFailed", walker.failures.recv()).await.unwrap();
    assert_eq!(failure.command, "legged.legMove");
    assert_eq!(failure.kind, MoveFailureKind::Refused);
    assert_eq!(failure.leg.as_deref(), Some("tail"));
    assert!(
        failure.detail.contains("no leg `tail`"),
        "{}",
        failure.detail
    );

    // A body move far beyond the legs' reach: a joint limit, nothing moved.
    let mut far = walker.module.query(&BodyPose).await.unwrap();
    far.z_m += 1.0;
    let outcome = walker.run(Command::Body(BodyMove { target: far })).await;
    assert!(matches!(outcome, TaskOutcome::Failed(_)));
    let failure = within("moveFailed", walker.failures.recv()).await.unwrap();
    assert_eq!(failure.command, "legged.bodyMove");
    assert_eq!(failure.kind, MoveFailureKind::JointLimit);

    let status = walker.module.query(&LeggedStatus).await.unwrap();
    assert_eq!(status.moves, 2);
    assert_eq!(status.collisions, 0);
    assert_eq!(status.falls, 0);
    assert!(!status.fallen);
    assert!((status.clock_s - moved.t_s).abs() < 1e-12);
}

/// The emergency stop: after `legged.halt` every move is refused with a hardware fault that
/// says how to resume, nothing moves, and after `legged.resume` moves are carried out again.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_emergency_stop_refuses_every_move_until_resumed() {
    let (_central, connector) = in_process_central().await;
    let _controller = within("controller connects", connect(&connector, config()))
        .await
        .unwrap();
    let mut walker = Client::connect(&connector).await;
    let halt = walker.module.send_watched(&Halt, []).unwrap();
    assert_eq!(
        within("the halt ends", halt.outcome()).await.unwrap(),
        TaskOutcome::Achieved
    );
    let before = walker.module.query(&BodyPose).await.unwrap();
    let mut target = before;
    target.x_m += 0.02;
    match walker.run(Command::Body(BodyMove { target })).await {
        TaskOutcome::Failed(reason) => assert!(
            reason.contains("emergency stop") && reason.contains("legged.resume"),
            "{reason}"
        ),
        other => panic!("a move while halted: {other:?}"),
    }
    let fault = within("the hardware fault", walker.faults.recv())
        .await
        .expect("a hardwareFault");
    assert!(
        fault.leg.is_none() && fault.detail.contains("legged.halt"),
        "{fault:?}"
    );
    assert_eq!(walker.module.query(&BodyPose).await.unwrap(), before);
    let resume = walker.module.send_watched(&Resume, []).unwrap();
    assert_eq!(
        within("the resume ends", resume.outcome()).await.unwrap(),
        TaskOutcome::Achieved
    );
    assert_eq!(
        walker.run(Command::Body(BodyMove { target })).await,
        TaskOutcome::Achieved
    );
    let after = walker.module.query(&BodyPose).await.unwrap();
    assert!((after.x_m - before.x_m - 0.02).abs() < 1e-9);
}
