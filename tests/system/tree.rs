//! Whole-system tests of task trees: the walking tree of Figure 5 in sequential and concurrent
//! mode, checked from the traffic log; an exception handled two levels up; monitors; kill;
//! `tca tree` and `tca log show --tree`.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::common::*;
use serde::{Deserialize, Serialize};
use tca_central::StartOptions;
use tca_messages::control::TaskOutcome;
use tca_messages::{ConstraintSpec, MessageId, NodeId, TaskRef, TimePoint};
use tca_module::{HandlerError, Module, raise_action, send_action};
use tca_task_tree::TreeOp;

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Walk {
    steps: u32,
    concurrent: bool,
}
tca_messages::message!(Walk: goal "walk");

#[derive(Clone, Debug, Serialize, Deserialize)]
struct PlanGait {
    step: u32,
    steps: u32,
    concurrent: bool,
    /// The previous step's body move, for the concurrent-mode constraint.
    previous_body_move: Option<MessageId>,
}
tca_messages::message!(PlanGait: goal "planGait");

#[derive(Clone, Debug, Serialize, Deserialize)]
struct LegMoveGoal {
    step: u32,
}
tca_messages::message!(LegMoveGoal: goal "legMoveGoal");

#[derive(Clone, Debug, Serialize, Deserialize)]
struct LegMove {
    step: u32,
}
tca_messages::message!(LegMove: command "legMove");

#[derive(Clone, Debug, Serialize, Deserialize)]
struct BodyMove {
    step: u32,
}
tca_messages::message!(BodyMove: command "bodyMove");

#[derive(Clone, Debug, Serialize, Deserialize)]
struct MoveFailed {
    step: u32,
}
tca_messages::message!(MoveFailed: exception "moveFailed");

const PLAN: Duration = Duration::from_millis(30);
const MOVE: Duration = Duration::from_millis(60);

/// The Figure 5 modules: gait (walk, planGait), lrp (legMoveGoal), controller (legMove,
/// bodyMove). With `fail_step`, the controller fails that step's first leg move with an
/// exception, which the gait planner handles at the walk node (two levels above the leg
/// move's goal) by planning the step again.
/// Waits (wall clock) or spends (simulated clock) `d`.
async fn work(ctx: &tca_module::Context, d: Duration) {
    if ctx.simulated_time() {
        ctx.spend(d * 1000); // simulated: 30 ms of planning stands for 30 s, and so on
    } else {
        tokio::time::sleep(d).await;
    }
}

