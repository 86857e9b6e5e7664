//! The goal-throughput measurement shared by the bus benchmarks: a sender floods a sink with
//! goals through central, waiting and sending again when central refuses one over its queue
//! limit (backpressure, as a real module would). The sender's loop runs as a task on a worker.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput};
use tca_messages::RouteError;
use tca_module::{Module, ModuleError};
use tca_ping::echo::PingGoal;
use tokio::runtime::Runtime;
use tokio::sync::Notify;

/// Times goals from `sender` until the sink's `count` reaches each sample's target; the sink
/// stores nothing but bumps `count` and wakes `notify` once the count reaches `target`.
pub(crate) fn measure(
    c: &mut Criterion,
    rt: &Runtime,
    name: &str,
    sender: &Module,
    count: &Arc<AtomicU64>,
    target: &Arc<AtomicU64>,
    notify: &Arc<Notify>,
) {
    let mut group = c.benchmark_group("throughput");
    group.throughput(Throughput::Elements(1));
    group.sample_size(10);
    group.bench_function(name, |b| {
        b.iter_custom(|iters| {
            let sender = sender.clone();
            let count = count.clone();
            let target = target.clone();
            let notify = notify.clone();
            // On a worker, as the `tca` command runs (see on_worker.rs).
            let flood = rt.spawn(async move {
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
                    let _ =
                        tokio::time::timeout(Duration::from_millis(10), notify.notified()).await;
                }
                start.elapsed()
            });
            rt.block_on(flood).expect("the timing task panicked")
        })
    });
    group.finish();
}
