//! The running bridge: a module on each central, the two delay lines between them, the log.
//!
//! On each side the bridge is a module (its name on both centrals) that registers what
//! crosses from that side, with the formats their handlers registered on the other side, so
//! that for the modules of either side the far side's messages are there like their own. It
//! also registers `NAME.carry` on both sides, the goal under which a forwarded goal or
//! command is carried out (see [`crate::forward`]).

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicI64, AtomicU32, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock, Weak};
use std::time::Duration;

use serde::{Deserialize, Serialize};
use tca_logs::LinkEvent;
use tca_messages::control::Registration;
use tca_messages::{Class, DataFormat, MessageName, ModuleName, NodeId};
use tca_module::{Connector, Module};
use tokio::sync::{oneshot, watch};
use tokio::task::JoinHandle;

use crate::crossing::{Answer, Crossing, DelayLine};
use crate::error::{BridgeError, Result};
use crate::file::BridgeConfig;
use crate::log::{BridgeLog, Settings};
use crate::select::{Forwarded, wait_for};
use crate::side::{Direction, Side};
use crate::stats::DelayStats;

/// How many goals and commands the bridge takes at once on each side: as many as come (the
/// far side's handlers keep their own capacity).
pub const CAPACITY: u32 = 65_536;

/// How often the bridge looks whether each side's central is still there.
const WATCH_EVERY: Duration = Duration::from_millis(50);

/// The goal under which the bridge carries out a forwarded goal or command on the far side.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Carry {
    /// The crossing that brought it.
    pub crossing: u32,
    /// The message carried out (for people reading the task tree and the log).
    pub name: String,
}

/// A forwarded query or task waiting on the side it came from for its answer.
pub(crate) struct Waiting {
    /// Where the answer goes.
    pub(crate) tx: oneshot::Sender<Answer>,
    /// The handler's module in the handler's context: exceptions raised in the far copy of a
    /// task are raised here again.
    pub(crate) handler: Module,
    /// The request's id on this side.
    pub(crate) request: tca_messages::MessageId,
}

/// A forwarded goal or command being carried out on the far side.
pub(crate) struct Carried {
    /// The crossing that brought it.
    pub(crate) crossing: Crossing,
    /// The carry goal's message id there, once sent.
    pub(crate) carry: Option<tca_messages::MessageId>,
    /// The carried message's id there, once sent.
    pub(crate) child: Option<tca_messages::MessageId>,
    /// The carry's node there (exceptions raised under it cross until its outcome has).
    pub(crate) node: Option<(Side, NodeId)>,
}

/// What both sides share.
pub(crate) struct Core {
    pub(crate) name: ModuleName,
    pub(crate) carry: MessageName,
    pub(crate) config: BridgeConfig,
    halves: [OnceLock<Module>; 2],
    /// Per side: the exceptions raised there that cross (attached at every carry there).
    pub(crate) exceptions: [Vec<MessageName>; 2],
    /// Who handles each forwarded name on its far side.
    pub(crate) handlers: HashMap<MessageName, ModuleName>,
    next: AtomicU32,
    lines: [DelayLine; 2],
    /// Set when the bridge stops: the lines release nothing more.
    stopped: AtomicBool,
    /// Crossings in each line now.
    in_line: [AtomicI64; 2],
    pub(crate) waiting: Mutex<HashMap<u32, Waiting>>,
    pub(crate) carried: Mutex<HashMap<u32, Carried>>,
    pub(crate) carry_nodes: Mutex<HashMap<(Side, NodeId), u32>>,
    pub(crate) log: Option<BridgeLog>,
    /// Measured delays, seconds, per direction.
    delays: Mutex<[Vec<f64>; 2]>,
}

pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl Core {
    /// The module on `side`, once connected.
    pub(crate) fn half(&self, side: Side) -> Option<&Module> {
        self.halves[side.index()].get()
    }

    /// A new crossing number.
    pub(crate) fn next_id(&self) -> u32 {
        self.next.fetch_add(1, Ordering::Relaxed)
    }

    /// Puts a crossing into its way's delay line (it left the line's side now).
    pub(crate) fn enqueue(&self, crossing: Crossing) {
        let d = crossing.direction;
        self.in_line[d.index()].fetch_add(1, Ordering::Relaxed);
        if !self.lines[d.index()].take(crossing) {
            self.in_line[d.index()].fetch_sub(1, Ordering::Relaxed);
            tracing::warn!("the bridge is stopping: a crossing was not forwarded");
        }
    }

    /// A crossing left its line.
    pub(crate) fn dequeued(&self, direction: Direction) {
        self.in_line[direction.index()].fetch_sub(1, Ordering::Relaxed);
    }

    /// Records a measured delay.
    pub(crate) fn measured(&self, direction: Direction, delay_s: f64) {
        lock(&self.delays)[direction.index()].push(delay_s);
    }

    /// The delays measured so far, one way.
    fn delay_stats(&self, direction: Direction) -> DelayStats {
        let delays = lock(&self.delays)[direction.index()].clone();
        DelayStats::of(
            direction,
            self.config.delay(direction).as_secs_f64(),
            &delays,
        )
    }

    /// Something could not be forwarded: said and logged.
    pub(crate) fn problem(&self, side: Option<Side>, text: String) {
        tracing::warn!("{text}");
        if let Some(log) = &self.log {
            log.problem(side, text);
        }
    }
}

/// A bridge between two centrals, running. Stop it with [`RunningBridge::stop`] (dropping
/// it drops both links at once).
pub struct RunningBridge {
    core: Arc<Core>,
    forwarded: Vec<Forwarded>,
    tasks: Vec<JoinHandle<()>>,
    closed: watch::Receiver<Option<Side>>,
}

/// What a bridge did, when it stops.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The messages it forwarded: name, class and way.
    pub forwarded: Vec<(String, String, String)>,
    /// The delays measured each way.
    pub delays: Vec<DelayStats>,
    /// Crossings still in the delay lines when it stopped (not forwarded).
    pub in_flight: i64,
}

impl RunningBridge {
    /// What it forwards.
    pub fn forwarded(&self) -> &[Forwarded] {
        &self.forwarded
    }

    /// The delays measured so far, up then down.
    pub fn delay_stats(&self) -> Vec<DelayStats> {
        Direction::BOTH
            .iter()
            .map(|d| self.core.delay_stats(*d))
            .collect()
    }

    /// The bridge's module on `side`.
    pub fn module(&self, side: Side) -> Option<&Module> {
        self.core.half(side)
    }

    /// Resolves when a side's link closes for good (its central stopped and the link cannot
    /// come back: in-process, or closed by central), with that side.
    pub async fn closed(&self) -> Side {
        let mut closed = self.closed.clone();
        loop {
            if let Some(side) = *closed.borrow_and_update() {
                return side;
            }
            if closed.changed().await.is_err() {
                return std::future::pending().await;
            }
        }
    }

    /// Says goodbye to both centrals, closes the log and tells what was done. Crossings
    /// still in the delay lines are not forwarded.
    pub async fn stop(self) -> Summary {
        self.core.stopped.store(true, Ordering::Relaxed);
        let summary = self.summary();
        for side in Side::BOTH {
            if let Some(m) = self.core.half(side) {
                m.close().await;
            }
        }
        for t in &self.tasks {
            t.abort();
        }
        if summary.in_flight > 0 {
            self.core.problem(
                None,
                format!(
                    "the bridge stopped with {} crossings still in its delay lines; they were \
                     not forwarded",
                    summary.in_flight
                ),
            );
        }
        if let Some(log) = &self.core.log {
            log.finish();
        }
        summary
    }

    /// What it did so far.
    pub fn summary(&self) -> Summary {
        Summary {
            forwarded: self
                .forwarded
                .iter()
                .map(|f| {
                    (
                        f.name().to_string(),
                        f.class().to_string(),
                        f.direction.to_string(),
                    )
                })
                .collect(),
            delays: self.delay_stats(),
            in_flight: self
                .core
                .in_line
                .iter()
                .map(|n| n.load(Ordering::Relaxed))
                .sum(),
        }
    }
}

