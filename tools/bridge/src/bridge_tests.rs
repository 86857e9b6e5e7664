//! The bridge between two centrals, class by class: informs, commands and their outcomes,
//! exceptions, kills, queries and their timeouts, the log and its playback, a bridge that
//! restarts, a central that dies, and what is refused.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::{BridgeConfig, Direction, NamePattern, PlaybackOptions, Recorded, RunningBridge};
use serde::{Deserialize, Serialize};
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, HandlerError, Module};
use tca_testkit::{TestCentral, TransportKind, within};
use tokio::sync::mpsc;

/// Inform, ground to robot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Up(u32);
tca_messages::message!(Up: inform "t.up");

/// Inform, robot to ground.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Down(u32);
tca_messages::message!(Down: inform "t.down");

/// Command the robot carries out: refused below 0, raises `t.failed` at 0, waits `x`
/// tenths of a second above.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Move {
    x: i32,
}
tca_messages::message!(Move: command "t.move");

/// Query the robot answers after `wait_ms`, with `wait_ms`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Ask {
    wait_ms: u64,
}
tca_messages::message!(Ask: query "t.ask" -> u64);

/// Exception the robot raises in a move at 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Failed {
    detail: String,
}
tca_messages::message!(Failed: exception "t.failed");

/// Goal on the ground whose handler sends a move and takes its exceptions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Walk {
    x: i32,
}
tca_messages::message!(Walk: goal "t.walk");

/// What the robot side saw.
#[derive(Default)]
struct RobotLog {
    ups: Vec<(u32, Instant)>,
    moves: Vec<(i32, Instant)>,
    cancelled: Vec<i32>,
}

