//! The simulated Controller behind an in-process central, driven by another module: every
//! query and command of §4.2, failures raised as exceptions, bad commands refused with the
//! leg left where it was, and queries answered while a move plays out.

use crate::common;

use common::{Client, builtin_fast, central, in_air, within};
use nalgebra::Point3;
use tca_controller_sim::SpeedFactor;
use tca_controller_sim::sim::{FaultConfig, LegSimulator};
use tca_messages::control::TaskOutcome;
use tca_module::Module;
use tca_robot::JointPosition;
use tca_single_leg_messages::{
    BodyMove, BodyPosition, CartLegPosition, ControllerStatus, GlobalLegPosition, JointLegPosition,
    Joints, LegMove, MoveFailureKind, ReadForce, SetTransForce,
};

fn to_joints(q: &JointPosition) -> Joints {
    Joints {
        shoulder_rad: q.shoulder_rad,
        elbow_rad: q.elbow_rad,
        vertical_m: q.vertical_m,
    }
}

/// The state visible over the bus.
#[derive(Debug, PartialEq)]
struct Seen {
    body_y_m: f64,
    joints: Joints,
    foot: [f64; 3],
    clock_s: f64,
}

async fn seen(client: &Module) -> Seen {
    let body = within("bodyPosition", client.query(&BodyPosition))
        .await
        .unwrap();
    let joints = within("jointLegPosition", client.query(&JointLegPosition))
        .await
        .unwrap();
    let foot = within("globalLegPosition", client.query(&GlobalLegPosition))
        .await
        .unwrap();
    let status = within("controllerStatus", client.query(&ControllerStatus))
        .await
        .unwrap();
    Seen {
        body_y_m: body.y_m,
        joints,
        foot: [foot.x_m, foot.y_m, foot.z_m],
        clock_s: status.clock_s,
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_query_answers_from_the_simulator() {
    let (central, connector) = central().await;
    let config = builtin_fast();
    let reference =
        LegSimulator::new(config.params.clone(), config.terrain.clone(), config.start).unwrap();
    let _controller = within(
        "controller connects",
        tca_controller_sim::connect(&connector, config),
    )
    .await
    .unwrap();
    let gait = Client::connect(&connector, "gait").await;

    let body = gait.module.query(&BodyPosition).await.unwrap();
    assert_eq!(body.y_m, reference.body_position().y_m);
    assert_eq!(body.y_m, 1.0);
    let joints = gait.module.query(&JointLegPosition).await.unwrap();
    assert_eq!(joints, to_joints(&reference.joint_leg_position()));
    let cart = gait.module.query(&CartLegPosition).await.unwrap();
    let c = reference.cart_leg_position();
    assert_eq!([cart.x_m, cart.y_m, cart.z_m], [c.x, c.y, c.z]);
    let foot = gait.module.query(&GlobalLegPosition).await.unwrap();
    assert!((foot.x_m - 3.8).abs() < 1e-9 && (foot.y_m - 1.2).abs() < 1e-9);
    // The planted foot reads the traction force (500 lb) upwards.
    let force = gait.module.query(&ReadForce).await.unwrap();
    assert!((force.force_n[2] - 2224.1).abs() < 1e-6, "{force:?}");
    let status = gait.module.query(&ControllerStatus).await.unwrap();
    assert!(status.foot_planted);
    assert_eq!(status.clock_s, 0.0);
    assert_eq!(status.collisions, 0);
    drop(central);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn commands_move_the_leg_in_simulated_time() {
    let (_central, connector) = central().await;
    let config = builtin_fast();
    // The same commands on a local simulator give the figures to expect.
    let mut reference =
        LegSimulator::new(config.params.clone(), config.terrain.clone(), config.start).unwrap();
    let _controller = tca_controller_sim::connect(&connector, config)
        .await
        .unwrap();
    let mut gait = Client::connect(&connector, "gait").await;

    let q = reference.joint_leg_position();
    let lifted = JointPosition {
        vertical_m: q.vertical_m - 0.3,
        ..q
    };
    // Lift the foot, set a transition force, put it down in transition mode, walk forward.
    let lift = LegMove {
        waypoints: vec![to_joints(&lifted)],
        transition: false,
    };
    assert_eq!(gait.run(lift).await, TaskOutcome::Achieved);
    reference.leg_move(&[lifted], false).unwrap();
    assert!(
        !gait
            .module
            .query(&ControllerStatus)
            .await
            .unwrap()
            .foot_planted
    );

    let force = SetTransForce { force_n: 1200.0 };
    assert_eq!(gait.run(force).await, TaskOutcome::Achieved);
    reference.set_trans_force(1200.0).unwrap();

    let place = LegMove {
        waypoints: vec![to_joints(&q)],
        transition: true,
    };
    assert_eq!(gait.run(place).await, TaskOutcome::Achieved);
    reference.leg_move(&[q], true).unwrap();
    let reading = gait.module.query(&ReadForce).await.unwrap();
    assert!((reading.force_n[2] - 1200.0).abs() < 1.0, "{reading:?}");

    assert_eq!(
        gait.run(BodyMove { target_y_m: 1.5 }).await,
        TaskOutcome::Achieved
    );
    reference.body_move(1.5).unwrap();

    let now = seen(&gait.module).await;
    assert!((now.body_y_m - 1.5).abs() <= 0.01);
    assert_eq!(now.body_y_m, reference.body_position().y_m);
    assert_eq!(now.joints, to_joints(&reference.joint_leg_position()));
    // Simulated time, exactly the simulator's (nothing waited: as fast as possible).
    assert_eq!(now.clock_s, reference.clock().as_secs_f64());
    assert!(now.clock_s > 20.0, "{}", now.clock_s);
    assert!(gait.no_exceptions());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn move_failures_raise_move_failed() {
    let (_central, connector) = central().await;
    let config = in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::AsFastAsPossible);
    let _controller = tca_controller_sim::connect(&connector, config)
        .await
        .unwrap();
    let mut gait = Client::connect(&connector, "gait").await;
    let q = gait.module.query(&JointLegPosition).await.unwrap();

    // A transition move that ends 30 cm above the ground: no contact.
    let short = LegMove {
        waypoints: vec![Joints {
            vertical_m: q.vertical_m + 0.5,
            ..q
        }],
        transition: true,
    };
    let reason = gait.fails(short).await;
    assert!(reason.contains("no ground contact"), "{reason}");
    let e = gait.next_move_failure().await;
    assert_eq!(e.command, "legMove");
    assert_eq!(e.kind, MoveFailureKind::NoContact);
    assert!((e.foot.z_m - 0.3).abs() < 1e-6, "{e:?}");

    // Straight down past the ground, not in transition mode: the foot strikes it.
    let strike = LegMove {
        waypoints: vec![Joints {
            vertical_m: q.vertical_m + 1.2,
            ..q
        }],
        transition: false,
    };
    let reason = gait.fails(strike).await;
    assert!(reason.contains("struck the terrain"), "{reason}");
    let e = gait.next_move_failure().await;
    assert_eq!(e.kind, MoveFailureKind::Collision);
    assert!(e.foot.z_m.abs() < 1e-3, "stopped at the ground: {e:?}");
    let status = gait.module.query(&ControllerStatus).await.unwrap();
    assert_eq!(status.collisions, 1);
    assert!(gait.no_exceptions());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hardware_faults_raise_hardware_fault() {
    let (_central, connector) = central().await;
    let faults = FaultConfig {
        force_drop_probability: 1.0,
        ..FaultConfig::none()
    };
    let config = builtin_fast().with_faults(faults);
    let _controller = tca_controller_sim::connect(&connector, config)
        .await
        .unwrap();
    let mut gait = Client::connect(&connector, "gait").await;
    let reason = gait.fails(BodyMove { target_y_m: 1.6 }).await;
    assert!(reason.starts_with("bodyMove: "), "{reason}");
    let fault = gait.next_hardware_fault().await;
    assert!(fault.detail.contains("force dropped"), "{fault:?}");
    assert!(gait.no_exceptions());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_commands_are_refused_and_the_leg_does_not_move() {
    let (_central, connector) = central().await;
    let _controller = tca_controller_sim::connect(&connector, builtin_fast())
        .await
        .unwrap();
    let mut gait = Client::connect(&connector, "gait").await;
    let before = seen(&gait.module).await;
    let q = before.joints;
    let leg = |waypoints: Vec<Joints>| LegMove {
        waypoints,
        transition: false,
    };
    let cases: Vec<(LegMove, &str)> = vec![
        (leg(vec![]), "at least one way-point"),
        (
            leg(vec![Joints {
                shoulder_rad: f64::NAN,
                ..q
            }]),
            "not a finite number",
        ),
        (
            leg(vec![
                Joints {
                    vertical_m: q.vertical_m - 0.1,
                    ..q
                },
                Joints {
                    shoulder_rad: 3.5,
                    ..q
                },
            ]),
            "way-point 1 is not reachable",
        ),
        (
            leg(vec![Joints {
                vertical_m: 5.0,
                ..q
            }]),
            "outside its limits",
        ),
        (
            leg(vec![Joints {
                elbow_rad: f64::INFINITY,
                ..q
            }]),
            "not a finite number",
        ),
    ];
    for (command, expected) in cases {
        let reason = gait.fails(command).await;
        assert!(reason.contains(expected), "{reason}");
        assert!(reason.contains("did not move"), "{reason}");
        let e = gait.next_move_failure().await;
        assert_eq!(e.kind, MoveFailureKind::Refused);
        assert_eq!(e.command, "legMove");
    }
    for (target_y_m, expected) in [
        (20.0, "beyond the rails"),
        (-1.0, "beyond the rails"),
        (f64::NAN, "not a finite number"),
    ] {
        let reason = gait.fails(BodyMove { target_y_m }).await;
        assert!(reason.contains(expected), "{reason}");
        let e = gait.next_move_failure().await;
        assert_eq!(
            (e.command.as_str(), e.kind),
            ("bodyMove", MoveFailureKind::Refused)
        );
    }
    for force_n in [f64::NAN, -5.0, 1e9] {
        let reason = gait.fails(SetTransForce { force_n }).await;
        assert!(reason.contains("transition force"), "{reason}");
    }
    // Nothing moved and no time passed.
    assert_eq!(seen(&gait.module).await, before);
    assert!(gait.no_exceptions());

    // A body move with the foot in the air is refused too.
    let lifted = LegMove {
        waypoints: vec![Joints {
            vertical_m: q.vertical_m - 0.2,
            ..q
        }],
        transition: false,
    };
    assert_eq!(gait.run(lifted).await, TaskOutcome::Achieved);
    let in_air = seen(&gait.module).await;
    let reason = gait.fails(BodyMove { target_y_m: 1.5 }).await;
    assert!(reason.contains("foot planted"), "{reason}");
    assert_eq!(
        gait.next_move_failure().await.kind,
        MoveFailureKind::Refused
    );
    assert_eq!(seen(&gait.module).await, in_air);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn queries_answer_while_a_move_plays_out() {
    let (_central, connector) = central().await;
    // Real time: lowering the foot 36 cm takes 10.7 s; the test only watches its start.
    let config = in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::real_time());
    let _controller = tca_controller_sim::connect(&connector, config)
        .await
        .unwrap();
    let gait = Client::connect(&connector, "gait").await;
    let q = gait.module.query(&JointLegPosition).await.unwrap();
    let target = q.vertical_m + 0.36;
    let task = gait
        .module
        .send_watched(
            &LegMove {
                waypoints: vec![Joints {
                    vertical_m: target,
                    ..q
                }],
                transition: false,
            },
            [],
        )
        .unwrap();
    let outcome = tokio::spawn(task.outcome());
    // Wait until the leg is seen moving.
    let moving = within("the leg starts moving", async {
        loop {
            let now = gait.module.query(&JointLegPosition).await.unwrap();
            if now.vertical_m > q.vertical_m {
                break now;
            }
            tokio::time::sleep(std::time::Duration::from_millis(5)).await;
        }
    })
    .await;
    assert!(moving.vertical_m < target, "{moving:?}");
    let foot = gait.module.query(&GlobalLegPosition).await.unwrap();
    assert!(foot.z_m < 0.8 && foot.z_m > 0.44, "{foot:?}");
    let status = gait.module.query(&ControllerStatus).await.unwrap();
    assert!(status.clock_s > 0.0 && status.clock_s < 10.72, "{status:?}");
    // The command is still running while the queries were answered.
    assert!(!outcome.is_finished());
    outcome.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn moves_advance_the_bus_simulated_time() {
    let (_central, connector) = central().await;
    let mut config = builtin_fast();
    config.bus_simulated_time = true;
    let _controller = tca_controller_sim::connect(&connector, config)
        .await
        .unwrap();
    let user = Module::builder("user")
        .simulated_time(true)
        .connect(&connector)
        .await
        .unwrap();
    assert_eq!(user.time_ns(), 0);
    let q = user.query(&JointLegPosition).await.unwrap();
    let lift = LegMove {
        waypoints: vec![Joints {
            vertical_m: q.vertical_m - 0.3,
            ..q
        }],
        transition: false,
    };
    let task = user.send_watched(&lift, []).unwrap();
    let outcome = within("legMove ends", task.outcome()).await.unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    // The user's clock moved on by the move's simulated duration, though nothing waited.
    let move_s = user.query(&ControllerStatus).await.unwrap().clock_s;
    assert!(move_s > 8.0, "{move_s}");
    let user_s = user.time_ns() as f64 / 1e9;
    assert!(
        (user_s - move_s).abs() < 1e-6,
        "user {user_s} s, move {move_s} s"
    );
}