impl Drop for RunningBridge {
    fn drop(&mut self) {
        self.core.stopped.store(true, Ordering::Relaxed);
        for t in &self.tasks {
            t.abort();
        }
        for side in Side::BOTH {
            if let Some(m) = self.core.half(side) {
                m.abort_link();
            }
        }
    }
}

/// Joins the two centrals: waits until what the bridge forwards is registered on the side
/// that handles it, registers it on the other side, and forwards from then on.
pub async fn start(config: BridgeConfig) -> Result<RunningBridge> {
    config.check()?;
    let name = ModuleName::new(config.name.clone())
        .map_err(|e| BridgeError::Config(format!("the bridge's name: {e}")))?;
    let probe_name = format!("{}-probe-{}", config.name, std::process::id());
    let robot = probe(&probe_name, &config.robot, Side::Robot).await?;
    let ground = match probe(&probe_name, &config.ground, Side::Ground).await {
        Ok(g) => g,
        Err(e) => {
            robot.close().await;
            return Err(e);
        }
    };
    let found = wait_for(&config, [&robot, &ground]).await;
    robot.close().await;
    ground.close().await;
    let forwarded = found?;
    let log = config.log.as_deref().map(BridgeLog::create).transpose()?;

    let mut exceptions: [Vec<MessageName>; 2] = [Vec::new(), Vec::new()];
    for f in forwarded.iter().filter(|f| f.class() == Class::Exception) {
        exceptions[f.direction.from().index()].push(f.name().clone());
    }
    let handlers = forwarded
        .iter()
        .map(|f| (f.name().clone(), f.entry.handler.clone()))
        .collect();
    let carry = MessageName::new(format!("{}.carry", config.name))
        .map_err(|e| BridgeError::Config(format!("the bridge's name: {e}")))?;
    let mut tasks = Vec::new();
    let core = Arc::new({
        Core {
            name: name.clone(),
            carry,
            config: config.clone(),
            halves: [OnceLock::new(), OnceLock::new()],
            exceptions,
            handlers,
            next: AtomicU32::new(1),
            lines: Direction::BOTH.map(|d| DelayLine::new(config.delay(d))),
            stopped: AtomicBool::new(false),
            in_line: [AtomicI64::new(0), AtomicI64::new(0)],
            waiting: Mutex::new(HashMap::new()),
            carried: Mutex::new(HashMap::new()),
            carry_nodes: Mutex::new(HashMap::new()),
            log,
            delays: Mutex::new([Vec::new(), Vec::new()]),
        }
    });
    for side in Side::BOTH {
        let module = connect_half(&core, side, &forwarded).await?;
        let _ = core.halves[side.index()].set(module);
        if let Some(log) = &core.log {
            let settings = Settings {
                bridge: config.name.clone(),
                side: side.label().to_owned(),
                endpoint: connector(&config, side).describe(),
                up_delay_s: config.delay(Direction::Up).as_secs_f64(),
                down_delay_s: config.delay(Direction::Down).as_secs_f64(),
            };
            let detail = serde_json::to_string(&settings).unwrap_or_default();
            log.link(side, LinkEvent::Connected, &name, detail);
            for f in forwarded.iter().filter(|f| f.direction.from() == side) {
                log.registered(side, f.registration());
            }
        }
    }
    // Both sides joined: the lines start releasing (what came meanwhile waited in them).
    for d in Direction::BOTH {
        let weak = Arc::downgrade(&core);
        core.lines[d.index()]
            .run(
                &format!("bridge-{d}"),
                tokio::runtime::Handle::current(),
                move |c| match weak.upgrade() {
                    Some(core) if !core.stopped.load(Ordering::Relaxed) => {
                        core.dequeued(c.direction);
                        core.release(c);
                        true
                    }
                    _ => false,
                },
            )
            .map_err(|e| BridgeError::Connect(format!("cannot start the {d} delay line: {e}")))?;
    }
    let (closed_tx, closed) = watch::channel(None);
    let closed_tx = Arc::new(closed_tx);
    for side in Side::BOTH {
        if let Some(module) = core.half(side) {
            tasks.push(tokio::spawn(watch_side(
                Arc::downgrade(&core),
                module.downgrade(),
                side,
                closed_tx.clone(),
            )));
        }
    }
    for f in &forwarded {
        tracing::info!(name = %f.name(), class = %f.class(), way = %f.direction, "forwarded");
    }
    Ok(RunningBridge {
        core,
        forwarded,
        tasks,
        closed,
    })
}

