//! The planner's side: a [`Joiner`] that hands each batch of joins to the workers owning
//! them, all at once, and replaces a worker that dies.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::process::Stdio;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use futures::future::{BoxFuture, join_all};
use tca_cg_space::{
    CgGrid, CgRobot, CgSpace, FootMap, JoinError, JoinQuery, Joiner, Joins, Partition, fingerprint,
};
use tca_messages::{decode_data, encode_data};
use tca_module::{Connector, Module, ModuleError};
use tokio::io::AsyncBufReadExt;
use tokio::runtime::{Handle, RuntimeFlavor};

use crate::messages::{JoinBatch, JoinReply, WorkerCounters, join_name, worker_name};
use crate::worker::connect_worker;

/// A running worker, as its factory started it.
pub trait WorkerHandle: Send {
    /// Stops it (closes its module, ends its process).
    fn stop(self: Box<Self>) -> BoxFuture<'static, ()>;

    /// If it has ended by itself: why (what it last said).
    fn ended(&mut self) -> Option<String> {
        None
    }
}

/// Starts workers: at the beginning, and to replace one that died. The replacement of worker
/// K is started under the same index, so it takes over worker K's strip and message, and
/// rebuilds its regions on demand.
pub trait WorkerFactory: Send + Sync {
    /// Starts worker `index`. It need not have joined central when this returns: the joiner
    /// waits until it has registered.
    fn start(&self, index: usize) -> BoxFuture<'_, Result<Box<dyn WorkerHandle>, JoinError>>;
}

/// Workers in this process, on a central reached through `connector`: each its own module
/// and CG-space (sharing the robot's tables and the foot map), under one region cap.
#[derive(Clone)]
pub struct InProcessWorkers {
    connector: Connector,
    template: CgSpace,
    region_cap: Option<usize>,
    live: Arc<Mutex<Vec<Option<Module>>>>,
}

impl InProcessWorkers {
    /// Workers over the robot, grid and foot map of `space`, each holding at most
    /// `region_cap` regions.
    pub fn new(connector: Connector, space: &CgSpace, region_cap: Option<usize>) -> Self {
        InProcessWorkers {
            connector,
            template: CgSpace::with_foot_map(
                space.robot().clone(),
                *space.grid(),
                space.foot_shared(),
            ),
            region_cap,
            live: Arc::new(Mutex::new(Vec::new())),
        }
    }

    /// The module of worker `index` as last started (a test closes it to make the worker
    /// die).
    pub fn module(&self, index: usize) -> Option<Module> {
        self.live
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .get(index)
            .cloned()
            .flatten()
    }
}

struct InProcessHandle(Module);

impl WorkerHandle for InProcessHandle {
    fn stop(self: Box<Self>) -> BoxFuture<'static, ()> {
        Box::pin(async move {
            if !self.0.is_closed() {
                self.0.close().await;
            }
        })
    }
}

impl WorkerFactory for InProcessWorkers {
    fn start(&self, index: usize) -> BoxFuture<'_, Result<Box<dyn WorkerHandle>, JoinError>> {
        Box::pin(async move {
            let module = connect_worker(
                &self.connector,
                index,
                self.template.clone(),
                self.region_cap,
            )
            .await
            .map_err(|e| JoinError::new(format!("worker {index} cannot start: {e}")))?;
            let mut live = self.live.lock().unwrap_or_else(PoisonError::into_inner);
            if live.len() <= index {
                live.resize(index + 1, None);
            }
            live[index] = Some(module.clone());
            Ok(Box::new(InProcessHandle(module)) as Box<dyn WorkerHandle>)
        })
    }
}

/// Workers as processes: `program ARGS... --index K` for worker K (e.g. the `tca` binary
/// with `module cgspace-worker --connect ENDPOINT --robot R --terrain F`). Each is killed
/// when its handle is dropped, and (as the `tca` binary's modules do when started with
/// [`tca_launch::LAUNCHER_PID_ENV`] set) stops by itself within half a second of this
/// process ending; what it last wrote on its standard error is kept, to say why it ended.
#[derive(Debug, Clone)]
pub struct ProcessWorkers {
    program: PathBuf,
    args: Vec<String>,
    pids: Arc<Mutex<Vec<Option<u32>>>>,
}

impl ProcessWorkers {
    /// Workers run as `program args... --index K`.
    pub fn new(program: impl Into<PathBuf>, args: Vec<String>) -> Self {
        ProcessWorkers {
            program: program.into(),
            args,
            pids: Arc::new(Mutex::new(Vec::new())),
        }
    }

