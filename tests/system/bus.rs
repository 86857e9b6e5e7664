//! Whole-system tests of the TCA core over every transport (in-process, zenoh, local link): routing, order, errors, format
//! checks, modules crashing and coming back, timeouts, and the traffic log.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::common::*;
use serde::{Deserialize, Serialize};
use tca_central::StartOptions;
use tca_messages::control::TaskOutcome;
use tca_messages::{Class, RouteError};
use tca_module::{HandlerError, Module, ModuleError};
use tca_ping::echo::{self, Ping};

/// Where the carriage is, in metres along the rails.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct BodyPosition;
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Pose {
    y_m: f64,
}
tca_messages::message!(BodyPosition: query "bodyPosition" -> Pose);

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct BodyMove {
    target_y_m: f64,
}
tca_messages::message!(BodyMove: command "bodyMove");

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct PlanStep {
    step: u32,
}
tca_messages::message!(PlanStep: goal "planStep");

/// The same name with the carriage position in the wrong unit (§7.1's bug).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "BodyMove")]
struct BodyMoveFeet {
    target_y_ft: f64,
}
tca_messages::message!(BodyMoveFeet: command "bodyMove");

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct SlowQuery;
tca_messages::message!(SlowQuery: query "slowQuery" -> ());

async fn controller(central: &TestCentral, moves: Arc<Mutex<Vec<f64>>>) -> Module {
    within(
        "controller connects",
        Module::builder("controller")
            .handle(|_ctx, _q: BodyPosition| async { Ok(Pose { y_m: 1.25 }) })
            .handle(move |_ctx, m: BodyMove| {
                let moves = moves.clone();
                async move {
                    // Take some time so later commands really have to wait for capacity.
                    tokio::time::sleep(Duration::from_millis(5)).await;
                    moves.lock().unwrap().push(m.target_y_m);
                    Ok(())
                }
            })
            .connect(&central.connector),
    )
    .await
    .expect("controller connects")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_query_is_routed_and_answered() {
    for transport in ALL {
        let central = TestCentral::start(transport).await;
        let _ctl = controller(&central, Default::default()).await;
        let gait = within(
            "gait connects",
            Module::builder("gait").connect(&central.connector),
        )
        .await
        .unwrap();
        let pose = within("query", gait.query(&BodyPosition)).await.unwrap();
        assert_eq!(pose, Pose { y_m: 1.25 }, "{transport:?}");
        central.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn commands_are_handled_one_at_a_time_in_order() {
    for transport in ALL {
        let central = TestCentral::start(transport).await;
        let moves = Arc::new(Mutex::new(Vec::new()));
        let _ctl = controller(&central, moves.clone()).await;
        let gait = within(
            "gait connects",
            Module::builder("gait").connect(&central.connector),
        )
        .await
        .unwrap();
        for i in 0..7 {
            let target = BodyMove {
                target_y_m: f64::from(i),
            };
            gait.send_task(&target, []).unwrap();
        }
        let last = gait
            .send_watched(&BodyMove { target_y_m: 7.0 }, [])
            .unwrap();
        let outcome = within("last command", last.outcome()).await.unwrap();
        assert_eq!(outcome, TaskOutcome::Achieved);
        let expected: Vec<f64> = (0..8).map(f64::from).collect();
        assert_eq!(*moves.lock().unwrap(), expected, "{transport:?}");
        central.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_goal_handler_s_commands_become_its_children() {
    let central = TestCentral::start(TransportKind::InProcess).await;
    let moves = Arc::new(Mutex::new(Vec::new()));
    let _ctl = controller(&central, moves.clone()).await;
    let _planner = Module::builder("planner")
        .handle(|ctx, g: PlanStep| async move {
            ctx.command(&BodyMove {
                target_y_m: f64::from(g.step),
            })?;
            Ok(())
        })
        .connect(&central.connector)
        .await
        .unwrap();
    let user = Module::builder("user")
        .connect(&central.connector)
        .await
        .unwrap();
    let walk = user.send_watched(&PlanStep { step: 3 }, []).unwrap();
    // The goal is achieved only once its child command is.
    let outcome = within("goal achieved", walk.outcome()).await.unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    assert_eq!(*moves.lock().unwrap(), vec![3.0]);
    central.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_unknown_name_gets_an_error_back() {
    for transport in ALL {
        let central = TestCentral::start(transport).await;
        let _ctl = controller(&central, Default::default()).await;
        let gait = within(
            "gait connects",
            Module::builder("gait").connect(&central.connector),
        )
        .await
        .unwrap();
        #[derive(Serialize, Deserialize)]
        struct BodyMoveTypo;
        tca_messages::message!(BodyMoveTypo: query "body_position" -> ());
        let err = within("query", gait.query(&BodyMoveTypo))
            .await
            .unwrap_err();
        match err {
            ModuleError::Route(RouteError::UnknownMessage { name, suggestion }) => {
                assert_eq!(name, "body_position");
                assert_eq!(suggestion.as_deref(), Some("bodyPosition"));
            }
            other => panic!("unexpected {other}"),
        }
        central.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_registration_with_another_format_is_refused() {
    for transport in ALL {
        let central = TestCentral::start(transport).await;
        let _ctl = controller(&central, Default::default()).await;
        let err = within(
            "impostor connects",
            Module::builder("impostor")
                .replace(true)
                .handle(|_ctx, _m: BodyMoveFeet| async { Ok(()) })
                .connect(&central.connector),
        )
        .await
        .unwrap_err();
        let text = err.to_string();
        assert!(text.contains("target_y_m"), "{text}");
        assert!(text.contains("target_y_ft"), "{text}");
        central.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_query_times_out_with_an_error_not_a_hang() {
    let central = TestCentral::start(TransportKind::InProcess).await;
    let _slow = Module::builder("slow")
        .handle(|_ctx, _q: SlowQuery| async {
            tokio::time::sleep(Duration::from_secs(30)).await;
            Ok::<(), HandlerError>(())
        })
        .connect(&central.connector)
        .await
        .unwrap();
    let asker = Module::builder("asker")
        .connect(&central.connector)
        .await
        .unwrap();
    let err = within(
        "query",
        asker.query_with_timeout(&SlowQuery, Duration::from_millis(200)),
    )
    .await
    .unwrap_err();
    assert!(matches!(err, ModuleError::Timeout { .. }), "{err}");
    central.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_query_in_flight_fails_at_once_when_its_handler_dies() {
    for transport in ALL {
        let central = TestCentral::start(transport).await;
        let slow = Module::builder("slow")
            .handle(|_ctx, _q: SlowQuery| async {
                tokio::time::sleep(Duration::from_secs(30)).await;
                Ok::<(), HandlerError>(())
            })
            .connect(&central.connector)
            .await
            .unwrap();
        let asker = Module::builder("asker")
            .connect(&central.connector)
            .await
            .unwrap();
        let pending = tokio::spawn(async move { asker.query(&SlowQuery).await });
        tokio::time::sleep(Duration::from_millis(200)).await;
        slow.abort_link();
        let err = within("query fails", pending).await.unwrap().unwrap_err();
        assert!(
            matches!(err, ModuleError::Route(RouteError::HandlerDied { .. })),
            "{transport:?}: {err}"
        );
        central.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn messages_wait_for_a_crashed_module_and_reach_it_when_it_returns() {
    for transport in ALL {
        let central = TestCentral::start(transport).await;
        let first = echo::connect(&central.connector, "echo").await.unwrap();
        let pinger = Module::builder("pinger")
            .connect(&central.connector)
            .await
            .unwrap();
        let ping = Ping {
            seq: 1,
            payload: vec![1, 2, 3],
        };
        assert_eq!(pinger.query(&ping).await.unwrap(), ping);
        first.abort_link();
        within("central notices the crash", async {
            loop {
                let registry = pinger.registry().await.unwrap();
                if registry
                    .entries
                    .iter()
                    .any(|e| e.name.as_str() == "tca-ping" && !e.connected)
                {
                    break;
                }
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
        })
        .await;
        // Sent while the echo is down: held by central.
        let waiting = {
            let pinger = pinger.clone();
            let ping = Ping {
                seq: 2,
                payload: vec![4],
            };
            tokio::spawn(async move { pinger.query(&ping).await })
        };
        tokio::time::sleep(Duration::from_millis(300)).await;
        assert!(!waiting.is_finished(), "{transport:?}: the query waits");
        let _second = retry("echo reconnects", || {
            echo::connect(&central.connector, "echo")
        })
        .await;
        let pong = within("held query answered", waiting)
            .await
            .unwrap()
            .unwrap();
        assert_eq!(
            pong,
            Ping {
                seq: 2,
                payload: vec![4]
            },
            "{transport:?}"
        );
        central.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_process_killed_and_restarted_still_gets_what_waited() {
    for transport in [TransportKind::Zenoh, TransportKind::Local] {
        module_process_killed_and_restarted(transport).await;
    }
}

/// An echo process is killed with a query waiting for it; a new one gets the query.
async fn module_process_killed_and_restarted(transport: TransportKind) {
    let central = TestCentral::start(transport).await;
    let endpoint = central.endpoint.clone().unwrap();
    let mut echo_proc = spawn_tca(&["module", "echo", "--connect", &endpoint]);
    let pinger = Module::builder("pinger")
        .connect(&central.connector)
        .await
        .unwrap();
    let first = Ping {
        seq: 1,
        payload: vec![9],
    };
    let pong = retry("echo process answers", || {
        pinger.query_with_timeout(&first, Duration::from_millis(500))
    })
    .await;
    assert_eq!(pong, first, "{transport:?}");
    echo_proc.kill();
    // Wait until central has noticed (zenoh withdraws the module's liveliness token; the local
    // socket closes).
    within("central notices the kill", async {
        loop {
            let registry = pinger.registry().await.unwrap();
            if registry
                .entries
                .iter()
                .any(|e| e.name.as_str() == "tca-ping" && !e.connected)
            {
                break;
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    })
    .await;
    let waiting = {
        let pinger = pinger.clone();
        tokio::spawn(async move {
            pinger
                .query(&Ping {
                    seq: 2,
                    payload: vec![],
                })
                .await
        })
    };
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert!(!waiting.is_finished(), "{transport:?}: the query waits");
    let _echo_again = spawn_tca(&["module", "echo", "--connect", &endpoint]);
    let pong = within("held query answered", waiting)
        .await
        .unwrap()
        .unwrap();
    assert_eq!(pong.seq, 2, "{transport:?}");
    central.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_log_is_readable_after_central_is_killed() {
    for endpoint in [free_endpoint(), unique_local_endpoint()] {
        log_readable_after_kill(&endpoint).await;
    }
}

/// A central process at `endpoint` logs 50 round trips and is killed with `kill -9`.
async fn log_readable_after_kill(endpoint: &str) {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("traffic.mcap");
    let mut central = spawn_tca(&[
        "central",
        "--listen",
        endpoint,
        "--log",
        log.to_str().unwrap(),
    ]);
    let connector = tca_module::Connector::endpoint(endpoint);
    let _echo = retry("central is up", || echo::connect(&connector, "echo")).await;
    let pinger = Module::builder("pinger").connect(&connector).await.unwrap();
    for seq in 0..50 {
        pinger
            .query(&Ping {
                seq,
                payload: vec![],
            })
            .await
            .unwrap();
    }
    // Everything older than ~100 ms must survive a kill -9.
    tokio::time::sleep(Duration::from_millis(150)).await;
    central.kill();
    remove_local_socket(endpoint);
    let file = tca_logs::LogFile::open(&log).expect("log readable after kill -9");
    let answered = file
        .records
        .iter()
        .filter_map(|r| match &r.kind {
            tca_logs::RecordKind::Frame(f) if f.direction == tca_logs::Direction::Out => {
                tca_logs::LogFile::envelope(f).ok()
            }
            _ => None,
        })
        .filter(|e| e.class == Class::Reply && e.name.as_str() == "tca-ping")
        .count();
    assert_eq!(answered, 50, "{endpoint}: every reply is in the log");
    // The viewer decodes the data through the registered format.
    let lines = tca_logs::render(
        &file,
        &tca_logs::ShowFilter {
            name: Some("tca-ping".into()),
            class: Some(Class::Query),
            ..Default::default()
        },
    );
    assert_eq!(lines.len(), 50, "{endpoint}: {lines:?}");
    assert!(
        lines[0].contains("Ping { seq: 0, payload: [] }"),
        "{}",
        lines[0]
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_clean_log_records_everything_and_shows_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.mcap");
    let central = TestCentral::start_with(
        TransportKind::InProcess,
        StartOptions {
            log: Some(path.clone()),
            ..StartOptions::default()
        },
    )
    .await;
    let moves = Arc::new(Mutex::new(Vec::new()));
    let _ctl = controller(&central, moves).await;
    let gait = Module::builder("gait")
        .connect(&central.connector)
        .await
        .unwrap();
    gait.query(&BodyPosition).await.unwrap();
    let t = gait
        .send_watched(&BodyMove { target_y_m: 2.0 }, [])
        .unwrap();
    t.outcome().await.unwrap();
    central.stop().await;
    let log = tca_logs::LogFile::open(&path).unwrap();
    assert!(log.truncated.is_none());
    let text = tca_logs::render(&log, &Default::default()).join("\n");
    assert!(
        text.contains("query     gait -> controller  bodyPosition"),
        "{text}"
    );
    assert!(
        text.contains("reply     controller -> gait  bodyPosition"),
        "{text}"
    );
    assert!(text.contains("Pose { y_m: 1.25 }"), "{text}");
    assert!(
        text.contains("command   gait -> controller  bodyMove"),
        "{text}"
    );
    assert!(text.contains("BodyMove { target_y_m: 2 }"), "{text}");
    assert!(
        text.contains("success   controller -> central  bodyMove"),
        "{text}"
    );
    assert!(
        text.contains("registered command bodyMove by controller"),
        "{text}"
    );
    let tree_ops = log
        .records
        .iter()
        .filter(|r| matches!(r.kind, tca_logs::RecordKind::Tree(_)))
        .count();
    assert!(tree_ops >= 3, "add, start, finish are logged: {tree_ops}");
}