/// Waits until what the robot side saw passes `check`.
async fn robot_saw(log: &Mutex<RobotLog>, what: &str, check: impl Fn(&RobotLog) -> bool) {
    within(what, async {
        while !check(&log.lock().unwrap()) {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await
}

struct Cancelled(Arc<Mutex<RobotLog>>, i32, bool);
impl Drop for Cancelled {
    fn drop(&mut self) {
        if !self.2 {
            self.0.lock().unwrap().cancelled.push(self.1);
        }
    }
}

/// The robot's module: handles up informs, moves and asks.
async fn robot_module(connector: &Connector, log: Arc<Mutex<RobotLog>>) -> Module {
    let l1 = log.clone();
    let l2 = log.clone();
    Module::builder("controller")
        .capacity(8)
        .handle(move |_ctx, u: Up| {
            l1.lock().unwrap().ups.push((u.0, Instant::now()));
            async { Ok(()) }
        })
        .handle(move |ctx, m: Move| {
            let log = l2.clone();
            async move {
                log.lock().unwrap().moves.push((m.x, Instant::now()));
                if m.x < 0 {
                    return Err(HandlerError::new(format!(
                        "refused: x = {} is below 0",
                        m.x
                    )));
                }
                if m.x == 0 {
                    let _ = ctx.raise(&Failed {
                        detail: "no ground under the foot".into(),
                    });
                    return Err(HandlerError::new("the move found no ground"));
                }
                let mut guard = Cancelled(log, m.x, false);
                tokio::time::sleep(Duration::from_millis(100 * m.x as u64)).await;
                guard.2 = true;
                Ok(())
            }
        })
        .handle(|_ctx, a: Ask| async move {
            tokio::time::sleep(Duration::from_millis(a.wait_ms)).await;
            Ok(a.wait_ms)
        })
        .connect(connector)
        .await
        .expect("the robot's module connects")
}

/// The ground's module: takes down informs (with their arrival), walks, and exceptions.
async fn ground_module(
    connector: &Connector,
) -> (
    Module,
    mpsc::UnboundedReceiver<(u32, Instant)>,
    mpsc::UnboundedReceiver<Failed>,
) {
    let (tx, rx) = mpsc::unbounded_channel();
    let (etx, erx) = mpsc::unbounded_channel();
    let module = Module::builder("monitor")
        .capacity(8)
        .handle(move |_ctx, d: Down| {
            let _ = tx.send((d.0, Instant::now()));
            async { Ok(()) }
        })
        .handle(move |_ctx, f: Failed| {
            let _ = etx.send(f);
            async { Ok(()) }
        })
        .handle(|ctx, w: Walk| async move {
            let node = ctx.node().expect("a goal has a node");
            ctx.on_exception::<Failed>(node).await?;
            let outcome = ctx.send_watched(&Move { x: w.x }, [])?.outcome().await?;
            match outcome {
                TaskOutcome::Achieved => Ok(()),
                other => Err(HandlerError::new(format!("the move: {other:?}"))),
            }
        })
        .connect(connector)
        .await
        .expect("the ground's module connects");
    (module, rx, erx)
}

fn patterns(names: &[&str]) -> Vec<NamePattern> {
    names
        .iter()
        .map(|n| NamePattern::parse(n).unwrap())
        .collect()
}

fn config(robot: &TestCentral, ground: &TestCentral, up_ms: u64, down_ms: u64) -> BridgeConfig {
    let mut c = BridgeConfig::new(robot.connector.clone(), ground.connector.clone());
    c.up.delay = Duration::from_millis(up_ms);
    c.down.delay = Duration::from_millis(down_ms);
    c.up.messages = patterns(&["t.up", "t.move", "t.ask"]);
    c.down.messages = patterns(&["t.down", "t.failed"]);
    c.wait = Duration::from_secs(10);
    c
}

struct Sides {
    robot: TestCentral,
    ground: TestCentral,
    robot_log: Arc<Mutex<RobotLog>>,
    controller: Module,
    monitor: Module,
    downs: mpsc::UnboundedReceiver<(u32, Instant)>,
    exceptions: mpsc::UnboundedReceiver<Failed>,
    operator: Module,
}

async fn sides(transport: TransportKind) -> Sides {
    let robot = TestCentral::start(transport).await;
    let ground = TestCentral::start(transport).await;
    let robot_log = Arc::new(Mutex::new(RobotLog::default()));
    let controller = robot_module(&robot.connector, robot_log.clone()).await;
    let (monitor, downs, exceptions) = ground_module(&ground.connector).await;
    let operator = Module::builder("operator")
        .connect(&ground.connector)
        .await
        .unwrap();
    Sides {
        robot,
        ground,
        robot_log,
        controller,
        monitor,
        downs,
        exceptions,
        operator,
    }
}

async fn bridge(config: BridgeConfig) -> RunningBridge {
    within("the bridge starts", crate::start(config))
        .await
        .expect("the bridge starts")
}

/// Slack for a loaded machine: a crossing never comes early, and comes at most this late.
const LATE: Duration = Duration::from_millis(250);

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn informs_cross_each_way_after_that_ways_delay() {
    let mut s = sides(TransportKind::InProcess).await;
    let b = bridge(config(&s.robot, &s.ground, 300, 150)).await;
    let forwarded: Vec<(String, Direction)> = b
        .forwarded()
        .iter()
        .map(|f| (f.name().to_string(), f.direction))
        .collect();
    assert!(
        forwarded.contains(&("t.up".into(), Direction::Up)),
        "{forwarded:?}"
    );
    assert!(
        forwarded.contains(&("t.down".into(), Direction::Down)),
        "{forwarded:?}"
    );
    let sensor = Module::builder("sensor")
        .connect(&s.robot.connector)
        .await
        .unwrap();
    for k in 0..5 {
        let sent = Instant::now();
        s.operator.inform(&Up(k)).unwrap();
        sensor.inform(&Down(k)).unwrap();
        let (got, at) = within("a down inform", s.downs.recv()).await.unwrap();
        assert_eq!(got, k);
        let took = at - sent;
        assert!(
            took >= Duration::from_millis(150) && took < Duration::from_millis(150) + LATE,
            "down took {took:?}"
        );
        let up_at = within("an up inform", async {
            loop {
                if let Some(&(n, at)) = s.robot_log.lock().unwrap().ups.last()
                    && n == k
                {
                    return at;
                }
                tokio::time::sleep(Duration::from_millis(5)).await;
            }
        })
        .await;
        let took = up_at - sent;
        assert!(
            took >= Duration::from_millis(300) && took < Duration::from_millis(300) + LATE,
            "up took {took:?}"
        );
    }
    let stats = b.delay_stats();
    assert_eq!(stats[0].crossings, 5);
    assert_eq!(stats[1].crossings, 5);
    assert!(
        stats[0].min_error_ms >= 0.0 && stats[1].min_error_ms >= 0.0,
        "{stats:?}"
    );
    let summary = b.stop().await;
    assert_eq!(summary.in_flight, 0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn a_command_ends_on_the_ground_as_it_ended_on_the_robot() {
    let s = sides(TransportKind::InProcess).await;
    let b = bridge(config(&s.robot, &s.ground, 200, 100)).await;
    let sent = Instant::now();
    let outcome = within(
        "a move",
        s.operator
            .send_watched(&Move { x: 2 }, [])
            .unwrap()
            .outcome(),
    )
    .await
    .unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    // Up, the move's 0.2 s, down.
    let took = sent.elapsed();
    assert!(
        took >= Duration::from_millis(500) && took < Duration::from_millis(500) + LATE,
        "{took:?}"
    );
    let outcome = within(
        "a refused move",
        s.operator
            .send_watched(&Move { x: -3 }, [])
            .unwrap()
            .outcome(),
    )
    .await
    .unwrap();
    match outcome {
        TaskOutcome::Failed(reason) => {
            assert!(reason.contains("refused: x = -3 is below 0"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    // The robot side carried it under the bridge's carry goal.
    assert_eq!(s.robot_log.lock().unwrap().moves.len(), 2);
    b.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn an_exception_raised_on_the_robot_reaches_the_grounds_handler() {
    let mut s = sides(TransportKind::InProcess).await;
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(&s.robot, &s.ground, 100, 100);
    c.log = Some(dir.path().join("b.mcap"));
    let b = bridge(c).await;
    let outcome = within(
        "a walk whose move fails",
        s.operator
            .send_watched(&Walk { x: 0 }, [])
            .unwrap()
            .outcome(),
    )
    .await
    .unwrap();
    match outcome {
        TaskOutcome::Failed(reason) => assert!(reason.contains("found no ground"), "{reason}"),
        other => panic!("{other:?}"),
    }
    let failed = tokio::time::timeout(Duration::from_secs(5), s.exceptions.recv()).await;
    let Ok(Some(failed)) = failed else {
        // What crossed, to see where the exception stayed.
        b.stop().await;
        let log = tca_logs::LogFile::open(&dir.path().join("b.mcap")).unwrap();
        let filter = tca_logs::ShowFilter {
            all_frames: true,
            ..Default::default()
        };
        panic!(
            "the exception did not come; the bridge's log:\n{}",
            tca_logs::render(&log, &filter).join("\n")
        );
    };
    assert_eq!(failed.detail, "no ground under the foot");
    // A walk whose move succeeds is achieved, with no exception.
    let outcome = within(
        "a walk",
        s.operator
            .send_watched(&Walk { x: 1 }, [])
            .unwrap()
            .outcome(),
    )
    .await
    .unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    assert!(s.exceptions.try_recv().is_err());
    b.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn killing_a_task_on_the_ground_kills_its_copy_on_the_robot() {
    let s = sides(TransportKind::InProcess).await;
    let b = bridge(config(&s.robot, &s.ground, 100, 100)).await;
    let task = s.operator.send_watched(&Move { x: 100 }, []).unwrap();
    let id = task.id();
    robot_saw(&s.robot_log, "the move reaches the robot", |l| {
        !l.moves.is_empty()
    })
    .await;
    let killed_at = Instant::now();
    s.operator.kill_task(id).await.unwrap();
    assert_eq!(
        within("the outcome", task.outcome()).await.unwrap(),
        TaskOutcome::Killed
    );
    robot_saw(&s.robot_log, "the robot's move is cancelled", |l| {
        !l.cancelled.is_empty()
    })
    .await;
    // The kill crossed up after the delay.
    assert!(killed_at.elapsed() >= Duration::from_millis(100));
    assert_eq!(s.robot_log.lock().unwrap().cancelled, vec![100]);
    b.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn a_query_waits_twice_the_delay_plus_its_own_timeout() {
    let s = sides(TransportKind::InProcess).await;
    let mut c = config(&s.robot, &s.ground, 300, 300);
    c.up.query_timeouts
        .insert("t.ask".parse().unwrap(), Duration::from_millis(500));
    let b = bridge(c).await;
    // Answered in 0.4 s there: 1.0 s here, longer than its own 0.5 s.
    let sent = Instant::now();
    let reply = s
        .operator
        .query_with_timeout(&Ask { wait_ms: 400 }, Duration::from_secs(5))
        .await
        .unwrap();
    assert_eq!(reply, 400);
    let took = sent.elapsed();
    assert!(
        took >= Duration::from_millis(1000) && took < Duration::from_millis(1000) + LATE,
        "{took:?}"
    );
    // Not answered within its own 0.5 s there: the failure comes back after 1.1 s.
    let sent = Instant::now();
    let e = s
        .operator
        .query_with_timeout(&Ask { wait_ms: 800 }, Duration::from_secs(5))
        .await
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("within its own timeout of 0.500 s on the robot side"),
        "{e}"
    );
    let took = sent.elapsed();
    assert!(
        took >= Duration::from_millis(1100) && took < Duration::from_millis(1100) + LATE,
        "{took:?}"
    );
    b.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn the_log_measures_every_crossing_and_plays_back_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bridge.mcap");
    let mut s = sides(TransportKind::InProcess).await;
    let mut c = config(&s.robot, &s.ground, 100, 200);
    c.log = Some(log.clone());
    let b = bridge(c).await;
    let sensor = Module::builder("sensor")
        .connect(&s.robot.connector)
        .await
        .unwrap();
    let mut live = Vec::new();
    for k in 0..6 {
        sensor.inform(&Down(k)).unwrap();
        tokio::time::sleep(Duration::from_millis(60)).await;
    }
    let outcome = within(
        "a move",
        s.operator
            .send_watched(&Move { x: 1 }, [])
            .unwrap()
            .outcome(),
    )
    .await
    .unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    for _ in 0..6 {
        live.push(within("a down inform", s.downs.recv()).await.unwrap());
    }
    let summary = b.stop().await;
    let recorded = Recorded::open(&log).unwrap();
    assert_eq!(recorded.bridge.as_deref(), Some("bridge"));
    assert_eq!(recorded.delays_s, Some((0.1, 0.2)));
    let stats = recorded.delay_stats();
    // Up: the move; down: six informs and the move's outcome.
    assert_eq!(
        (stats[0].crossings, stats[1].crossings),
        (1, 7),
        "{stats:?}"
    );
    assert_eq!(summary.delays[1].crossings, 7);
    assert!(stats.iter().all(|s| s.min_error_ms >= 0.0), "{stats:?}");
    // `tca log show` reads it: the data is decoded through the registered formats.
    let lines = tca_logs::render(&recorded.log, &tca_logs::ShowFilter::default());
    assert!(
        lines.iter().any(|l| l.contains("sensor -> ground")
            && l.contains("t.down")
            && l.contains("Down(3)")),
        "{lines:#?}"
    );

    // Played back to a fresh ground side: the same informs, the move answered as recorded.
    let ground2 = TestCentral::start(TransportKind::InProcess).await;
    let (_monitor2, mut downs2, _e) = ground_module(&ground2.connector).await;
    let operator2 = Module::builder("operator")
        .connect(&ground2.connector)
        .await
        .unwrap();
    let player = tokio::spawn({
        let ground = ground2.connector.clone();
        async move {
            crate::play(
                &recorded,
                PlaybackOptions {
                    ground,
                    speed: 2.0,
                    name: None,
                    linger: Duration::from_secs(30),
                },
            )
            .await
        }
    });
    let mut again = Vec::new();
    for _ in 0..6 {
        again.push(within("a played-back inform", downs2.recv()).await.unwrap());
    }
    // Sent twice: the recording answers one, and has no more for the other.
    let first = operator2.send_watched(&Move { x: 1 }, []).unwrap();
    let second = operator2.send_watched(&Move { x: 1 }, []).unwrap();
    let mut outcomes = [
        within("a move answered from the recording", first.outcome())
            .await
            .unwrap(),
        within("a move the recording has no more of", second.outcome())
            .await
            .unwrap(),
    ];
    outcomes.sort_by_key(|o| o != &TaskOutcome::Achieved);
    assert_eq!(outcomes[0], TaskOutcome::Achieved);
    match &outcomes[1] {
        TaskOutcome::Failed(reason) => assert!(reason.contains("no more t.move"), "{reason}"),
        other => panic!("{other:?}"),
    }
    let report = within("the playback ends", player).await.unwrap().unwrap();
    assert_eq!(report.informs, 6);
    assert_eq!(
        (report.answered, report.differing, report.unmatched),
        (1, 0, 1)
    );
    let values: Vec<u32> = again.iter().map(|(v, _)| *v).collect();
    assert_eq!(values, live.iter().map(|(v, _)| *v).collect::<Vec<_>>());
    // With the recorded timing, twice as fast: 60 ms apart live, 30 ms played back.
    for k in 1..6 {
        let live_gap = live[k].1 - live[k - 1].1;
        let again_gap = again[k].1 - again[k - 1].1;
        let diff = (live_gap.as_secs_f64() / 2.0 - again_gap.as_secs_f64()).abs();
        assert!(
            diff < 0.05,
            "gap {k}: live {live_gap:?}, played back {again_gap:?}"
        );
    }
    drop(s.controller);
    drop(s.monitor);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn a_task_under_way_when_the_bridge_stops_is_not_carried_out_twice() {
    let s = sides(TransportKind::InProcess).await;
    let b = bridge(config(&s.robot, &s.ground, 50, 50)).await;
    let task = s.operator.send_watched(&Move { x: 50 }, []).unwrap();
    robot_saw(&s.robot_log, "the move reaches the robot", |l| {
        !l.moves.is_empty()
    })
    .await;
    // The bridge dies (both links drop at once)...
    drop(b);
    // ...and a new one starts: the ground's task, delivered to it again, fails saying why.
    let b = bridge(config(&s.robot, &s.ground, 50, 50)).await;
    match within("the outcome", task.outcome()).await.unwrap() {
        TaskOutcome::Failed(reason) => assert!(
            reason.contains("when the bridge stopped") && reason.contains("not sent again"),
            "{reason}"
        ),
        other => panic!("{other:?}"),
    }
    // The robot's copy was killed with the old bridge's carry; nothing was sent twice.
    robot_saw(&s.robot_log, "the robot's move is cancelled", |l| {
        !l.cancelled.is_empty()
    })
    .await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    assert_eq!(s.robot_log.lock().unwrap().moves.len(), 1);
    // The new bridge forwards as before.
    let outcome = within(
        "a move through the new bridge",
        s.operator
            .send_watched(&Move { x: 1 }, [])
            .unwrap()
            .outcome(),
    )
    .await
    .unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    b.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn when_the_robots_central_dies_a_task_across_fails_saying_so() {
    let s = sides(TransportKind::Zenoh).await;
    let b = bridge(config(&s.robot, &s.ground, 50, 50)).await;
    let task = s.operator.send_watched(&Move { x: 100 }, []).unwrap();
    robot_saw(&s.robot_log, "the move reaches the robot", |l| {
        !l.moves.is_empty()
    })
    .await;
    let Sides { robot, .. } = s;
    robot.stop().await;
    match within("the outcome", task.outcome()).await.unwrap() {
        TaskOutcome::Failed(reason) => {
            assert!(reason.contains("central went away"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    drop(b);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn names_no_side_handles_and_simulated_centrals_are_refused() {
    let s = sides(TransportKind::InProcess).await;
    let mut c = config(&s.robot, &s.ground, 0, 0);
    c.down
        .messages
        .push(NamePattern::parse("t.nobody").unwrap());
    c.wait = Duration::from_millis(600);
    let e = within("the bridge gives up", crate::start(c))
        .await
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("the ground side's central has no handler for t.nobody"),
        "{e}"
    );
    let sim = TestCentral::start_with(
        TransportKind::InProcess,
        tca_central::StartOptions::simulated(None),
    )
    .await;
    let e = within(
        "the bridge refuses a simulated central",
        crate::start(BridgeConfig::new(
            sim.connector.clone(),
            s.ground.connector.clone(),
        )),
    )
    .await
    .err()
    .expect("refused")
    .to_string();
    assert!(e.contains("keeps a simulated clock"), "{e}");
}
