//! The async driver around the core: one task owns the [`Central`] state machine, every link
//! feeds one channel, and the driver carries out the actions (send, log, close).

use std::collections::{HashMap, VecDeque};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use bytes::Bytes;
use tca_logs::LogSink;
use tca_messages::{ModuleName, now_ns};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use crate::core::{Action, Central, Counters, Event, LinkId};
use crate::inbox::{Inbox, Taken};
use crate::inproc::InProcLink;
use crate::zenoh_transport::ZenohCentral;
use crate::{CentralConfig, CentralError, Result};

/// What reaches the driver task. Frames do not travel here: they wait in their link's
/// [`Inbox`], and `Ready` tells the driver that an idle inbox has something.
#[derive(Debug)]
pub(crate) enum Input {
    /// An event for the core (not `Frame`: frames come through inboxes).
    Event(Event),
    /// A new link, where to send its frames and its inbox (precedes its `Opened` event).
    Attach(LinkId, mpsc::UnboundedSender<Bytes>, Arc<Inbox>),
    /// The inbox of a link has frames to handle.
    Ready(LinkId),
    /// A request for statistics.
    Inspect(oneshot::Sender<Stats>),
    /// Stop.
    Shutdown,
}

/// A snapshot of central's state.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Running totals.
    pub counters: Counters,
    /// Connected modules.
    pub modules: Vec<ModuleName>,
    /// Live task-tree nodes.
    pub live_nodes: usize,
    /// The task trees as text.
    pub tree: String,
}

/// A cheap, cloneable handle to a running central.
#[derive(Clone, Debug)]
pub struct CentralHandle {
    tx: mpsc::UnboundedSender<Input>,
    next_link: Arc<AtomicU32>,
    inbox_limits: (u32, u64),
}

impl CentralHandle {
    /// Opens an in-process link, as a module in this process connecting.
    pub fn connect_in_process(&self) -> Result<InProcLink> {
        let (link, inbox, from_central) = self.attach()?;
        Ok(InProcLink::new(link, self.tx.clone(), inbox, from_central))
    }

    /// Opens a link: its number, its inbox and the receiver of what central sends on it.
    pub(crate) fn attach(&self) -> Result<(LinkId, Arc<Inbox>, mpsc::UnboundedReceiver<Bytes>)> {
        let link = self.allocate_link();
        let (sink, from_central) = mpsc::unbounded_channel();
        let (frames, bytes) = self.inbox_limits;
        let inbox = Arc::new(Inbox::new(link, frames, bytes, self.tx.clone()));
        self.tx
            .send(Input::Attach(link, sink, inbox.clone()))
            .map_err(|_| CentralError::Stopped)?;
        self.tx
            .send(Input::Event(Event::Opened(link)))
            .map_err(|_| CentralError::Stopped)?;
        Ok((link, inbox, from_central))
    }

    /// Central's current statistics.
    pub async fn stats(&self) -> Result<Stats> {
        let (tx, rx) = oneshot::channel();
        self.tx
            .send(Input::Inspect(tx))
            .map_err(|_| CentralError::Stopped)?;
        rx.await.map_err(|_| CentralError::Stopped)
    }

    pub(crate) fn allocate_link(&self) -> LinkId {
        self.next_link.fetch_add(1, Ordering::Relaxed)
    }

    pub(crate) fn input(&self) -> &mpsc::UnboundedSender<Input> {
        &self.tx
    }
}

/// A central running in this process.
pub struct RunningCentral {
    handle: CentralHandle,
    task: JoinHandle<Result<Stats>>,
    zenoh: Option<ZenohCentral>,
}

impl RunningCentral {
    /// The handle.
    pub fn handle(&self) -> CentralHandle {
        self.handle.clone()
    }

    /// The zenoh endpoints central listens on, if the zenoh transport is on.
    pub fn listening(&self) -> Vec<String> {
        self.zenoh
            .as_ref()
            .map(|z| z.endpoints().to_vec())
            .unwrap_or_default()
    }

    /// Stops central: closes every link, finishes the log and returns the final statistics.
    pub async fn shutdown(self) -> Result<Stats> {
        let _ = self.handle.tx.send(Input::Shutdown);
        let stats = self.task.await.map_err(|_| CentralError::Stopped)??;
        if let Some(z) = self.zenoh {
            z.close().await;
        }
        Ok(stats)
    }

    /// Waits until central stops by itself (it does not, unless the runtime fails).
    pub async fn wait(self) -> Result<Stats> {
        self.task.await.map_err(|_| CentralError::Stopped)?
    }
}

/// How to start central.
#[derive(Clone, Debug, Default)]
pub struct StartOptions {
    /// Limits and defaults.
    pub config: CentralConfig,
    /// Write the traffic log here (MCAP).
    pub log: Option<PathBuf>,
    /// Also serve modules over zenoh, listening on these endpoints
    /// (e.g. `tcp/127.0.0.1:7447`).
    pub listen: Vec<String>,
}

/// Starts central on the current tokio runtime.
pub async fn start(options: StartOptions) -> Result<RunningCentral> {
    let (tx, rx) = mpsc::unbounded_channel();
    let handle = CentralHandle {
        tx,
        next_link: Arc::new(AtomicU32::new(1)),
        inbox_limits: (
            options.config.max_inbox_frames,
            options.config.max_inbox_bytes,
        ),
    };
    let log = match &options.log {
        Some(path) => Some(LogSink::create(path)?),
        None => None,
    };
    let zenoh = if options.listen.is_empty() {
        None
    } else {
        let users = options
            .config
            .policy
            .as_ref()
            .and_then(|p| p.zenoh_users_file().map(|f| f.to_owned()));
        Some(ZenohCentral::start(&options.listen, users.as_deref(), handle.clone()).await?)
    };
    let core = Central::new(options.config);
    let task = tokio::spawn(drive(core, rx, log));
    Ok(RunningCentral {
        handle,
        task,
        zenoh,
    })
}

