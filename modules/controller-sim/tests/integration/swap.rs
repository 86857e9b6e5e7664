//! Swapping the Controller: any module that registers the Controller's
//! messages replaces it, and the modules that use it do not change. Here a trivial "replay"
//! Controller answering fixed poses takes over from the simulator, then a restarted
//! simulator takes over back, while the same client code keeps running.

use crate::common;

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};

use common::{Client, builtin_fast, central, within};
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module, ModuleError};
use tca_single_leg_messages::{
    BodyMove, BodyPose, BodyPosition, CarriagePoint, CartLegPosition, ControllerState,
    ControllerStatus, ForceReading, GlobalLegPosition, JointLegPosition, Joints, LegMove,
    ReadForce, SetTransForce, WorldPoint,
};

/// The names of every message the Controller handles.
const CONTROLLER_MESSAGES: [&str; 9] = [
    "bodyMove",
    "legMove",
    "setTransForce",
    "bodyPosition",
    "jointLegPosition",
    "cartLegPosition",
    "globalLegPosition",
    "readForce",
    "controllerStatus",
];

/// A Controller that does not simulate anything: it answers fixed poses and accepts every
/// command, counting them.
async fn replay(connector: &Connector, commands: Arc<AtomicU32>) -> Result<Module, ModuleError> {
    let joints = Joints {
        shoulder_rad: 0.1,
        elbow_rad: 0.2,
        vertical_m: 3.3,
    };
    let count = |commands: &Arc<AtomicU32>| {
        let commands = commands.clone();
        move || {
            commands.fetch_add(1, Ordering::SeqCst);
        }
    };
    let (c1, c2, c3) = (count(&commands), count(&commands), count(&commands));
    Module::builder("replay")
        .replace(true)
        .handle(move |_ctx, _m: LegMove| {
            c1();
            async { Ok(()) }
        })
        .handle(move |_ctx, _m: BodyMove| {
            c2();
            async { Ok(()) }
        })
        .handle(move |_ctx, _m: SetTransForce| {
            c3();
            async { Ok(()) }
        })
        .handle(|_ctx, _q: BodyPosition| async {
            Ok(BodyPose {
                y_m: 7.0,
                roll_rad: 0.0,
                pitch_rad: 0.0,
            })
        })
        .handle(move |_ctx, _q: JointLegPosition| async move { Ok(joints) })
        .handle(|_ctx, _q: CartLegPosition| async {
            Ok(CarriagePoint {
                x_m: 1.0,
                y_m: 1.0,
                z_m: -3.3,
            })
        })
        .handle(|_ctx, _q: GlobalLegPosition| async {
            Ok(WorldPoint {
                x_m: 4.0,
                y_m: 8.0,
                z_m: 0.7,
            })
        })
        .handle(|_ctx, _q: ReadForce| async {
            Ok(ForceReading {
                force_n: [0.0; 3],
                moment_n_m: [0.0; 3],
            })
        })
        .handle(|_ctx, _q: ControllerStatus| async {
            Ok(ControllerState {
                clock_s: 42.0,
                foot_planted: false,
                collisions: 0,
            })
        })
        .connect(connector)
        .await
}

/// The walking system's side: what it sees of the Controller and one step it commands. The
/// same code runs against every implementation.
async fn look_and_step(client: &Module) -> (f64, WorldPoint, f64, TaskOutcome) {
    let body = within("bodyPosition", client.query(&BodyPosition))
        .await
        .unwrap();
    let foot = within("globalLegPosition", client.query(&GlobalLegPosition))
        .await
        .unwrap();
    let joints = within("jointLegPosition", client.query(&JointLegPosition))
        .await
        .unwrap();
    let lift = LegMove {
        waypoints: vec![Joints {
            vertical_m: joints.vertical_m - 0.05,
            ..joints
        }],
        transition: false,
    };
    let task = client.send_watched(&lift, []).unwrap();
    let outcome = within("legMove ends", task.outcome()).await.unwrap();
    let status = within("controllerStatus", client.query(&ControllerStatus))
        .await
        .unwrap();
    (body.y_m, foot, status.clock_s, outcome)
}

/// Which module handles each Controller message, per central's registry.
async fn handlers(client: &Module) -> Vec<String> {
    let registry = within("registry", client.registry()).await.unwrap();
    CONTROLLER_MESSAGES
        .iter()
        .map(|name| {
            registry
                .entries
                .iter()
                .find(|e| e.name.as_str() == *name)
                .map(|e| e.handler.to_string())
                .unwrap_or_else(|| panic!("{name} is not registered"))
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_controller_takes_over_and_the_client_is_unchanged() {
    let (_central, connector) = central().await;
    let simulator = tca_controller_sim::connect(&connector, builtin_fast())
        .await
        .unwrap();
    let mut gait = Client::connect(&connector, "gait").await;

    // The simulator answers.
    assert_eq!(handlers(&gait.module).await, vec!["controller"; 9]);
    let (body_y, foot, clock_s, outcome) = look_and_step(&gait.module).await;
    assert_eq!(body_y, 1.0);
    assert!((foot.x_m - 3.8).abs() < 1e-9);
    assert!(clock_s > 1.0, "the lift took simulated time: {clock_s}");
    assert_eq!(outcome, TaskOutcome::Achieved);

    // The replay Controller registers the same messages with replace: it takes over.
    let commands = Arc::new(AtomicU32::new(0));
    let _replay = replay(&connector, commands.clone()).await.unwrap();
    assert_eq!(handlers(&gait.module).await, vec!["replay"; 9]);
    let (body_y, foot, clock_s, outcome) = look_and_step(&gait.module).await;
    assert_eq!(body_y, 7.0);
    assert_eq!((foot.x_m, foot.y_m, foot.z_m), (4.0, 8.0, 0.7));
    assert_eq!(clock_s, 42.0);
    assert_eq!(outcome, TaskOutcome::Achieved);
    assert_eq!(commands.load(Ordering::SeqCst), 1);

    // The simulator, still connected, no longer gets the Controller's messages; a restarted
    // simulator takes them back (from where a fresh start puts the leg).
    assert!(!simulator.is_closed());
    simulator.close().await;
    let _restarted = tca_controller_sim::connect(&connector, builtin_fast())
        .await
        .unwrap();
    assert_eq!(handlers(&gait.module).await, vec!["controller"; 9]);
    let (body_y, foot, _, outcome) = look_and_step(&gait.module).await;
    assert_eq!(body_y, 1.0);
    assert!((foot.x_m - 3.8).abs() < 1e-9);
    assert_eq!(outcome, TaskOutcome::Achieved);
    assert_eq!(commands.load(Ordering::SeqCst), 1);
    assert!(gait.no_exceptions());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_replace_a_second_controller_is_refused() {
    let (_central, connector) = central().await;
    let _simulator = tca_controller_sim::connect(&connector, builtin_fast())
        .await
        .unwrap();
    let mut second = builtin_fast().with_module_name("controller-2");
    second.replace = false;
    let err = tca_controller_sim::connect(&connector, second)
        .await
        .unwrap_err();
    assert!(
        err.to_string()
            .contains("already handled by module controller"),
        "{err}"
    );
}