    /// The process id of worker `index` as last started.
    pub fn pid(&self, index: usize) -> Option<u32> {
        self.pids
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .get(index)
            .copied()
            .flatten()
    }
}

/// Lines of a worker's standard error kept.
const KEPT_LINES: usize = 12;

struct ProcessHandle {
    child: tokio::process::Child,
    said: Arc<Mutex<VecDeque<String>>>,
}

impl ProcessHandle {
    fn last_words(&self) -> String {
        let said = self.said.lock().unwrap_or_else(PoisonError::into_inner);
        said.iter().cloned().collect::<Vec<_>>().join(" / ")
    }
}

impl WorkerHandle for ProcessHandle {
    fn stop(mut self: Box<Self>) -> BoxFuture<'static, ()> {
        Box::pin(async move {
            if self.child.try_wait().ok().flatten().is_none()
                && let Err(e) = self.child.kill().await
            {
                tracing::warn!(error = %e, "cannot stop a CG-space worker process");
            }
        })
    }

    fn ended(&mut self) -> Option<String> {
        match self.child.try_wait() {
            Ok(Some(status)) => Some(format!("it exited ({status}): {}", self.last_words())),
            Ok(None) => None,
            Err(e) => Some(format!("it cannot be watched: {e}")),
        }
    }
}

impl WorkerFactory for ProcessWorkers {
    fn start(&self, index: usize) -> BoxFuture<'_, Result<Box<dyn WorkerHandle>, JoinError>> {
        Box::pin(async move {
            let mut child = tokio::process::Command::new(&self.program)
                .args(&self.args)
                .args(["--index", &index.to_string()])
                // A worker whose planner has gone (even killed with SIGKILL, which drops no
                // handle) notices and stops.
                .env(tca_launch::LAUNCHER_PID_ENV, std::process::id().to_string())
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .kill_on_drop(true)
                .spawn()
                .map_err(|e| {
                    JoinError::new(format!(
                        "worker {index}: cannot start {}: {e}",
                        self.program.display()
                    ))
                })?;
            {
                let mut pids = self.pids.lock().unwrap_or_else(PoisonError::into_inner);
                if pids.len() <= index {
                    pids.resize(index + 1, None);
                }
                pids[index] = child.id();
            }
            let said = Arc::new(Mutex::new(VecDeque::new()));
            if let Some(err) = child.stderr.take() {
                let said = said.clone();
                tokio::spawn(async move {
                    let mut lines = tokio::io::BufReader::new(err).lines();
                    while let Ok(Some(line)) = lines.next_line().await {
                        tracing::debug!(worker = index, "{line}");
                        let mut said = said.lock().unwrap_or_else(PoisonError::into_inner);
                        if said.len() == KEPT_LINES {
                            said.pop_front();
                        }
                        said.push_back(line);
                    }
                });
            }
            Ok(Box::new(ProcessHandle { child, said }) as Box<dyn WorkerHandle>)
        })
    }
}

/// Workers started elsewhere (by hand on other machines, or by a supervisor that restarts
/// them): starting one only waits for it to register, and a replacement is the same worker
/// started again from outside within the joiner's `start_timeout`. Stopping does nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct ExternalWorkers;

struct ExternalHandle;

impl WorkerHandle for ExternalHandle {
    fn stop(self: Box<Self>) -> BoxFuture<'static, ()> {
        Box::pin(async {})
    }
}

impl WorkerFactory for ExternalWorkers {
    fn start(&self, index: usize) -> BoxFuture<'_, Result<Box<dyn WorkerHandle>, JoinError>> {
        tracing::info!(
            worker = index,
            "waiting for {} to join central",
            worker_name(index)
        );
        Box::pin(async { Ok(Box::new(ExternalHandle) as Box<dyn WorkerHandle>) })
    }
}

/// How the joiner waits and how often it replaces.
#[derive(Debug, Clone, PartialEq)]
pub struct JoinerOptions {
    /// Longest wait for one worker's answer to one batch before it is taken for dead.
    pub query_timeout: Duration,
    /// How often, while waiting, the joiner checks with central that each worker it waits
    /// for is still connected.
    pub watch_every: Duration,
    /// Longest wait for a started worker to register.
    pub start_timeout: Duration,
    /// Most replacements over the joiner's life (a worker that dies every time it starts
    /// ends the planning instead of looping).
    pub max_replacements: u64,
}

