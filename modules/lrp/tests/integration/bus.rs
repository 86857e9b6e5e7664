//! The Leg Recovery Planner module behind an in-process central, with fake LTM Manager and
//! Controller modules (the Controller runs the pure simulator on the true terrain):
//! `recoverLeg` sends a `legMove` that the leg executes without striking anything,
//! `legReachability` answers a binary map, and bad footfalls raise `moveFailed`.

use crate::common;

use std::sync::{Arc, Mutex};
use tca_testkit::within;

use common::footfall;
use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use tca_central::RunningCentral;
use tca_controller_sim::sim::{LegSimulator, StartPose};
use tca_lrp::{LrpConfig, MapValue, TerrainGrid};
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, HandlerError, Module};
use tca_robot::{Course, ElbowBranch, HeightField, JointPosition, LegParams};
use tca_single_leg_messages::{
    BodyPose, BodyPosition, GlobalLegPosition, JointLegPosition, Joints, LegMove, LegReachability,
    MapCell, MapGrid, MapKind, MapRegion, MoveFailed, MoveFailureKind, PlanePoint, RecoverLeg,
    WorldPoint,
};
use tokio::sync::mpsc;

/// A goal for the test's walker: send `recoverLeg` as a child and handle its exceptions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Attempt(RecoverLeg);
tca_messages::message!(Attempt: goal "testAttempt");

struct Scene {
    _central: RunningCentral,
    connector: Connector,
    sim: Arc<Mutex<LegSimulator>>,
    moves: mpsc::UnboundedReceiver<Result<(), String>>,
    _modules: Vec<Module>,
}

