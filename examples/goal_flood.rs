//! Sends N goals through an in-process central (logging on) to a sink module and prints the
//! rate: a quick profile target for `perf` and `valgrind --tool=callgrind`.
//!
//! `cargo run --release --example goal_flood -- 100000`

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use tca_central::StartOptions;
use tca_module::{Connector, Module};
use tca_ping::PingGoal;

/// The allocator the `tca` command uses, so that what is measured here is what it runs.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() -> anyhow::Result<()> {
    let n: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(50_000);
    let dir = tempfile::tempdir()?;
    let central = tca_central::start(StartOptions {
        log: std::env::var("NO_LOG")
            .is_err()
            .then(|| dir.path().join("flood.mcap")),
        ..StartOptions::default()
    })
    .await?;
    let connector = Connector::from(central.in_process());
    let count = Arc::new(AtomicU64::new(0));
    let c = count.clone();
    let _sink = Module::builder("sink")
        .capacity(4096)
        .handle(move |_ctx, _g: PingGoal| {
            let c = c.clone();
            async move {
                c.fetch_add(1, Ordering::Relaxed);
                Ok(())
            }
        })
        .connect(&connector)
        .await?;
    let sender = Module::builder("sender").connect(&connector).await?;
    let start = Instant::now();
    for seq in 0..n {
        sender.goal(&PingGoal { seq })?;
    }
    let sent = start.elapsed();
    while count.load(Ordering::Relaxed) < n {
        tokio::time::sleep(Duration::from_millis(1)).await;
    }
    let took = start.elapsed();
    println!(
        "{n} goals: sent in {sent:?}, all handled in {took:?}: {:.0} goals/s",
        n as f64 / took.as_secs_f64()
    );
    central.shutdown().await?;
    Ok(())
}
