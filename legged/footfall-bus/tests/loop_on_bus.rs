//! The operator's loop on the bus, in one process: the simulated Controller of the rover on
//! the rock field, the robot-side executor and the ground-side planner behind one central;
//! maps, a plan, the plan sent, the telemetry back; a stale plan refused.

use std::sync::Arc;
use std::time::Duration;

use nalgebra::Point2;
use tca_central::StartOptions;
use tca_footfall::maps::Colour;
use tca_footfall::plan::{PlanOptions, PlannerKind};
use tca_footfall_bus::{
    EXECUTOR_MODULE, FootfallMaps, FootfallPlanStep, FootfallSetup, PLANNER_MODULE, PlannerConfig,
    Telemetry, connect_executor, connect_planner, send_plan,
};
use tca_legged_controller::{LeggedControllerConfig, connect};
use tca_legged_messages::LegState;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module};
use tca_testkit::within;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn maps_plan_send_and_the_telemetry_comes_back() {
    within("the FootFall loop on the bus", async {
        let central = tca_central::start(StartOptions::simulated(None))
            .await
            .unwrap();
        let connector = Connector::from(central.in_process());
        let setup = FootfallSetup::default();
        let (model, urdf, terrain, start) = setup.load().unwrap();
        let controller = connect(
            &connector,
            LeggedControllerConfig::new(model.clone(), urdf, terrain.clone(), start),
        )
        .await
        .unwrap();
        let executor = connect_executor(&connector, EXECUTOR_MODULE).await.unwrap();
        let planner = connect_planner(
            &connector,
            PlannerConfig {
                terrain: terrain.clone(),
                options: PlanOptions::default(),
                module_name: PLANNER_MODULE.into(),
            },
        )
        .await
        .unwrap();
        let operator = Module::builder("operator")
            .connect(&connector)
            .await
            .unwrap();

        let maps = operator
            .query(&FootfallMaps {
                leg: "left_front".into(),
                polygon: None,
                resolution_m: Some(0.1),
            })
            .await
            .unwrap();
        assert!(maps.counts.green > 20, "{:?}", maps.counts);
        assert!(maps.now.conservative_margin_m > 1.0);
        // A green cell 40 cm or more from where the foot stands.
        let here = operator
            .query(&LegState {
                leg: "left_front".into(),
            })
            .await
            .unwrap()
            .foot;
        let here = Point2::new(here.x_m, here.y_m);
        let target = maps
            .cells_of(Colour::Green)
            .into_iter()
            .map(|(ix, iy)| maps.centre(ix, iy))
            .find(|p| (p - here).norm() > 0.4)
            .expect("a green cell away from the foot");
        let plan = operator
            .query(&FootfallPlanStep {
                leg: "left_front".into(),
                target: [target.x, target.y],
                planner: PlannerKind::Astar,
                heuristics: true,
            })
            .await
            .unwrap();
        assert!(plan.swing_waypoints <= 5);
        let mut telemetry = Vec::new();
        let outcome = send_plan(&operator, &plan, Duration::from_millis(300), |t| {
            telemetry.push(t)
        })
        .await
        .unwrap();
        assert_eq!(outcome, TaskOutcome::Achieved);
        let contacts: Vec<_> = telemetry
            .iter()
            .filter_map(|t| match t {
                Telemetry::Contact(c) => Some(c.clone()),
                _ => None,
            })
            .collect();
        assert!(
            contacts.iter().any(|c| !c.stance) && contacts.iter().any(|c| c.stance),
            "lift-off and touch-down: {contacts:?}"
        );
        assert!(telemetry.iter().any(|t| matches!(t, Telemetry::Support(_))));
        let landed = operator
            .query(&LegState {
                leg: "left_front".into(),
            })
            .await
            .unwrap();
        assert!(landed.stance);
        let d = Point2::new(landed.foot.x_m, landed.foot.y_m) - target;
        assert!(d.norm() < 0.02, "landed {d:?} from the target");

        // The same plan again: the leg is no longer where it was planned from.
        let again = send_plan(&operator, &plan, Duration::from_millis(10), |_| {})
            .await
            .unwrap();
        match again {
            TaskOutcome::Failed(why) => assert!(why.contains("plan again"), "{why}"),
            other => panic!("a stale plan was not refused: {other:?}"),
        }
        // A leg that does not exist.
        let e = operator
            .query(&FootfallPlanStep {
                leg: "tail".into(),
                target: [0.0, 0.0],
                planner: PlannerKind::Sbl,
                heuristics: true,
            })
            .await
            .unwrap_err();
        assert!(e.to_string().contains("left_front"), "{e}");

        for m in [operator, planner, executor, controller] {
            m.close().await;
        }
        central.shutdown().await.unwrap();
        let _ = Arc::new(());
    })
    .await;
}
