//! What central's journal costs in goal throughput, in-process, logging on: two centrals side
//! by side in this process, one without a journal and one with it, each with its own sender
//! and sink, flooded in turn (A B, then B A, and so on) so that both see the same moments of
//! the machine. Each pair gives a cost, `1 - journaled / plain`; the bench prints every pair,
//! their mean and median, and a 95 % bootstrap interval of the mean.
//!
//! A criterion run of one configuration after the other cannot show a 10 % effect on this
//! machine: the same binary's throughput moves by about ±15 % from one run to the next, and
//! that drift lands wholly on one side of the comparison. Alternating short floods puts it on
//! both sides.
//!
//! Run: `cargo bench --bench journal_cost` (`JOURNAL_PAIRS`, default 30, and `JOURNAL_GOALS`
//! per flood, default 100000). Figures in BENCHMARKS.md.
//!
//! `JOURNAL_AA=1` runs the same pairs with neither side keeping a journal: the "cost" it
//! prints is the bench's own bias (the order the sides were started in, their memory), which
//! should be near zero.
//!
//! For a profiler, `JOURNAL_ONLY=with` (or `without`) floods one side alone, `JOURNAL_PAIRS`
//! times, so that a profile of the process shows that side's costs and no other's.

use std::time::Duration;

use rand::{Rng, SeedableRng};
use tca_central::{RunningCentral, StartOptions};
use tca_module::{Connector, Module};
use tokio::runtime::Runtime;

// Shared with the criterion benches; its criterion helper is not used here.
#[path = "common/goal_flood.rs"]
#[allow(dead_code)]
mod goal_flood;
use goal_flood::{GoalCount, flood};

/// The allocator the `tca` command uses, so that what is measured here is what it runs.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// A central with a sender and a sink connected in-process.
struct Side {
    central: RunningCentral,
    sender: Module,
    _sink: Module,
    goals: GoalCount,
    _dir: tempfile::TempDir,
}

impl Side {
    async fn start(journal: bool) -> Side {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let central = tca_central::start(StartOptions {
            log: Some(dir.path().join("bench.mcap")),
            journal: journal.then(|| dir.path().join("central.journal")),
            ..StartOptions::default()
        })
        .await
        .expect("central starts");
        let connector = Connector::from(central.in_process());
        let goals = GoalCount::new();
        let sink = goals.sink("sink").connect(&connector).await.expect("sink");
        let sender = Module::builder("sender")
            .connect(&connector)
            .await
            .expect("sender");
        Side {
            central,
            sender,
            _sink: sink,
            goals,
            _dir: dir,
        }
    }

    /// Goals per second over a flood of `n` goals, timed on a runtime worker.
    fn rate(&self, rt: &Runtime, n: u64) -> f64 {
        let took: Duration = rt
            .block_on(rt.spawn(flood(self.sender.clone(), self.goals.clone(), n)))
            .expect("the flood task panicked");
        n as f64 / took.as_secs_f64()
    }
}

fn env_u64(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(v) => v.parse().unwrap_or_else(|_| {
            eprintln!("{name}={v} is not a whole number; using {default}");
            default
        }),
        Err(_) => default,
    }
}

fn mean(xs: &[f64]) -> f64 {
    xs.iter().sum::<f64>() / xs.len() as f64
}

fn median(xs: &[f64]) -> f64 {
    let mut s = xs.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len().is_multiple_of(2) {
        (s[m - 1] + s[m]) / 2.0
    } else {
        s[m]
    }
}

/// The 2.5th and 97.5th percentiles of the mean of `xs` over resamples with replacement.
fn bootstrap_mean_interval(xs: &[f64]) -> (f64, f64) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut means: Vec<f64> = (0..10_000)
        .map(|_| {
            let sum: f64 = (0..xs.len())
                .map(|_| xs[rng.random_range(0..xs.len())])
                .sum();
            sum / xs.len() as f64
        })
        .collect();
    means.sort_by(f64::total_cmp);
    (means[249], means[9749])
}

fn main() {
    // `cargo bench` passes `--bench`; any other argument is a filter this bench ignores.
    let pairs = env_u64("JOURNAL_PAIRS", 30).max(2) as usize;
    let goals = env_u64("JOURNAL_GOALS", 100_000).max(1_000);
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    if let Ok(only) = std::env::var("JOURNAL_ONLY") {
        let journal = match only.as_str() {
            "with" => true,
            "without" => false,
            _ => {
                eprintln!("JOURNAL_ONLY={only}: give `with` or `without`");
                std::process::exit(2);
            }
        };
        let side = rt.block_on(Side::start(journal));
        side.rate(&rt, goals / 2);
        let rates: Vec<f64> = (0..pairs).map(|_| side.rate(&rt, goals)).collect();
        println!(
            "journal_cost: {only} a journal alone, {pairs} floods of {goals} goals: mean {:.0} \
             goals/s, median {:.0}",
            mean(&rates),
            median(&rates)
        );
        rt.block_on(side.central.shutdown()).expect("shutdown");
        return;
    }
    let plain = rt.block_on(Side::start(false));
    let aa = std::env::var("JOURNAL_AA").is_ok_and(|v| v == "1");
    let journaled = rt.block_on(Side::start(!aa));
    // Warm-up: allocators, the log files and the journal's first rewrite.
    plain.rate(&rt, goals / 2);
    journaled.rate(&rt, goals / 2);
    println!("journal_cost: {pairs} pairs of {goals}-goal floods, in-process, logging on");
    if aa {
        println!("JOURNAL_AA=1: neither side keeps a journal (the bench's own bias)");
    }
    let mut costs = Vec::with_capacity(pairs);
    let (mut sum_plain, mut sum_journaled) = (0.0, 0.0);
    for i in 0..pairs {
        let (p, j) = if i.is_multiple_of(2) {
            let p = plain.rate(&rt, goals);
            (p, journaled.rate(&rt, goals))
        } else {
            let j = journaled.rate(&rt, goals);
            (plain.rate(&rt, goals), j)
        };
        sum_plain += p;
        sum_journaled += j;
        let cost = 1.0 - j / p;
        costs.push(cost);
        println!(
            "pair {i:2}: without {p:9.0} goals/s, with a journal {j:9.0} goals/s, cost {:6.1} %",
            100.0 * cost
        );
    }
    let (lo, hi) = bootstrap_mean_interval(&costs);
    println!(
        "mean without {:.0} goals/s, with {:.0} goals/s",
        sum_plain / pairs as f64,
        sum_journaled / pairs as f64
    );
    println!(
        "cost: mean {:.1} %, median {:.1} %, 95 % interval of the mean {:.1} % to {:.1} %",
        100.0 * mean(&costs),
        100.0 * median(&costs),
        100.0 * lo,
        100.0 * hi
    );
    println!(
        "target (at most 10 %): {}",
        if hi <= 0.10 {
            "met: the interval's upper end is at most 10 %"
        } else if lo > 0.10 {
            "NOT met: the whole interval is above 10 %"
        } else {
            "not shown: the interval reaches above 10 %"
        }
    );
    rt.block_on(async {
        plain.central.shutdown().await.expect("shutdown");
        journaled.central.shutdown().await.expect("shutdown");
    });
}