impl Default for JoinerOptions {
    fn default() -> Self {
        JoinerOptions {
            query_timeout: Duration::from_secs(300),
            watch_every: Duration::from_millis(200),
            start_timeout: Duration::from_secs(30),
            max_replacements: 16,
        }
    }
}

/// What the joiner has done.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct JoinStats {
    /// Batches joined.
    pub batches: u64,
    /// Queries answered.
    pub queries: u64,
    /// Queries sent to each worker.
    pub queries_per_worker: Vec<u64>,
    /// Workers replaced after they died.
    pub replacements: u64,
    /// Shares of a batch sent again (to a replacement).
    pub resent: u64,
    /// Each worker's counters at its latest answer (a replacement starts from zero).
    pub workers: Vec<WorkerCounters>,
}

impl JoinStats {
    /// Cells evaluated by all workers (as last reported).
    pub fn cells_evaluated(&self) -> u64 {
        self.workers.iter().map(|c| c.cells_evaluated).sum()
    }

    /// Regions materialised by all workers (as last reported).
    pub fn regions_materialised(&self) -> u64 {
        self.workers.iter().map(|c| c.regions_materialised).sum()
    }
}

struct Slot {
    handle: Option<Box<dyn WorkerHandle>>,
}

struct Shared {
    /// The module the joins are asked from: the planner's own, or a handler's (see
    /// [`DistributedJoiner::ask_as`]).
    module: Mutex<Module>,
    workers: usize,
    factory: Arc<dyn WorkerFactory>,
    slots: Vec<tokio::sync::Mutex<Slot>>,
    generations: Vec<AtomicU64>,
    options: JoinerOptions,
    stats: Mutex<JoinStats>,
}

/// A [`Joiner`] over workers on the bus: worker K (module `cgspace-worker-K`, query
/// `cgspace.join.K`) answers the queries of strip K of the [`Partition`]; a batch's shares go
/// to their workers at once and the joiner waits for all. A worker that dies (its query
/// fails, or central no longer has it connected) is replaced through the factory and its
/// share sent again.
///
/// `join` blocks its thread: call it from a thread that is not one of tokio's (e.g. inside
/// `spawn_blocking`), or from a multi-threaded runtime, where it steps aside with
/// `block_in_place`.
pub struct DistributedJoiner {
    shared: Arc<Shared>,
    runtime: Handle,
    /// The last space's fingerprint, kept while its robot tables, grid and foot map are the
    /// same ones (holding the foot map makes any change to it a copy: a new pointer).
    print: Option<(Arc<CgRobot>, Arc<FootMap>, CgGrid, u64)>,
}

impl DistributedJoiner {
    /// Starts `workers` workers through `factory` and waits until each has registered; the
    /// planner's `module` sends them their queries. Runs on the current tokio runtime.
    pub async fn start(
        module: Module,
        workers: usize,
        factory: impl WorkerFactory + 'static,
        options: JoinerOptions,
    ) -> Result<Self, JoinError> {
        if workers == 0 {
            return Err(JoinError::new("give at least one CG-space worker"));
        }
        let shared = Arc::new(Shared {
            module: Mutex::new(module),
            workers,
            factory: Arc::new(factory),
            slots: (0..workers)
                .map(|_| tokio::sync::Mutex::new(Slot { handle: None }))
                .collect(),
            generations: (0..workers).map(|_| AtomicU64::new(0)).collect(),
            options,
            stats: Mutex::new(JoinStats {
                queries_per_worker: vec![0; workers],
                workers: vec![WorkerCounters::default(); workers],
                ..JoinStats::default()
            }),
        });
        let started = join_all((0..workers).map(|k| {
            let shared = shared.clone();
            async move { shared.launch(k).await }
        }))
        .await;
        if let Some(Err(e)) = started.into_iter().find(Result::is_err) {
            for k in 0..workers {
                if let Some(h) = shared.slots[k].lock().await.handle.take() {
                    h.stop().await;
                }
            }
            return Err(e);
        }
        Ok(DistributedJoiner {
            shared,
            runtime: Handle::current(),
            print: None,
        })
    }

    /// Asks the joins (and whether the workers are still there) through `module` from now
    /// on: a handler's context ([`tca_module::Context::module`]), so that on central's
    /// simulated clock the joins are that handler's own queries and the handler counts as
    /// waiting for them. (Asked from another module while a handler plans, they would wait
    /// in central's queue until that handler ended.)
    pub fn ask_as(&self, module: Module) {
        *self
            .shared
            .module
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = module;
    }

    /// The number of workers.
    pub fn workers(&self) -> usize {
        self.shared.workers
    }

