//! The Gait Planner module behind an in-process central, with the real Leg Recovery
//! Planner module, a fake LTM Manager serving the true terrain's maps and a fake Controller
//! running the simulator: `planStep` sends `recoverLeg` and a `bodyMove` that starts only
//! after the leg move is achieved, informs `stepPlanned`, and fails clearly on bad input.

use std::sync::{Arc, Mutex};
use tca_testkit::within;

use nalgebra::Point2;
use tca_central::RunningCentral;
use tca_controller_sim::sim::{LegSimulator, StartPose};
use tca_gait_planner::{GaitConfig, synthetic};
use tca_lrp::{LrpConfig, MapValue, TerrainGrid};
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, HandlerError, Module};
use tca_robot::{Course, ElbowBranch, HeightField, JointPosition, LegParams};
use tca_single_leg_messages::{
    BodyMove, BodyPose, BodyPosition, GlobalLegPosition, JointLegPosition, Joints, LegMove,
    MapKind, MapRegion, PlanStep, StepPlanned, WorldPoint,
};
use tokio::sync::mpsc;

/// What the fake Controller executed, in order.
#[derive(Debug, Clone, PartialEq)]
enum Executed {
    Leg(Result<(), String>),
    Body(Result<f64, String>),
}

struct Scene {
    _central: RunningCentral,
    connector: Connector,
    sim: Arc<Mutex<LegSimulator>>,
    executed: mpsc::UnboundedReceiver<Executed>,
    planned: mpsc::UnboundedReceiver<StepPlanned>,
    _modules: Vec<Module>,
}

async fn scene(terrain: HeightField, body_y: f64, foot: Point2<f64>) -> Scene {
    let (central, connector) = tca_testkit::in_process_central().await;
    let sim = LegSimulator::new(
        LegParams::default(),
        terrain.clone(),
        StartPose::PlantedAt {
            carriage_y_m: body_y,
            foot_xy: foot,
            branch: ElbowBranch::Positive,
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
                let cells = tca_lrp::polygon::region_grid(&q.polygon, q.resolution_m)?;
                let (lo, _) = cells.bounds();
                let hi = Point2::new(
                    lo.x + cells.nx() as f64 * q.resolution_m,
                    lo.y + cells.ny() as f64 * q.resolution_m,
                );
                let mut map: TerrainGrid = match q.kind {
                    MapKind::Elevation => {
                        synthetic::elevation_map(&terrain, lo, hi, q.resolution_m)?
                    }
                    MapKind::Footfall => {
                        synthetic::footfall_map(&terrain, lo, hi, q.resolution_m, 0.15)?
                    }
                    other => return Err(HandlerError::new(format!("no {other:?} maps here"))),
                };
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
    let (tx, executed) = mpsc::unbounded_channel();
    let tx2 = tx.clone();
    let (s1, s2, s3, s4, s5) = (
        sim.clone(),
        sim.clone(),
        sim.clone(),
        sim.clone(),
        sim.clone(),
    );
    let controller = Module::builder("controller")
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
            let r = s4
                .lock()
                .unwrap()
                .leg_move(&wps, m.transition)
                .map(|_| ())
                .map_err(|e| e.to_string());
            let _ = tx.send(Executed::Leg(r.clone()));
            async move { r.map_err(HandlerError::new) }
        })
        .handle(move |_ctx, m: BodyMove| {
            let r = {
                let mut sim = s5.lock().unwrap();
                sim.body_move(m.target_y_m)
                    .map(|_| sim.body_position().y_m)
                    .map_err(|e| e.to_string())
            };
            let _ = tx2.send(Executed::Body(r.clone()));
            async move { r.map(|_| ()).map_err(HandlerError::new) }
        })
        .connect(&connector)
        .await
        .unwrap();
    let (ptx, planned) = mpsc::unbounded_channel();
    let display = Module::builder("display")
        .handle(move |_ctx, s: StepPlanned| {
            let _ = ptx.send(s);
            async { Ok(()) }
        })
        .connect(&connector)
        .await
        .unwrap();
    let lrp = tca_lrp::connect(&connector, LrpConfig::default())
        .await
        .unwrap();
    let gait = tca_gait_planner::connect(&connector, GaitConfig::default())
        .await
        .unwrap();
    Scene {
        _central: central,
        connector,
        sim,
        executed,
        planned,
        _modules: vec![ltm, controller, display, lrp, gait],
    }
}

async fn plan_step(client: &Module, step: u32, goal_y_m: f64) -> TaskOutcome {
    let task = client
        .send_watched(
            &PlanStep {
                step,
                goal_y_m,
                mode: tca_single_leg_messages::WalkMode::Sequential,
                start: None,
                after_body_move: None,
            },
            [],
        )
        .unwrap();
    within("planStep ends", task.outcome()).await.unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn plan_step_moves_the_leg_then_the_body() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let mut s = scene(terrain, 1.0, Point2::new(3.8, 0.6)).await;
    let client = Module::builder("client")
        .connect(&s.connector)
        .await
        .unwrap();
    assert_eq!(plan_step(&client, 1, 9.5).await, TaskOutcome::Achieved);
    let first = within("leg move", s.executed.recv()).await.unwrap();
    let second = within("body move", s.executed.recv()).await.unwrap();
    assert_eq!(first, Executed::Leg(Ok(())));
    let Executed::Body(Ok(y)) = second else {
        panic!("expected the body move second, got {second:?}");
    };
    let planned = within("stepPlanned", s.planned.recv()).await.unwrap();
    assert_eq!(planned.step, 1);
    assert!(
        (planned.body_target_y_m - y).abs() < 0.02,
        "{planned:?} vs {y}"
    );
    assert!(y > 2.0, "the carriage advanced to {y}");
    let sim = s.sim.lock().unwrap();
    let foot = sim.true_foot_position();
    assert!(
        (Point2::new(foot.x, foot.y) - Point2::new(planned.footfall.x_m, planned.footfall.y_m))
            .norm()
            < 0.05,
        "foot {foot} vs footfall {:?}",
        planned.footfall
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn steps_walk_course_2_to_the_goal() {
    let terrain = Course::builtin(2).unwrap().height_field().unwrap();
    let s = scene(terrain, 1.0, Point2::new(2.4, 1.2)).await;
    let client = Module::builder("client")
        .connect(&s.connector)
        .await
        .unwrap();
    let goal = 6.0;
    let mut steps = 0;
    while (s.sim.lock().unwrap().body_position().y_m - goal).abs() > 0.02 {
        steps += 1;
        assert!(steps <= 6, "not at the goal after 5 steps");
        assert_eq!(plan_step(&client, steps, goal).await, TaskOutcome::Achieved);
    }
    assert!(steps >= 4, "{steps} steps for 5 m");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_step_at_the_goal_does_nothing_and_succeeds() {
    let terrain = Course::builtin(1).unwrap().height_field().unwrap();
    let mut s = scene(terrain, 3.0, Point2::new(3.8, 2.6)).await;
    let client = Module::builder("client")
        .connect(&s.connector)
        .await
        .unwrap();
    // A walk's last step finds the carriage at the goal: there is nothing to do.
    assert_eq!(plan_step(&client, 1, 3.0).await, TaskOutcome::Achieved);
    assert!(s.executed.try_recv().is_err(), "nothing may move");
    assert!(s.planned.try_recv().is_err(), "no step is planned");
}