fn connector(config: &BridgeConfig, side: Side) -> &Connector {
    match side {
        Side::Robot => &config.robot,
        Side::Ground => &config.ground,
    }
}

/// A module with no handlers that reads a side's registry, refusing a central on simulated
/// time.
async fn probe(name: &str, connector: &Connector, side: Side) -> Result<Module> {
    let module = Module::builder(name)
        .connect(connector)
        .await
        .map_err(|e| {
            BridgeError::Connect(format!(
                "cannot join the {side} side's {}: {e}",
                connector.describe()
            ))
        })?;
    if module.central_keeps_simulated_time() {
        module.close().await;
        return Err(BridgeError::Connect(format!(
            "the {side} side's {} keeps a simulated clock; the bridge delays in wall-clock \
             seconds: start that central without --simulated-time",
            connector.describe()
        )));
    }
    Ok(module)
}

/// Connects the bridge's module on `side`, registering what crosses from there and the carry.
async fn connect_half(core: &Arc<Core>, side: Side, forwarded: &[Forwarded]) -> Result<Module> {
    let mut builder = Module::builder(core.name.as_str()).capacity(CAPACITY);
    for f in forwarded.iter().filter(|f| f.direction.from() == side) {
        let weak = Arc::downgrade(core);
        let direction = f.direction;
        let class = f.class();
        let name = f.name().clone();
        builder = builder.handle_raw(f.registration(), move |ctx, data| {
            crate::forward::forward(weak.clone(), direction, class, name.clone(), ctx, data)
        });
    }
    let carry = Registration {
        name: core.carry.clone(),
        class: Class::Goal,
        format: DataFormat::of::<Carry>()
            .map_err(|e| BridgeError::Config(format!("the carry goal's format: {e}")))?,
        reply: None,
        replace: false,
    };
    let weak = Arc::downgrade(core);
    builder = builder.handle_raw(carry, move |ctx, data| {
        crate::forward::carry(weak.clone(), side, ctx, data)
    });
    let connector = connector(&core.config, side);
    builder.connect(connector).await.map_err(|e| {
        BridgeError::Connect(format!(
            "the {side} side's {} did not take the bridge: {e}",
            connector.describe()
        ))
    })
}

/// Follows a side's link: logs when its central goes and comes back, and says when the link
/// closed for good.
async fn watch_side(
    core: Weak<Core>,
    module: tca_module::WeakModule,
    side: Side,
    closed: Arc<watch::Sender<Option<Side>>>,
) {
    let mut online = true;
    loop {
        let Some(m) = module.upgrade() else { return };
        let now = m.is_online();
        if m.is_closed() {
            if let Some(core) = core.upgrade() {
                core.problem(
                    Some(side),
                    format!("the link to the {side} side's central closed"),
                );
                if let Some(log) = &core.log {
                    log.link(side, LinkEvent::Closed, &core.name, "closed".into());
                }
            }
            closed.send_replace(Some(side));
            return;
        }
        drop(m);
        if now != online {
            online = now;
            if let Some(core) = core.upgrade() {
                let (event, what) = if now {
                    (LinkEvent::Connected, "is back; the bridge joined it again")
                } else {
                    (
                        LinkEvent::Closed,
                        "went away; what was in flight there is lost, and the bridge joins it \
                         again when it is back",
                    )
                };
                tracing::warn!("the {side} side's central {what}");
                if let Some(log) = &core.log {
                    log.link(side, event, &core.name, what.to_owned());
                }
            }
        }
        tokio::time::sleep(WATCH_EVERY).await;
    }
}