async fn figure5_modules(central: &TestCentral, fail_step: Option<u32>, sim: bool) -> Vec<Module> {
    let connector = &central.connector;
    let failed_once = Arc::new(AtomicU32::new(0));
    let controller = Module::builder("controller")
        .simulated_time(sim)
        .handle(move |ctx, m: LegMove| {
            let failed_once = failed_once.clone();
            async move {
                work(&ctx, MOVE).await;
                if Some(m.step) == fail_step && failed_once.fetch_add(1, Ordering::SeqCst) == 0 {
                    ctx.raise(&MoveFailed { step: m.step })?;
                    return Err(HandlerError::new("leg struck an obstacle"));
                }
                Ok(())
            }
        })
        .handle(|ctx, _m: BodyMove| async move {
            work(&ctx, MOVE).await;
            Ok(())
        })
        .connect(connector)
        .await
        .unwrap();
    let lrp = Module::builder("lrp")
        .capacity(4)
        .simulated_time(sim)
        .handle(|ctx, g: LegMoveGoal| async move {
            work(&ctx, PLAN).await;
            ctx.command(&LegMove { step: g.step })?;
            Ok(())
        })
        .connect(connector)
        .await
        .unwrap();
    // Which planGait node handles which step, so the exception handler can re-plan it.
    let steps: Arc<Mutex<HashMap<u32, (NodeId, PlanGait)>>> = Arc::default();
    let steps_for_plan = steps.clone();
    let gait = Module::builder("gait")
        .capacity(4)
        .simulated_time(sim)
        .handle(|ctx, w: Walk| async move {
            let walk_node = ctx.node().expect("a goal has a node");
            ctx.on_exception::<MoveFailed>(walk_node).await?;
            ctx.goal(&PlanGait {
                step: 1,
                steps: w.steps,
                concurrent: w.concurrent,
                previous_body_move: None,
            })?;
            Ok(())
        })
        .handle(move |ctx, p: PlanGait| {
            let steps = steps_for_plan.clone();
            async move {
                steps
                    .lock()
                    .unwrap()
                    .insert(p.step, (ctx.node().unwrap(), p.clone()));
                work(&ctx, PLAN).await;
                // In concurrent mode the leg may not move before the previous body move ends.
                let leg_constraints = p.previous_body_move.map(|prev| {
                    ConstraintSpec::sequential_achievement(TaskRef::Message(prev), TaskRef::This)
                });
                let leg = ctx.send_task(&LegMoveGoal { step: p.step }, leg_constraints)?;
                let body = ctx.send_task(
                    &BodyMove { step: p.step },
                    [ConstraintSpec::sequential_achievement(
                        leg.task_ref(),
                        TaskRef::This,
                    )],
                )?;
                if p.step < p.steps {
                    // The next step is a sibling, under the walk (this goal's sender's node).
                    let walk = ctx.in_context(ctx.origin());
                    let next = (!p.concurrent)
                        .then(|| ConstraintSpec::delay_planning(body.task_ref(), TaskRef::This));
                    walk.send_task(
                        &PlanGait {
                            step: p.step + 1,
                            previous_body_move: p.concurrent.then(|| body.id()),
                            ..p
                        },
                        next,
                    )?;
                }
                Ok(())
            }
        })
        .handle(move |ctx, failure: MoveFailed| {
            let steps = steps.clone();
            async move {
                // Patch the plan: the failed step is planned again, then the old one killed.
                let (node, plan) = steps.lock().unwrap()[&failure.step].clone();
                ctx.goal(&PlanGait {
                    step: plan.step,
                    steps: plan.step, // the retried step does not send the next one again
                    ..plan
                })?;
                ctx.kill(node).await?;
                Ok(())
            }
        })
        .connect(connector)
        .await
        .unwrap();
    vec![controller, lrp, gait]
}

/// Handling starts and ends by (name, step order) from the log's tree operations.
#[derive(Debug, Default)]
struct Timeline {
    starts: Vec<(u64, String)>,
    ends: Vec<(u64, String)>,
}

fn timeline(log: &tca_logs::LogFile) -> Timeline {
    let mut names: HashMap<u64, String> = HashMap::new();
    let mut counts: HashMap<String, u32> = HashMap::new();
    let mut t = Timeline::default();
    for r in &log.records {
        let tca_logs::RecordKind::Tree(tr) = &r.kind else {
            continue;
        };
        match &tr.op {
            TreeOp::AddNode { id, spec, .. } => {
                let n = counts.entry(spec.name.clone()).or_default();
                *n += 1;
                names.insert(id.0, format!("{}{}", spec.name, n));
            }
            TreeOp::Start { node, now } => t.starts.push((*now, names[&node.0].clone())),
            TreeOp::Finish { node, now, .. } => t.ends.push((*now, names[&node.0].clone())),
            _ => {}
        }
    }
    t
}

impl Timeline {
    fn start(&self, name: &str) -> u64 {
        self.starts
            .iter()
            .find(|(_, n)| n == name)
            .unwrap_or_else(|| panic!("{name} never started: {:?}", self.starts))
            .0
    }
    fn end(&self, name: &str) -> u64 {
        self.ends
            .iter()
            .find(|(_, n)| n == name)
            .unwrap_or_else(|| panic!("{name} never ended: {:?}", self.ends))
            .0
    }
    fn order(&self) -> Vec<&str> {
        self.starts.iter().map(|(_, n)| n.as_str()).collect()
    }
}