/// Central, a fake LTM Manager serving the true terrain, a fake Controller over the
/// simulator (foot planted at `foot`, carriage at `body_y`), and the LRP.
async fn scene(terrain: HeightField, body_y: f64, foot: Point2<f64>) -> Scene {
    let (central, connector) = tca_testkit::in_process_central().await;
    let branch = ElbowBranch::of(&common::planted(
        &terrain,
        body_y,
        foot,
        ElbowBranch::Positive,
    ));
    let sim = LegSimulator::new(
        LegParams::default(),
        terrain.clone(),
        StartPose::PlantedAt {
            carriage_y_m: body_y,
            foot_xy: foot,
            branch,
            force_n: 2224.1,
        },
    )
    .unwrap();
    let sim = Arc::new(Mutex::new(sim));
    let terrain = Arc::new(terrain);
    let ltm = Module::builder("ltm")
        .handle(move |_ctx, q: MapRegion| {
            let terrain = terrain.clone();
            async move {
                if q.kind != MapKind::Elevation {
                    return Err(HandlerError::new("this fake LTM serves elevation only"));
                }
                let cells = tca_lrp::polygon::region_grid(&q.polygon, q.resolution_m)?;
                let (lo, _) = cells.bounds();
                let hi = Point2::new(
                    lo.x + cells.nx() as f64 * q.resolution_m,
                    lo.y + cells.ny() as f64 * q.resolution_m,
                );
                let mut map =
                    TerrainGrid::elevation_from_height_field(&terrain, lo, hi, q.resolution_m)?;
                for (c, v) in map.grid_mut().iter_mut() {
                    if !cells.get(c).copied().unwrap_or(false) {
                        *v = MapValue::Unknown;
                    }
                }
                Ok(map.to_map_grid())
            }
        })
        .connect(&connector)
        .await
        .unwrap();
    let (tx, moves) = mpsc::unbounded_channel();
    let controller = {
        let (s1, s2, s3, s4) = (sim.clone(), sim.clone(), sim.clone(), sim.clone());
        Module::builder("controller")
            .handle(move |_ctx, _q: BodyPosition| {
                let p = s1.lock().unwrap().body_position();
                async move {
                    Ok(BodyPose {
                        y_m: p.y_m,
                        roll_rad: p.roll_rad,
                        pitch_rad: p.pitch_rad,
                    })
                }
            })
            .handle(move |_ctx, _q: JointLegPosition| {
                let q = s2.lock().unwrap().joint_leg_position();
                async move {
                    Ok(Joints {
                        shoulder_rad: q.shoulder_rad,
                        elbow_rad: q.elbow_rad,
                        vertical_m: q.vertical_m,
                    })
                }
            })
            .handle(move |_ctx, _q: GlobalLegPosition| {
                let p = s3.lock().unwrap().global_leg_position();
                async move {
                    Ok(WorldPoint {
                        x_m: p.x,
                        y_m: p.y,
                        z_m: p.z,
                    })
                }
            })
            .handle(move |_ctx, m: LegMove| {
                let wps: Vec<JointPosition> = m
                    .waypoints
                    .iter()
                    .map(|j| JointPosition::new(j.shoulder_rad, j.elbow_rad, j.vertical_m))
                    .collect();
                let result = s4
                    .lock()
                    .unwrap()
                    .leg_move(&wps, m.transition)
                    .map(|_| ())
                    .map_err(|e| e.to_string());
                let _ = tx.send(result.clone());
                async move { result.map_err(HandlerError::new) }
            })
            .connect(&connector)
            .await
            .unwrap()
    };
    let lrp = within(
        "lrp connects",
        tca_lrp::connect(&connector, LrpConfig::default()),
    )
    .await
    .unwrap();
    Scene {
        _central: central,
        connector,
        sim,
        moves,
        _modules: vec![ltm, controller, lrp],
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn recover_leg_moves_the_foot_around_the_sun_box() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let target = Point2::new(3.3, 3.4);
    let ff = footfall(&terrain, target);
    let mut s = scene(terrain, 2.0, Point2::new(3.3, 1.0)).await;
    let client = Module::builder("client")
        .connect(&s.connector)
        .await
        .unwrap();
    let task = client
        .send_watched(
            &RecoverLeg {
                footfall: WorldPoint {
                    x_m: ff.x,
                    y_m: ff.y,
                    z_m: ff.z,
                },
                body_y_m: 2.0,
                elbow: None,
                start_foot: None,
            },
            [],
        )
        .unwrap();
    let outcome = within("recoverLeg achieved", task.outcome()).await.unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    let executed = within("the legMove ran", s.moves.recv()).await.unwrap();
    assert_eq!(executed, Ok(()));
    let sim = s.sim.lock().unwrap();
    assert!(sim.foot_planted());
    let foot = sim.true_foot_position();
    assert!(
        (Point2::new(foot.x, foot.y) - target).norm() < 0.02,
        "{foot}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn leg_reachability_answers_a_binary_map() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let s = scene(terrain, 2.0, Point2::new(3.3, 1.0)).await;
    let client = Module::builder("client")
        .connect(&s.connector)
        .await
        .unwrap();
    let polygon = tca_lrp::polygon::rectangle(Point2::new(0.5, 2.0), Point2::new(5.5, 4.5));
    let map: MapGrid = within(
        "legReachability",
        client.query(&LegReachability {
            polygon: polygon.clone(),
            resolution_m: 0.1,
            body_y_m: 2.0,
            start_foot: None,
        }),
    )
    .await
    .unwrap();
    assert_eq!((map.nx, map.ny), (50, 25));
    let at = |x: f64, y: f64| {
        let ix = ((x - map.origin_x_m) / map.resolution_m).round() as usize;
        let iy = ((y - map.origin_y_m) / map.resolution_m).round() as usize;
        map.cells[iy * map.nx as usize + ix]
    };
    let known = |v: MapCell| match v {
        MapCell::Known { value, .. } => value,
        other => panic!("expected a known cell, got {other:?}"),
    };
    // On the sun box: unreachable; open sand ahead: reachable; beyond the links: not.
    assert_eq!(known(at(3.3, 2.15)), 0.0);
    assert_eq!(known(at(3.3, 3.45)), 1.0);
    assert_eq!(known(at(0.55, 4.45)), 0.0);
    // A triangle leaves the cells outside it unknown.
    let triangle = vec![
        PlanePoint { x_m: 0.5, y_m: 2.0 },
        PlanePoint { x_m: 5.5, y_m: 2.0 },
        PlanePoint { x_m: 0.5, y_m: 4.5 },
    ];
    let map = client
        .query(&LegReachability {
            polygon: triangle,
            resolution_m: 0.1,
            body_y_m: 2.0,
            start_foot: None,
        })
        .await
        .unwrap();
    assert_eq!(map.cells[map.cells.len() - 1], MapCell::Unknown);
    // A bad polygon is a clear failure.
    let err = client
        .query(&LegReachability {
            polygon: polygon[..2].to_vec(),
            resolution_m: 0.1,
            body_y_m: 2.0,
            start_foot: None,
        })
        .await
        .unwrap_err();
    assert!(err.to_string().contains("three finite corners"), "{err}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_blocked_footfall_raises_move_failed_and_moves_nothing() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let mut s = scene(terrain, 2.0, Point2::new(3.3, 1.0)).await;
    let (tx, mut failures) = mpsc::unbounded_channel();
    let _walker = Module::builder("walker")
        .handle(|ctx, a: Attempt| async move {
            let node = ctx.node().expect("a goal has a node");
            ctx.on_exception::<MoveFailed>(node).await?;
            ctx.goal(&a.0)?;
            Ok(())
        })
        .handle(move |_ctx, e: MoveFailed| {
            let _ = tx.send(e);
            async { Ok(()) }
        })
        .connect(&s.connector)
        .await
        .unwrap();
    let client = Module::builder("client")
        .connect(&s.connector)
        .await
        .unwrap();
    // Right beside the 1.2 m box: too close to a box the foot cannot lift over.
    client
        .goal(&Attempt(RecoverLeg {
            footfall: WorldPoint {
                x_m: 3.3,
                y_m: 2.75,
                z_m: 0.0,
            },
            body_y_m: 2.0,
            elbow: None,
            start_foot: None,
        }))
        .unwrap();
    let failure = within("moveFailed", failures.recv()).await.unwrap();
    assert_eq!(failure.command, "recoverLeg");
    assert_eq!(failure.kind, MoveFailureKind::Refused);
    assert!(
        failure.detail.contains("choose a footfall farther"),
        "{}",
        failure.detail
    );
    assert!((failure.foot.y_m - 1.0).abs() < 0.05, "{:?}", failure.foot);
    assert!(s.moves.try_recv().is_err(), "no legMove may be sent");
}