/// Most inputs handled between two hand-overs to the log writer.
const MAX_BATCH: usize = 512;

/// What the driver owns besides the core.
struct Driver {
    core: Central,
    sinks: HashMap<LinkId, mpsc::UnboundedSender<Bytes>>,
    inboxes: HashMap<LinkId, Arc<Inbox>>,
    /// Links whose inboxes have something, served one item each in turn.
    ring: VecDeque<LinkId>,
    actions: Vec<Action>,
    records: Vec<tca_logs::LogRecord>,
    stop: bool,
}

impl Driver {
    /// Handles one input from the channel.
    fn input(&mut self, now: u64, input: Input) {
        match input {
            Input::Event(Event::Closed(link)) => {
                // Everything the link sent before it closed is handled first.
                if let Some(inbox) = self.inboxes.remove(&link) {
                    while let (Some(item), _) = inbox.take() {
                        self.item(now, link, item);
                    }
                    inbox.close();
                }
                self.event(now, Event::Closed(link));
            }
            Input::Event(event) => self.event(now, event),
            Input::Attach(link, sink, inbox) => {
                self.sinks.insert(link, sink);
                self.inboxes.insert(link, inbox);
            }
            Input::Ready(link) => self.ring.push_back(link),
            Input::Inspect(reply) => {
                let _ = reply.send(stats(&self.core));
            }
            Input::Shutdown => self.stop = true,
        }
    }

    /// Serves up to `budget` inbox items, one per link per turn.
    fn serve(&mut self, now: u64, budget: usize) -> usize {
        let mut served = 0;
        while served < budget {
            let Some(link) = self.ring.pop_front() else {
                break;
            };
            let Some(inbox) = self.inboxes.get(&link).cloned() else {
                continue;
            };
            let (item, more) = inbox.take();
            if more {
                self.ring.push_back(link);
            }
            if let Some(item) = item {
                self.item(now, link, item);
                served += 1;
            }
        }
        served
    }

    fn item(&mut self, now: u64, link: LinkId, item: Taken) {
        let event = match item {
            Taken::Frame(frame) => Event::Frame(link, frame),
            Taken::Refused(frame, used) => Event::InboxFull(link, frame, used),
            Taken::Dropped(count) => Event::InboxDropped(link, count),
        };
        self.event(now, event);
    }

    /// Hands an event to the core and carries out the actions at once, so closes and sends
    /// keep their order.
    fn event(&mut self, now: u64, event: Event) {
        self.core.handle(now, event, &mut self.actions);
        for action in self.actions.drain(..) {
            match action {
                Action::Send(link, frame) => {
                    if let Some(sink) = self.sinks.get(&link) {
                        // A closed sink means the module is gone; its Closed event follows.
                        let _ = sink.send(frame);
                    }
                }
                Action::Log(record) => self.records.push(record),
                Action::Close(link) => {
                    self.sinks.remove(&link);
                    if let Some(inbox) = self.inboxes.remove(&link) {
                        inbox.close();
                    }
                }
            }
        }
    }
}

/// The driver loop.
async fn drive(
    core: Central,
    mut rx: mpsc::UnboundedReceiver<Input>,
    mut log: Option<LogSink>,
) -> Result<Stats> {
    let mut d = Driver {
        core,
        sinks: HashMap::new(),
        inboxes: HashMap::new(),
        ring: VecDeque::new(),
        actions: Vec::with_capacity(256),
        records: Vec::new(),
        stop: false,
    };
    while !d.stop {
        if d.ring.is_empty() {
            // Idle: sleep until an input or the core's next deadline.
            let first = match d.core.next_deadline() {
                Some(at) => {
                    let wait = Duration::from_nanos(at.saturating_sub(now_ns()));
                    match tokio::time::timeout(wait, rx.recv()).await {
                        Ok(input) => input,
                        Err(_) => Some(Input::Event(Event::Tick)),
                    }
                }
                None => rx.recv().await,
            };
            let Some(first) = first else { break };
            d.input(now_ns(), first);
        } else {
            // Busy: let other tasks (transports, modules in this process) run between batches.
            tokio::task::yield_now().await;
        }
        // One clock read and one log hand-over per batch.
        let now = now_ns();
        let mut handled = 0;
        while handled < MAX_BATCH && !d.stop {
            match rx.try_recv() {
                Ok(input) => d.input(now, input),
                Err(_) => break,
            }
            handled += 1;
        }
        if !d.stop {
            d.serve(now, MAX_BATCH);
            if d.core.next_deadline().is_some_and(|at| at <= now) {
                d.event(now, Event::Tick);
            }
        }
        if let Some(l) = log.as_mut() {
            l.append_batch(std::mem::take(&mut d.records));
        } else {
            d.records.clear();
        }
    }
    let final_stats = stats(&d.core);
    drop(d);
    if let Some(l) = log {
        l.finish()?;
    }
    Ok(final_stats)
}

fn stats(core: &Central) -> Stats {
    Stats {
        counters: core.counters(),
        modules: core.connected_modules(),
        live_nodes: core.live_nodes(),
        tree: core.render_tree(),
    }
}