async fn walk(concurrent: bool, fail_step: Option<u32>) -> (Timeline, tca_logs::LogFile, Duration) {
    let (t, log, took, _) = walk_on(concurrent, fail_step, false).await;
    (t, log, took)
}

/// Walks three steps; returns the timeline, the log, the wall time and the final time on the
/// user's clock (simulated seconds when `sim`).
async fn walk_on(
    concurrent: bool,
    fail_step: Option<u32>,
    sim: bool,
) -> (Timeline, tca_logs::LogFile, Duration, f64) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("walk.mcap");
    let central = TestCentral::start_with(
        TransportKind::InProcess,
        StartOptions {
            log: Some(path.clone()),
            ..StartOptions::default()
        },
    )
    .await;
    let _modules = figure5_modules(&central, fail_step, sim).await;
    let user = Module::builder("user")
        .simulated_time(sim)
        .connect(&central.connector)
        .await
        .unwrap();
    let started = std::time::Instant::now();
    let task = user
        .send_watched(
            &Walk {
                steps: 3,
                concurrent,
            },
            [],
        )
        .unwrap();
    let outcome = within("walk", task.outcome()).await.unwrap();
    let took = started.elapsed();
    let clock_s = user.time_ns() as f64 / 1e9;
    assert_eq!(outcome, TaskOutcome::Achieved);
    central.stop().await;
    let log = tca_logs::LogFile::open(&path).unwrap();
    (timeline(&log), log, took, clock_s)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn simulated_time_shows_what_concurrency_saves() {
    // Planning steps cost 30 s, moves 60 s of simulated time. Sequentially each step takes
    // plan + leg plan + leg move + body move = 180 s; concurrently the next step is planned
    // while this one moves, so after the first step only the moves are on the critical path.
    let (_, _, _, sequential) = walk_on(false, None, true).await;
    let (_, _, _, concurrent) = walk_on(true, None, true).await;
    assert_eq!(sequential, 3.0 * 180.0);
    assert_eq!(concurrent, 60.0 + 3.0 * 120.0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn figure5_sequential_plans_each_step_after_the_previous_body_move() {
    let (t, _, _) = walk(false, None).await;
    assert_eq!(
        t.order(),
        [
            "walk1",
            "planGait1",
            "legMoveGoal1",
            "legMove1",
            "bodyMove1",
            "planGait2",
            "legMoveGoal2",
            "legMove2",
            "bodyMove2",
            "planGait3",
            "legMoveGoal3",
            "legMove3",
            "bodyMove3"
        ]
    );
    for k in 1..=3 {
        assert!(t.end(&format!("legMove{k}")) <= t.start(&format!("bodyMove{k}")));
    }
    for k in 1..=2 {
        assert!(
            t.end(&format!("bodyMove{k}")) <= t.start(&format!("planGait{}", k + 1)),
            "step {} is planned after body move {k}",
            k + 1
        );
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn figure5_concurrent_plans_the_next_step_while_this_one_executes() {
    let (t, _, concurrent_took) = walk(true, None).await;
    for k in 1..=2 {
        // Planning k+1 starts before body move k ends...
        assert!(
            t.start(&format!("planGait{}", k + 1)) < t.end(&format!("bodyMove{k}")),
            "step {} planned during step {k}: {:?}",
            k + 1,
            t.starts
        );
        // ...but leg move k+1 still waits for body move k.
        assert!(t.end(&format!("bodyMove{k}")) <= t.start(&format!("legMove{}", k + 1)));
    }
    for k in 1..=3 {
        assert!(t.end(&format!("legMove{k}")) <= t.start(&format!("bodyMove{k}")));
    }
    let (_, _, sequential_took) = walk(false, None).await;
    assert!(
        concurrent_took < sequential_took,
        "concurrent {concurrent_took:?} vs sequential {sequential_took:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_exception_two_levels_up_patches_the_plan_and_the_walk_completes() {
    let (t, log, _) = walk(false, Some(2)).await;
    // Step 2 was planned twice; the second plan's leg and body moves ran.
    assert!(t.order().contains(&"planGait4"), "{:?}", t.order());
    let legs: Vec<_> = t
        .order()
        .into_iter()
        .filter(|n| n.starts_with("legMove"))
        .collect();
    assert!(legs.len() >= 4, "{legs:?}");
    let text = tca_logs::render(&log, &Default::default()).join("\n");
    assert!(
        text.contains("exception controller -> gait  moveFailed"),
        "{text}"
    );
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct TooFar;
tca_messages::message!(TooFar: query "tooFar" -> bool);

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Stop;
tca_messages::message!(Stop: exception "stop");

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Alarm {
    node: u64,
}
tca_messages::message!(Alarm: inform "alarm");

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Work;
tca_messages::message!(Work: goal "work");

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn monitors_check_conditions_and_end_with_their_node() {
    let central = TestCentral::start(TransportKind::InProcess).await;
    let polls = Arc::new(AtomicU32::new(0));
    let alarms = Arc::new(Mutex::new(Vec::new()));
    let stops = Arc::new(AtomicU32::new(0));
    let (p, a, s) = (polls.clone(), alarms.clone(), stops.clone());
    let _sensor = Module::builder("sensor")
        .handle(move |_ctx, _q: TooFar| {
            let p = p.clone();
            // true from the third check on
            async move { Ok(p.fetch_add(1, Ordering::SeqCst) >= 2) }
        })
        .handle(move |_ctx, alarm: Alarm| {
            let a = a.clone();
            async move {
                a.lock().unwrap().push(alarm.node);
                Ok(())
            }
        })
        .connect(&central.connector)
        .await
        .unwrap();
    let _worker = Module::builder("worker")
        .handle(move |ctx, _w: Work| {
            let s = s.clone();
            async move {
                let node = ctx.node().unwrap();
                ctx.on_exception::<Stop>(node).await?;
                // Polling monitor: checks every 20 ms, raises `stop` when the condition holds.
                ctx.polling_monitor(
                    node,
                    &TooFar,
                    Duration::from_millis(20),
                    raise_action(&Stop)?,
                )
                .await?;
                // Point monitor: checks once now; false, so the alarm is never sent.
                ctx.point_monitor(node, &TooFar, send_action(&Alarm { node: node.0 })?)
                    .await?;
                // Work until stopped.
                for _ in 0..200 {
                    if s.load(Ordering::SeqCst) > 0 {
                        return Ok(());
                    }
                    tokio::time::sleep(Duration::from_millis(10)).await;
                }
                Err(HandlerError::new("never stopped"))
            }
        })
        .handle(move |ctx, _s: Stop| {
            let stops = stops.clone();
            async move {
                stops.fetch_add(1, Ordering::SeqCst);
                let _ = ctx;
                Ok(())
            }
        })
        .connect(&central.connector)
        .await
        .unwrap();
    let user = Module::builder("user")
        .connect(&central.connector)
        .await
        .unwrap();
    let t = user.send_watched(&Work, []).unwrap();
    assert_eq!(
        within("work", t.outcome()).await.unwrap(),
        TaskOutcome::Achieved
    );
    let checks = polls.load(Ordering::SeqCst);
    assert!(
        checks >= 3,
        "the polling monitor checked until true: {checks}"
    );
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert_eq!(
        polls.load(Ordering::SeqCst),
        checks,
        "monitors end with their node"
    );
    assert!(
        alarms.lock().unwrap().is_empty(),
        "the point monitor's condition was false"
    );
    central.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_tree_cancels_running_handlers_and_drops_waiting_ones() {
    let central = TestCentral::start(TransportKind::InProcess).await;
    let started = Arc::new(AtomicU32::new(0));
    let cancelled = Arc::new(AtomicU32::new(0));
    struct OnDrop(Arc<AtomicU32>);
    impl Drop for OnDrop {
        fn drop(&mut self) {
            self.0.fetch_add(1, Ordering::SeqCst);
        }
    }
    let (s, c) = (started.clone(), cancelled.clone());
    let _ctl = Module::builder("controller")
        .handle(move |_ctx, _m: BodyMove| {
            let (s, c) = (s.clone(), c.clone());
            async move {
                s.fetch_add(1, Ordering::SeqCst);
                let _guard = OnDrop(c);
                tokio::time::sleep(Duration::from_secs(30)).await;
                Ok(())
            }
        })
        .connect(&central.connector)
        .await
        .unwrap();
    let user = Module::builder("user")
        .connect(&central.connector)
        .await
        .unwrap();
    let first = user.send_watched(&BodyMove { step: 1 }, []).unwrap();
    let second = user.send_watched(&BodyMove { step: 2 }, []).unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    let view = user.tree().await.unwrap();
    assert!(view.text.contains("bodyMove"), "{}", view.text);
    // Kill both roots, the waiting one first (killing the running one first would free the
    // controller for it): the running one's handler is cancelled, the waiting one dropped.
    let mut nodes: Vec<u64> = view
        .text
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix('n'))
        .filter_map(|l| l.split_whitespace().next()?.parse().ok())
        .collect();
    assert_eq!(nodes.len(), 2, "{}", view.text);
    nodes.sort_unstable_by(|a, b| b.cmp(a));
    for n in nodes {
        user.kill(NodeId(n)).await.unwrap();
    }
    assert_eq!(
        within("first", first.outcome()).await.unwrap(),
        TaskOutcome::Killed
    );
    assert_eq!(
        within("second", second.outcome()).await.unwrap(),
        TaskOutcome::Killed
    );
    assert_eq!(
        started.load(Ordering::SeqCst),
        1,
        "the waiting command never started"
    );
    assert!(user.tree().await.unwrap().nodes == 0);
    central.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_tree_is_rebuilt_from_the_log_at_any_time() {
    let (t, log, _) = walk(false, None).await;
    let start = log.records.first().unwrap().at_ns;
    let mid = (t.start("bodyMove2") - start) as f64 / 1e9 + 0.001;
    let text = tca_logs::tree_at(&log, Some(mid)).unwrap();
    assert!(text.contains("bodyMove"), "{text}");
    assert!(text.contains("walk"), "{text}");
    let end = tca_logs::tree_at(&log, None).unwrap();
    assert!(end.contains("no live task nodes"), "{end}");
    let _ = TimePoint::HandlingStart;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn log_stats_give_the_figure18_breakdown_in_simulated_time() {
    let (_, log, _, clock) = walk_on(false, None, true).await;
    let stats = tca_logs::stats(&log, tca_logs::TimeBase::Envelope);
    let module = |name: &str| {
        stats
            .modules
            .iter()
            .find(|m| m.module == name)
            .unwrap_or_else(|| panic!("{name}: {stats:#?}"))
    };
    // Six moves of 60 s each; three plans of 30 s each for the gait planner and the LRP.
    assert_eq!(module("controller").computing_s, 360.0);
    assert_eq!(module("controller").handled, 6);
    assert_eq!(module("lrp").computing_s, 90.0);
    assert_eq!(module("gait").computing_s, 90.0);
    assert_eq!(stats.span_s, clock);
    assert_eq!(module("controller").idle_s, clock - 360.0);
    assert_eq!(stats.by_name["planGait"], 3);
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("timeline.png");
    tca_timeline::write_png(&stats, &png).unwrap();
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    let text = tca_timeline::text(&stats, 3);
    assert!(text.contains("controller"), "{text}");
}
