//! Load on central: many modules, each handling a query, a goal and an inform of its own and
//! sending all three to randomly chosen other modules, through one central with its traffic
//! log on, for a fixed time; then every message is accounted for.
//!
//! Each module keeps at most `window` queries and goals in flight and sends an inform whenever
//! its draw says so, so the load is as much as central and the modules can take (closed loop).
//! A message central refuses because its sender is over a limit (`RouteError::OverLimit`, at
//! once or as the goal's outcome) is sent again after a millisecond: backpressure, as a real
//! module would meet it. At the end every query must have had its reply, every goal must have
//! ended achieved, and every inform must have reached its handler ([`LoadReport::losses`]).
//!
//! Used by `benches/load.rs` (the figures in BENCHMARKS.md) and by `tests/load.rs`.
//!
//! # Layout
//!
//! - this file: [`LoadOptions`], [`TransportKind`], [`run`]: the modules, their senders and
//!   the tally of what was sent, handled and answered.
//! - `report`: [`LoadReport`], what a run found, as text.
//! - `memory`: the process's resident memory, sampled while the load runs.

mod memory;
mod report;

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::time::{Duration, Instant};

use anyhow::{Context as _, bail};
use tca_central::{CentralConfig, StartOptions};
use tca_messages::control::{Registration, TaskOutcome};
use tca_messages::{Class, DataFormat, MessageName, RouteError, encode_data};
use tca_module::{Connector, Module, ModuleError};
use tokio::task::JoinSet;

pub use memory::{peak_rss_kib, reset_peak_rss, rss_kib};
pub use report::{ClassCounts, LoadReport};

/// How central is reached.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportKind {
    /// Central and the modules share channels in this process.
    InProcess,
    /// Central listens on a free loopback port; each module is its own zenoh client session.
    Zenoh,
    /// Central listens on a Unix socket of its own (`local/load-PID-N`); each module is its
    /// own connection over the local link.
    Local,
}

impl TransportKind {
    /// A word for tables.
    pub fn label(self) -> &'static str {
        match self {
            TransportKind::InProcess => "in-process",
            TransportKind::Zenoh => "zenoh",
            TransportKind::Local => "local",
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Modules connected to central.
    pub modules: usize,
    /// How long the modules send.
    pub duration: Duration,
    /// Queries and goals one module has in flight at most.
    pub window: usize,
    /// Goals one module handles at once (its hello's capacity).
    pub capacity: u32,
    /// How central is reached.
    pub transport: TransportKind,
    /// Central's limits.
    pub config: CentralConfig,
    /// Seed of the modules' random choices.
    pub seed: u64,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            modules: 100,
            duration: Duration::from_secs(60),
            window: 16,
            capacity: 4,
            transport: TransportKind::InProcess,
            config: CentralConfig::default(),
            seed: 1,
        }
    }
}

/// Longest the end of a run may take: in-flight messages answered, informs delivered.
const SETTLE: Duration = Duration::from_secs(120);

/// How long a refused sender waits before it sends again.
const BACK_OFF: Duration = Duration::from_millis(1);

/// Counters shared by every module of a run.
#[derive(Debug, Default)]
struct Tally {
    queries: Counts,
    goals: Counts,
    informs: Counts,
}

#[derive(Debug, Default)]
struct Counts {
    sent: AtomicU64,
    handled: AtomicU64,
    completed: AtomicU64,
    refused: AtomicU64,
    failed: AtomicU64,
}

impl Counts {
    fn snapshot(&self) -> ClassCounts {
        ClassCounts {
            sent: self.sent.load(Relaxed),
            handled: self.handled.load(Relaxed),
            completed: self.completed.load(Relaxed),
            refused: self.refused.load(Relaxed),
            failed: self.failed.load(Relaxed),
        }
    }
}

fn name(module: usize, class: &str) -> String {
    format!("load-{module:03}.{class}")
}

