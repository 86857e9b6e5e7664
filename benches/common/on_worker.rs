//! Timing loops that run as a task on the runtime's workers, as the `tca` command runs its
//! work. Criterion's `to_async` drives each iteration from the bench thread with `block_on`,
//! outside the worker pool, so every wake between the caller and the tasks it talks to would
//! cross threads; that measures the runtime's hand-offs more than the bus.

use std::future::Future;
use std::time::{Duration, Instant};

use tokio::runtime::Runtime;

/// Runs `step` `iters` times, one after the other, in a task on one of `rt`'s workers, and
/// returns the time the loop took.
pub(crate) fn time_on_worker<F, Fut>(rt: &Runtime, iters: u64, mut step: F) -> Duration
where
    F: FnMut() -> Fut + Send + 'static,
    Fut: Future + Send + 'static,
{
    rt.block_on(rt.spawn(async move {
        let start = Instant::now();
        for _ in 0..iters {
            step().await;
        }
        start.elapsed()
    }))
    .expect("the timing task panicked")
}

/// Runs `step` `n` times in a task on one of `rt`'s workers and returns each call's time.
#[allow(dead_code)] // each bench file includes this module; not every one takes samples
pub(crate) fn samples_on_worker<F, Fut>(rt: &Runtime, n: usize, mut step: F) -> Vec<Duration>
where
    F: FnMut() -> Fut + Send + 'static,
    Fut: Future + Send + 'static,
{
    rt.block_on(rt.spawn(async move {
        let mut samples = Vec::with_capacity(n);
        for _ in 0..n {
            let start = Instant::now();
            step().await;
            samples.push(start.elapsed());
        }
        samples
    }))
    .expect("the timing task panicked")
}