    /// What the joiner has done so far.
    pub fn stats(&self) -> JoinStats {
        self.shared.stats()
    }

    /// Stops every worker; what the joiner did.
    pub async fn shutdown(self) -> JoinStats {
        for slot in &self.shared.slots {
            if let Some(h) = slot.lock().await.handle.take() {
                h.stop().await;
            }
        }
        self.shared.stats()
    }

    /// Answers a batch: shares by owner, sent at once, waited for together.
    async fn join_async(
        &self,
        batch: Vec<(usize, JoinBatch, Vec<usize>)>,
        total: usize,
    ) -> Result<Joins, JoinError> {
        let shared = &self.shared;
        let replies = join_all(
            batch
                .into_iter()
                .map(|(k, b, at)| async move { shared.run_share(k, b).await.map(|r| (k, r, at)) }),
        )
        .await;
        let mut out: Joins = vec![None; total];
        let mut stats = shared.stats.lock().unwrap_or_else(PoisonError::into_inner);
        stats.batches += 1;
        for reply in replies {
            let (k, reply, at) = reply?;
            stats.queries += at.len() as u64;
            stats.queries_per_worker[k] += at.len() as u64;
            stats.workers[k] = reply.counters;
            for (route, i) in reply.routes.into_iter().zip(at) {
                out[i] = route;
            }
        }
        Ok(out)
    }

    /// The space's fingerprint, computed again only when its tables, grid or foot map changed.
    fn fingerprint_of(&mut self, space: &CgSpace) -> u64 {
        if let Some((robot, foot, grid, print)) = &self.print
            && Arc::ptr_eq(robot, space.robot())
            && Arc::ptr_eq(foot, &space.foot_shared())
            && grid == space.grid()
        {
            return *print;
        }
        let print = fingerprint(space);
        self.print = Some((
            space.robot().clone(),
            space.foot_shared(),
            *space.grid(),
            print,
        ));
        print
    }

    /// Runs a future to its end from synchronous code.
    fn block_on<T>(&self, f: impl std::future::Future<Output = T>) -> Result<T, JoinError> {
        match Handle::try_current() {
            Err(_) => Ok(self.runtime.block_on(f)),
            Ok(h) if h.runtime_flavor() == RuntimeFlavor::MultiThread => {
                Ok(tokio::task::block_in_place(|| self.runtime.block_on(f)))
            }
            Ok(_) => Err(JoinError::new(
                "the distributed joiner was called on a single-threaded tokio runtime; plan inside spawn_blocking or on a multi-threaded runtime",
            )),
        }
    }
}

impl Joiner for DistributedJoiner {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        if queries.is_empty() {
            return Ok(Vec::new());
        }
        let workers = self.shared.workers;
        let partition =
            Partition::new(space.grid(), workers).map_err(|e| JoinError::new(e.to_string()))?;
        let print = self.fingerprint_of(space);
        let mut marked: Vec<_> = space.marked().iter().copied().collect();
        marked.sort_unstable();
        let mut shares: Vec<(Vec<JoinQuery>, Vec<usize>)> = vec![(Vec::new(), Vec::new()); workers];
        for (i, q) in queries.iter().enumerate() {
            let k = partition.owner(q);
            shares[k].0.push(*q);
            shares[k].1.push(i);
        }
        let batch: Vec<(usize, JoinBatch, Vec<usize>)> = shares
            .into_iter()
            .enumerate()
            .filter(|(_, (q, _))| !q.is_empty())
            .map(|(k, (queries, at))| {
                (
                    k,
                    JoinBatch {
                        fingerprint: print,
                        workers: workers as u32,
                        marked: marked.clone(),
                        queries,
                    },
                    at,
                )
            })
            .collect();
        self.block_on(self.join_async(batch, queries.len()))?
    }
}

