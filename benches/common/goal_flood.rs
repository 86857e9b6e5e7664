//! The goal-throughput measurement shared by the bus benchmarks: a sender floods a sink with
//! goals through central, waiting and sending again when central refuses one over its queue
//! limit (backpressure, as a real module would). The sender's loop runs as a task on a worker.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput};
use tca_messages::RouteError;
use tca_module::{Module, ModuleBuilder, ModuleError};
use tca_ping::echo::PingGoal;
use tokio::runtime::Runtime;
use tokio::sync::Notify;

/// Times goals from `sender` until the sink counting into `goals` has handled each sample's
/// number of them.
pub(crate) fn measure(
    c: &mut Criterion,
    rt: &Runtime,
    name: &str,
    sender: &Module,
    goals: &GoalCount,
) {
    let mut group = c.benchmark_group("throughput");
    group.throughput(Throughput::Elements(1));
    group.sample_size(10);
    group.bench_function(name, |b| {
        b.iter_custom(|iters| {
            // On a worker, as the `tca` command runs (see on_worker.rs).
            let flood = rt.spawn(flood(sender.clone(), goals.clone(), iters));
            rt.block_on(flood).expect("the timing task panicked")
        })
    });
    group.finish();
}

/// Sends `iters` goals from `sender` (waiting and sending again while central refuses one
/// over its queue limit) and returns the time until the sink's `count` has grown by `iters`.
/// Call it on a runtime worker.
pub(crate) async fn flood(sender: Module, goals: GoalCount, iters: u64) -> Duration {
    let GoalCount {
        count,
        target,
        notify,
    } = goals;
    let goal_count = count.load(Ordering::Relaxed) + iters;
    target.store(goal_count, Ordering::Relaxed);
    let start = Instant::now();
    for seq in 0..iters {
        while let Err(e) = sender.goal(&PingGoal { seq }) {
            match e {
                ModuleError::Route(RouteError::OverLimit { .. }) => {
                    tokio::time::sleep(Duration::from_micros(100)).await
                }
                other => panic!("sending a goal failed: {other}"),
            }
        }
    }
    while count.load(Ordering::Relaxed) < goal_count {
        let _ = tokio::time::timeout(Duration::from_millis(10), notify.notified()).await;
    }
    start.elapsed()
}

/// What a sink module counts: the goals it has handled, the count at which it wakes the
/// timing loop (once, so that a wake per goal does not time tokio's `Notify` as much as
/// central), and that wake.
#[derive(Clone)]
pub(crate) struct GoalCount {
    pub(crate) count: Arc<AtomicU64>,
    pub(crate) target: Arc<AtomicU64>,
    pub(crate) notify: Arc<Notify>,
}

impl GoalCount {
    pub(crate) fn new() -> Self {
        GoalCount {
            count: Arc::new(AtomicU64::new(0)),
            target: Arc::new(AtomicU64::new(u64::MAX)),
            notify: Arc::new(Notify::new()),
        }
    }

    /// A sink module named `name` (room for 4,096 goals at once) counting into `self`.
    pub(crate) fn sink(&self, name: impl Into<String>) -> ModuleBuilder {
        let (count, target, notify) =
            (self.count.clone(), self.target.clone(), self.notify.clone());
        Module::builder(name)
            .capacity(4096)
            .handle(move |_ctx, _g: PingGoal| {
                if count.fetch_add(1, Ordering::Relaxed) + 1 >= target.load(Ordering::Relaxed) {
                    notify.notify_one();
                }
                async { Ok(()) }
            })
    }
}