/// Starts central (logging into `log_dir`), connects the modules, runs the load and accounts
/// for every message.
pub async fn run(options: &LoadOptions, log_dir: &Path) -> anyhow::Result<LoadReport> {
    if options.modules < 2 || options.window == 0 {
        bail!("a load needs at least 2 modules and a window of at least 1");
    }
    let log = log_dir.join("load.mcap");
    let endpoint = match options.transport {
        TransportKind::InProcess | TransportKind::Zenoh => free_endpoint()?,
        TransportKind::Local => unique_local_endpoint(),
    };
    let central = tca_central::start(StartOptions {
        config: options.config.clone(),
        log: Some(log.clone()),
        listen: match options.transport {
            TransportKind::InProcess => vec![],
            TransportKind::Zenoh | TransportKind::Local => vec![endpoint.clone()],
        },
        ..StartOptions::default()
    })
    .await
    .context("central did not start")?;
    let connector = match options.transport {
        TransportKind::InProcess => Connector::from(central.in_process()),
        TransportKind::Zenoh | TransportKind::Local => Connector::endpoint(endpoint),
    };
    let tally = Arc::new(Tally::default());
    let connecting = Instant::now();
    let modules = connect_all(options, &connector, &tally).await?;
    let connect_time = connecting.elapsed();

    let rss_before_kib = rss_kib();
    let peak_reset = reset_peak_rss();
    let sampling = Arc::new(AtomicBool::new(true));
    let sampler = tokio::spawn(memory::sample_rss(sampling.clone(), Duration::from_secs(1)));

    let start = Instant::now();
    let deadline = tokio::time::Instant::now() + options.duration;
    let mut senders = JoinSet::new();
    for (i, module) in modules.iter().enumerate() {
        let seed = options.seed ^ ((i as u64 + 1) << 32);
        let job = send_until(
            module.clone(),
            i,
            options.modules,
            options.window,
            deadline,
            seed,
            tally.clone(),
        );
        senders.spawn(job);
    }
    // The senders return when their last query and goal are answered.
    let settled = tokio::time::timeout(options.duration + SETTLE, senders.join_all()).await;
    if settled.is_err() {
        bail!("the modules' last queries and goals were not answered within {SETTLE:?} of the end");
    }
    let sending = start.elapsed();
    // Informs have no answer: wait until each has reached its handler, or stop counting.
    let informs = &tally.informs;
    let until = Instant::now() + SETTLE;
    while informs.handled.load(Relaxed) < informs.sent.load(Relaxed) && Instant::now() < until {
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let elapsed = start.elapsed();
    sampling.store(false, Relaxed);
    let rss_samples_kib = sampler.await.unwrap_or_default();
    let peak_rss_kib = peak_rss_kib();

    for m in &modules {
        m.close().await;
    }
    drop(modules);
    let central_stats = central
        .shutdown()
        .await
        .context("central did not stop cleanly")?;
    let log_bytes = std::fs::metadata(&log).map(|m| m.len()).unwrap_or(0);
    Ok(LoadReport {
        modules: options.modules,
        transport: options.transport,
        window: options.window,
        duration: options.duration,
        connect_time,
        sending,
        elapsed,
        queries: tally.queries.snapshot(),
        goals: tally.goals.snapshot(),
        informs: ClassCounts {
            // An inform is complete when its handler has it.
            completed: tally.informs.handled.load(Relaxed),
            ..tally.informs.snapshot()
        },
        central: central_stats,
        config: options.config.clone(),
        rss_before_kib,
        rss_samples_kib,
        peak_rss_kib,
        peak_reset,
        log_bytes,
    })
}

/// A zenoh endpoint on a free loopback port.
fn free_endpoint() -> anyhow::Result<String> {
    tca_link::net::free_loopback_endpoint().context("no free loopback port")
}

/// A local endpoint no other run (in this process or another) uses.
fn unique_local_endpoint() -> String {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    format!(
        "local/load-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Relaxed)
    )
}

/// Connects the modules, a few at a time, each handling its query, goal and inform.
async fn connect_all(
    options: &LoadOptions,
    connector: &Connector,
    tally: &Arc<Tally>,
) -> anyhow::Result<Vec<Module>> {
    let mut modules = Vec::with_capacity(options.modules);
    let indices: Vec<usize> = (0..options.modules).collect();
    for batch in indices.chunks(10) {
        let mut connecting = JoinSet::new();
        for &i in batch {
            let builder = builder(i, options.capacity, tally)?;
            let connector = connector.clone();
            connecting.spawn(async move { (i, builder.connect(&connector).await) });
        }
        let mut connected = connecting.join_all().await;
        connected.sort_by_key(|(i, _)| *i);
        for (i, m) in connected {
            modules.push(m.with_context(|| format!("module {i} did not connect"))?);
        }
    }
    Ok(modules)
}

fn registration(module: usize, class: Class) -> anyhow::Result<Registration> {
    let word = match class {
        Class::Query => "query",
        Class::Goal => "goal",
        _ => "inform",
    };
    Ok(Registration {
        name: MessageName::new(name(module, word))?,
        class,
        format: DataFormat::of::<u64>()?,
        reply: (class == Class::Query)
            .then(DataFormat::of::<u64>)
            .transpose()?,
        replace: false,
    })
}

fn builder(
    i: usize,
    capacity: u32,
    tally: &Arc<Tally>,
) -> anyhow::Result<tca_module::ModuleBuilder> {
    let (q, g, n) = (tally.clone(), tally.clone(), tally.clone());
    Ok(Module::builder(format!("load-{i:03}"))
        .capacity(capacity)
        .query_timeout(SETTLE)
        .handle_raw(registration(i, Class::Query)?, move |_ctx, data| {
            q.queries.handled.fetch_add(1, Relaxed);
            async move { Ok(data) }
        })
        .handle_raw(registration(i, Class::Goal)?, move |_ctx, _data| {
            g.goals.handled.fetch_add(1, Relaxed);
            async { Ok(Vec::new()) }
        })
        .handle_raw(registration(i, Class::Inform)?, move |_ctx, _data| {
            n.informs.handled.fetch_add(1, Relaxed);
            async { Ok(Vec::new()) }
        }))
}

/// Sends to random other modules until `deadline`, then waits for its last answers.
async fn send_until(
    module: Module,
    me: usize,
    modules: usize,
    window: usize,
    deadline: tokio::time::Instant,
    seed: u64,
    tally: Arc<Tally>,
) {
    let mut draw = SplitMix(seed);
    let mut in_flight = JoinSet::new();
    let mut seq = 0u64;
    while tokio::time::Instant::now() < deadline {
        // Finished ones are reaped here too: the set never holds more than the window.
        while in_flight.len() >= window {
            in_flight.join_next().await;
        }
        let to = (me + 1 + draw.below(modules as u64 - 1) as usize) % modules;
        seq += 1;
        let data = encode_data(&(((me as u64) << 40) | seq)).unwrap_or_default();
        match draw.below(3) {
            0 => {
                in_flight.spawn(query(
                    module.clone(),
                    name(to, "query"),
                    data,
                    tally.clone(),
                ));
            }
            1 => {
                in_flight.spawn(goal(module.clone(), name(to, "goal"), data, tally.clone()));
            }
            _ => inform(&module, &name(to, "inform"), data, &tally).await,
        }
    }
    while in_flight.join_next().await.is_some() {}
}

/// Whether central refused a message because its sender is over a limit: send it again later.
fn over_limit(e: &ModuleError) -> bool {
    matches!(e, ModuleError::Route(RouteError::OverLimit { .. }))
}

async fn query(module: Module, name: String, data: Vec<u8>, tally: Arc<Tally>) {
    let c = &tally.queries;
    c.sent.fetch_add(1, Relaxed);
    loop {
        match module.query_raw(&name, data.clone(), None).await {
            Ok(reply) if reply == data => {
                c.completed.fetch_add(1, Relaxed);
                return;
            }
            Err(e) if over_limit(&e) => {
                c.refused.fetch_add(1, Relaxed);
                tokio::time::sleep(BACK_OFF).await;
            }
            Ok(_) => {
                c.failed.fetch_add(1, Relaxed);
                tracing::warn!(%name, "a reply did not echo its query");
                return;
            }
            Err(e) => {
                c.failed.fetch_add(1, Relaxed);
                tracing::warn!(%name, error = %e, "query failed");
                return;
            }
        }
    }
}

async fn goal(module: Module, name: String, data: Vec<u8>, tally: Arc<Tally>) {
    let c = &tally.goals;
    c.sent.fetch_add(1, Relaxed);
    loop {
        // A refusal comes at once (the sender's inbox in central) or as the goal's outcome
        // (its queue in central).
        let outcome = match module.send_watched_raw(Class::Goal, &name, data.clone(), []) {
            Ok(task) => task.outcome().await,
            Err(e) => Err(e),
        };
        match outcome {
            Ok(TaskOutcome::Achieved) => {
                c.completed.fetch_add(1, Relaxed);
                return;
            }
            Err(e) if over_limit(&e) => {
                c.refused.fetch_add(1, Relaxed);
                tokio::time::sleep(BACK_OFF).await;
            }
            Ok(other) => {
                c.failed.fetch_add(1, Relaxed);
                tracing::warn!(%name, outcome = ?other, "goal not achieved");
                return;
            }
            Err(e) => {
                c.failed.fetch_add(1, Relaxed);
                tracing::warn!(%name, error = %e, "goal failed");
                return;
            }
        }
    }
}

async fn inform(module: &Module, name: &str, data: Vec<u8>, tally: &Tally) {
    let c = &tally.informs;
    loop {
        match module.send_raw(Class::Inform, name, data.clone(), []) {
            Ok(_) => {
                c.sent.fetch_add(1, Relaxed);
                return;
            }
            Err(e) if over_limit(&e) => {
                c.refused.fetch_add(1, Relaxed);
                tokio::time::sleep(BACK_OFF).await;
            }
            Err(e) => {
                c.failed.fetch_add(1, Relaxed);
                tracing::warn!(%name, error = %e, "inform failed");
                return;
            }
        }
    }
}

/// SplitMix64: the modules' random choices, reproducible from the seed.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (n > 0).
    fn below(&mut self, n: u64) -> u64 {
        ((u128::from(self.next()) * u128::from(n)) >> 64) as u64
    }
}