impl Shared {
    /// The module the joins are asked from.
    fn module(&self) -> Module {
        self.module
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    fn stats(&self) -> JoinStats {
        self.stats
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    fn generation(&self, k: usize) -> u64 {
        self.generations[k].load(Ordering::SeqCst)
    }

    /// Whether central has worker `k` connected with its query registered.
    async fn registered(&self, k: usize) -> Result<bool, ModuleError> {
        let name = join_name(k);
        let module = self.module();
        let registry = module.registry().await?;
        Ok(registry
            .entries
            .iter()
            .any(|e| e.name.as_str() == name && e.connected))
    }

    /// Starts worker `k` into its slot and waits until it has registered.
    async fn launch(&self, k: usize) -> Result<(), JoinError> {
        let mut slot = self.slots[k].lock().await;
        self.launch_into(k, &mut slot).await
    }

    async fn launch_into(&self, k: usize, slot: &mut Slot) -> Result<(), JoinError> {
        let mut handle = self.factory.start(k).await?;
        let deadline = tokio::time::Instant::now() + self.options.start_timeout;
        loop {
            if let Some(why) = handle.ended() {
                return Err(JoinError::new(format!(
                    "worker {k} ({}) ended before it joined central: {why}",
                    worker_name(k)
                )));
            }
            match self.registered(k).await {
                Ok(true) => break,
                Ok(false) => {}
                Err(e) => {
                    handle.stop().await;
                    return Err(JoinError::new(format!(
                        "cannot ask central whether worker {k} has joined: {e}"
                    )));
                }
            }
            if tokio::time::Instant::now() >= deadline {
                handle.stop().await;
                return Err(JoinError::new(format!(
                    "worker {k} ({}) did not register within {:?}",
                    worker_name(k),
                    self.options.start_timeout
                )));
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        slot.handle = Some(handle);
        Ok(())
    }

    /// Replaces worker `k` if it is still generation `generation` (else someone already did).
    async fn replace(&self, k: usize, generation: u64, why: &str) -> Result<(), JoinError> {
        let mut slot = self.slots[k].lock().await;
        if self.generation(k) != generation {
            return Ok(());
        }
        self.generations[k].fetch_add(1, Ordering::SeqCst);
        {
            let mut stats = self.stats.lock().unwrap_or_else(PoisonError::into_inner);
            if stats.replacements >= self.options.max_replacements {
                return Err(JoinError::new(format!(
                    "worker {k} died ({why}) after {} replacements already; giving up",
                    stats.replacements
                )));
            }
            stats.replacements += 1;
            stats.workers[k] = WorkerCounters::default();
        }
        tracing::warn!(
            worker = k,
            why,
            "a CG-space worker died; starting a replacement"
        );
        if let Some(old) = slot.handle.take() {
            old.stop().await;
        }
        self.launch_into(k, &mut slot).await
    }

    /// Sends worker `k` its share and waits for the answer, replacing the worker and sending
    /// again when it dies.
    async fn run_share(&self, k: usize, batch: JoinBatch) -> Result<JoinReply, JoinError> {
        let name = join_name(k);
        let payload = encode_data(&batch).map_err(|e| JoinError::new(e.to_string()))?;
        let mut failures = 0u64;
        loop {
            let generation = self.generation(k);
            let module = self.module();
            let ask = module.query_raw(&name, payload.clone(), Some(self.options.query_timeout));
            tokio::pin!(ask);
            // The first check one period from now: an interval's immediate first tick still
            // waits for the timer wheel (up to a millisecond), and the query would wait with it.
            let mut watch = tokio::time::interval_at(
                tokio::time::Instant::now() + self.options.watch_every,
                self.options.watch_every,
            );
            watch.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            let answer = loop {
                tokio::select! {
                    answer = &mut ask => break answer,
                    _ = watch.tick() => {
                        // A worker that died idle leaves its query waiting in central, where
                        // its replacement will find it.
                        if self.generation(k) == generation
                            && matches!(self.registered(k).await, Ok(false))
                        {
                            self.replace(k, generation, "it left central").await?;
                        }
                    }
                }
            };
            let error = match answer {
                Ok(data) => {
                    let reply: JoinReply = decode_data(&data).map_err(|e| {
                        JoinError::new(format!("worker {k}'s answer does not decode: {e}"))
                    })?;
                    if reply.routes.len() != batch.queries.len() {
                        return Err(JoinError::new(format!(
                            "worker {k} answered {} of {} queries",
                            reply.routes.len(),
                            batch.queries.len()
                        )));
                    }
                    return Ok(reply);
                }
                Err(ModuleError::HandlerFailed { reason, .. }) => {
                    return Err(JoinError::new(format!(
                        "worker {k} refused its joins: {reason}"
                    )));
                }
                Err(e @ (ModuleError::Disconnected | ModuleError::CentralLost)) => {
                    return Err(JoinError::new(format!(
                        "the planner lost central while waiting for worker {k}: {e}"
                    )));
                }
                Err(e) => e,
            };
            failures += 1;
            if failures > self.options.max_replacements {
                return Err(JoinError::new(format!(
                    "worker {k}'s joins failed {failures} times, the last: {error}"
                )));
            }
            self.replace(k, generation, &error.to_string()).await?;
            self.stats
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .resent += 1;
        }
    }
}
