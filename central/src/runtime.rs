//! The async driver around the core: one task owns the [`Central`] state machine, every link
//! feeds one channel, and the driver carries out the actions (send, log, close).
//!
//! The driver never waits for a link: frames for a link go into its outbox (see
//! `tca_link::outbox`), whose level the driver measures when the core asks and reports when a
//! watched one drains; the core decides what a slow module gets. Nor does it wait for the log
//! writer: while that is `max_log_backlog` records behind, frames stay in the inboxes.
//!
//! With a journal (`crate::journal`), what the core does is carried out once what caused it is
//! written: the actions of a batch wait, the batch's journal entries are written in one go,
//! then the actions go out (and what they call for in turn, likewise).

use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use bytes::Bytes;
use tca_logs::LogSink;
use tca_messages::{ModuleName, now_ns};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use tca_link::local::Attach;
use tca_link::{
    FrameReceiver, Gauge, Hub, InProcLink, InProcTransport, Inbox, LinkError, LinkSignal,
    LocalEndpoint, LocalListener, OutboxLimits, PeerPolicy, Taken,
};

use crate::core::{Action, Central, Counters, Event, LinkId, OutboxUse};
use crate::journal::Journal;
use crate::zenoh_router::ZenohCentral;
use crate::{CentralConfig, CentralError, Result};

/// The driver's end of the links' signals: inboxes, outboxes and in-process links wake it
/// through its input channel.
#[derive(Clone, Debug)]
pub(crate) struct DriverHub(pub(crate) mpsc::UnboundedSender<Input>);

impl Hub for DriverHub {
    fn signal(&self, signal: LinkSignal) -> bool {
        let input = match signal {
            LinkSignal::Ready(link) => Input::Ready(link),
            LinkSignal::Drained(link) => Input::Drained(link),
            LinkSignal::Closed(link) => Input::Event(Event::Closed(link)),
        };
        self.0.send(input).is_ok()
    }

    fn stopped(&self) -> bool {
        self.0.is_closed()
    }
}

/// What reaches the driver task. Frames do not travel here: they wait in their link's
/// [`Inbox`], and `Ready` tells the driver that an idle inbox has something.
#[derive(Debug)]
pub(crate) enum Input {
    /// An event for the core (not `Frame`: frames come through inboxes).
    Event(Event),
    /// A new link, where to send its frames (and the gauge of that outbox) and its inbox
    /// (precedes its `Opened` event).
    Attach(LinkId, mpsc::UnboundedSender<Bytes>, Arc<Gauge>, Arc<Inbox>),
    /// The inbox of a link has frames to handle.
    Ready(LinkId),
    /// The watched outbox of a congested link was read down to a quarter of its bound.
    Drained(LinkId),
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
    /// The most central's bounded queues have held since it started.
    pub high_water: HighWater,
    /// Times central stopped taking frames from modules until its log writer caught up
    /// (`max_log_backlog`).
    pub log_waits: u64,
    /// Messages from zenoh clients that central's router refused by its access control (when
    /// the policy authenticates zenoh clients, each identity is confined to its own keys):
    /// frames published on another identity's keys, subscriptions, liveliness tokens and
    /// queries outside its own. They never reach central's core, so they are not in
    /// `counters`.
    pub refused_by_router: u64,
}

/// The most each of central's bounded queues has held at once since it started: the largest
/// of any one link (inbox, outbox) or any one sender (queued), frames and bytes each on their
/// own. Compare with the limits in [`CentralConfig`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HighWater {
    /// Frames a link sent that waited for central to handle them (`max_inbox_frames`).
    pub inbox_frames: u64,
    /// Their bytes (`max_inbox_bytes`).
    pub inbox_bytes: u64,
    /// Frames central sent to a link that waited for the link to take them
    /// (`max_outbox_frames`).
    pub outbox_frames: u64,
    /// Their bytes (`max_outbox_bytes`).
    pub outbox_bytes: u64,
    /// Messages of one sender held in central (`max_queued_messages`).
    pub queued_messages: u64,
    /// Their data bytes (`max_queued_bytes`).
    pub queued_bytes: u64,
    /// Log records handed to the log writer and not yet written (`max_log_backlog`, which
    /// one batch of the driver's may pass).
    pub log_records: u64,
}

/// A cheap, cloneable handle to a running central.
#[derive(Clone, Debug)]
pub struct CentralHandle {
    tx: mpsc::UnboundedSender<Input>,
    /// The zenoh router's session, when its access control is on (for its refusal count).
    router: Arc<std::sync::OnceLock<zenoh::Session>>,
    hub: Arc<dyn Hub>,
    next_link: Arc<AtomicU32>,
    inbox_limits: (u32, u64),
    outbox_limits: OutboxLimits,
}

impl CentralHandle {
    /// The transport of modules in this process: give it to the module library
    /// (`tca_module::Connector::from(handle.in_process())`); each connection opens a new
    /// in-process link.
    pub fn in_process(&self) -> InProcTransport {
        let handle = self.clone();
        InProcTransport::new(move || handle.connect_in_process().map_err(|_| LinkError::Stopped))
    }

    /// Opens an in-process link, as a module in this process connecting.
    pub fn connect_in_process(&self) -> Result<InProcLink> {
        let (link, inbox, from_central) = self.attach()?;
        Ok(InProcLink::new(link, self.hub.clone(), inbox, from_central))
    }

    /// Opens a link: its number, its inbox and the receiver of what central sends on it.
    pub(crate) fn attach(&self) -> Result<(LinkId, Arc<Inbox>, FrameReceiver)> {
        self.attach_as(None)
    }

    /// Opens a link whose transport authenticated its peer as `identity`, if given (the
    /// module's hello is then held to that identity).
    pub(crate) fn attach_as(
        &self,
        identity: Option<String>,
    ) -> Result<(LinkId, Arc<Inbox>, FrameReceiver)> {
        let link = self.allocate_link();
        let (sink, from_central) = mpsc::unbounded_channel();
        let gauge = Arc::new(Gauge::new(link, self.outbox_limits, self.hub.clone()));
        let (frames, bytes) = self.inbox_limits;
        let inbox = Arc::new(Inbox::new(link, frames, bytes, self.hub.clone()));
        self.tx
            .send(Input::Attach(link, sink, gauge.clone(), inbox.clone()))
            .map_err(|_| CentralError::Stopped)?;
        self.tx
            .send(Input::Event(Event::Opened(link)))
            .map_err(|_| CentralError::Stopped)?;
        if let Some(identity) = identity {
            self.tx
                .send(Input::Event(Event::Identified(link, identity)))
                .map_err(|_| CentralError::Stopped)?;
        }
        Ok((link, inbox, FrameReceiver::metered(from_central, gauge)))
    }

    /// Central's current statistics.
    pub async fn stats(&self) -> Result<Stats> {
        let (tx, rx) = oneshot::channel();
        self.tx
            .send(Input::Inspect(tx))
            .map_err(|_| CentralError::Stopped)?;
        let mut stats = rx.await.map_err(|_| CentralError::Stopped)?;
        stats.refused_by_router = self.refused_by_router().await?;
        Ok(stats)
    }

    /// Messages the zenoh router's access control refused so far (0 without it).
    async fn refused_by_router(&self) -> Result<u64> {
        match self.router.get() {
            Some(session) => tca_link::zenoh::acl::refusals(session)
                .await
                .map_err(CentralError::from),
            None => Ok(0),
        }
    }

    pub(crate) fn allocate_link(&self) -> LinkId {
        self.next_link.fetch_add(1, Ordering::Relaxed)
    }

    pub(crate) fn input(&self) -> &mpsc::UnboundedSender<Input> {
        &self.tx
    }
}

/// Central's side of local links: connections accepted on its Unix sockets open links here.
#[derive(Debug)]
struct LocalAttach(CentralHandle);

impl Attach for LocalAttach {
    fn attach(&self) -> Option<(LinkId, Arc<Inbox>, FrameReceiver)> {
        self.0.attach().ok()
    }

    fn closed(&self, link: LinkId) {
        let _ = self.0.tx.send(Input::Event(Event::Closed(link)));
    }
}

/// A central running in this process.
pub struct RunningCentral {
    handle: CentralHandle,
    task: JoinHandle<Result<Stats>>,
    zenoh: Option<ZenohCentral>,
    local: Vec<LocalListener>,
    restored: Option<Restored>,
    kept_log: Option<PathBuf>,
}

/// What a central started on a journal of a crashed central restored.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Restored {
    /// What was restored, in words (task nodes, modules to rejoin, events replayed).
    pub summary: String,
    /// Records of the crashed central's last moments, which its traffic log lacked, written at
    /// the start of the new log.
    pub log_records_recovered: usize,
    /// What could not be done about the traffic log, if anything.
    pub warnings: Vec<String>,
}

impl RunningCentral {
    /// The handle.
    pub fn handle(&self) -> CentralHandle {
        self.handle.clone()
    }

    /// The transport of modules in this process (see [`CentralHandle::in_process`]).
    pub fn in_process(&self) -> InProcTransport {
        self.handle.in_process()
    }

    /// What was restored from the journal, when central was started on a crashed central's
    /// journal ([`StartOptions::journal`]).
    pub fn restored(&self) -> Option<&Restored> {
        self.restored.as_ref()
    }

    /// Where the log found at the log path was kept ([`StartOptions::keep_previous_log`]).
    pub fn kept_log(&self) -> Option<&Path> {
        self.kept_log.as_deref()
    }

    /// The endpoints central listens on: local ones first, then zenoh ones.
    pub fn listening(&self) -> Vec<String> {
        let mut all: Vec<String> = self
            .local
            .iter()
            .map(|l| l.endpoint().to_string())
            .collect();
        if let Some(z) = &self.zenoh {
            all.extend(z.endpoints().iter().cloned());
        }
        all
    }

    /// Stops central: closes every link, finishes the log and returns the final statistics. A
    /// journal is removed: a central stopped on purpose ends its task trees, and the next one
    /// starts afresh.
    pub async fn shutdown(self) -> Result<Stats> {
        let refused = self.handle.refused_by_router().await.unwrap_or(0);
        let _ = self.handle.tx.send(Input::Shutdown);
        // No new local connections; the socket files go.
        drop(self.local);
        let mut stats = self.task.await.map_err(|_| CentralError::Stopped)??;
        stats.refused_by_router = refused;
        if let Some(z) = self.zenoh {
            z.close().await;
        }
        Ok(stats)
    }

    /// Stops central the way a crash (`kill -9`) would, for tests of recovery: the driver stops
    /// where it is, every link drops, and nothing is cleaned up: the journal stays, for a
    /// central started on it to restore. (Unlike a real crash, the traffic log's writer still
    /// writes what it was handed.)
    pub async fn crash(self) {
        self.task.abort();
        let _ = self.task.await;
        drop(self.local);
        if let Some(z) = self.zenoh {
            z.close().await;
        }
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
    /// Also serve modules from other processes, listening on these endpoints: `local` or
    /// `local/NAME` (a Unix socket, for modules on this machine) and zenoh ones (e.g.
    /// `tcp/127.0.0.1:7447`), any mix of them.
    pub listen: Vec<String>,
    /// Listen on endpoints other machines can reach (`tcp/0.0.0.0:7447`, a LAN address, a
    /// host name) without a policy, or with a policy that authenticates no zenoh client (no
    /// `zenoh_users_file`, no `[transport.tls]`). Off (the default), [`start`] refuses the
    /// first with [`CentralError::Insecure`] (an open central admits any process that finds
    /// it) and the second with [`CentralError::Unisolated`] (its router cannot keep modules
    /// from reading and speaking for each other).
    pub insecure: bool,
    /// Keep central's task trees and queues in this journal (see `crate::journal`). If it holds
    /// the state of a central that crashed, central starts from that state: the modules rejoin
    /// and what they were doing goes on. A clean [`RunningCentral::shutdown`] removes it.
    pub journal: Option<PathBuf>,
    /// Keep a non-empty log found at `log` under the next free `STEM.N.mcap` next to it
    /// ([`tca_logs::set_aside`]) instead of overwriting it; [`RunningCentral::kept_log`] says
    /// where it went. On a crashed central's journal, that log is first checked against the
    /// journal: the records of the crashed central's last moments that it lacks (the log is
    /// flushed every 50 ms, the journal before anything goes out) are written at the start of
    /// the new log, so that the logs read in order tell the whole history. The log is moved
    /// only once the new journal head says where it goes, so a central killed while it starts
    /// leaves the next one able to tell whose log is whose.
    pub keep_previous_log: bool,
}

impl StartOptions {
    /// Central in this process on the simulated clock, logging to `log` if given (what a
    /// whole walk in one process starts).
    pub fn simulated(log: Option<PathBuf>) -> Self {
        StartOptions {
            log,
            config: CentralConfig {
                simulated_time: true,
                ..CentralConfig::default()
            },
            ..StartOptions::default()
        }
    }
}

/// Starts central on the current tokio runtime.
pub async fn start(options: StartOptions) -> Result<RunningCentral> {
    let (local_endpoints, zenoh_endpoints): (Vec<&String>, Vec<&String>) = options
        .listen
        .iter()
        .partition(|e| LocalEndpoint::is_local(e));
    let security = options
        .config
        .policy
        .as_ref()
        .map(|p| p.router_security())
        .unwrap_or_default();
    for e in &zenoh_endpoints {
        let tca_link::zenoh::Exposure::Network(reason) = tca_link::zenoh::exposure(e) else {
            continue;
        };
        if options.config.policy.is_none() {
            if !options.insecure {
                return Err(CentralError::Insecure(reason));
            }
        } else if !security.authenticators().any() {
            if !options.insecure {
                return Err(CentralError::Unisolated(reason));
            }
            tracing::warn!(
                endpoint = %e,
                "the policy authenticates no zenoh client (no zenoh_users_file, no \
                 [transport.tls]): any client that reaches this endpoint can read every \
                 module's frames and publish on their keys (--insecure)"
            );
        }
    }
    let recovered = match &options.journal {
        Some(path) => Some(crate::journal::open(
            path,
            options.config.clone(),
            options.log.as_deref(),
            now_ns(),
        )?),
        None => None,
    };
    let first_link = recovered
        .as_ref()
        .map_or(1, |r| r.core.highest_link().saturating_add(1).max(1));
    let (tx, rx) = mpsc::unbounded_channel();
    let handle = CentralHandle {
        hub: Arc::new(DriverHub(tx.clone())),
        tx,
        router: Arc::default(),
        next_link: Arc::new(AtomicU32::new(first_link)),
        inbox_limits: (
            options.config.max_inbox_frames,
            options.config.max_inbox_bytes,
        ),
        outbox_limits: OutboxLimits::new(
            options.config.max_outbox_frames,
            options.config.max_outbox_bytes,
        ),
    };
    // A restored central's journal gets its new head first, carrying the records its log is
    // to start with (what the crashed central's log lacks, its links closing): a crash from
    // here on finds them in the journal, whatever reached the log.
    let mut pending_prefix = Vec::new();
    let kept_log = match (&options.log, options.keep_previous_log) {
        (Some(log), true) => tca_logs::aside_name(log)?,
        _ => None,
    };
    let (core, journal, restored) = match recovered {
        Some(mut r) => {
            let mut core = r.core;
            pending_prefix = std::mem::take(&mut r.log_prefix);
            let journal = r.pending.start(
                &mut core,
                options.log.is_some(),
                pending_prefix.clone(),
                kept_log.clone(),
            )?;
            for w in &r.warnings {
                tracing::warn!(journal = %journal.path().display(), "{w}");
            }
            let restored = r.summary.map(|summary| {
                tracing::info!("{summary}");
                Restored {
                    summary,
                    log_records_recovered: r.recovered,
                    warnings: r.warnings,
                }
            });
            (core, Some(journal), restored)
        }
        None => (Central::new(options.config.clone()), None, None),
    };
    if let (Some(log), Some(kept)) = (&options.log, &kept_log) {
        std::fs::rename(log, kept).map_err(|source| {
            CentralError::Log(tca_logs::LogError::Io {
                path: log.clone(),
                source,
            })
        })?;
    }
    let mut log = match &options.log {
        Some(path) => Some(LogSink::create(path)?),
        None => None,
    };
    let mut logged = 0u64;
    if let Some(sink) = log.as_mut()
        && !pending_prefix.is_empty()
    {
        logged = pending_prefix.len() as u64;
        sink.append_batch(pending_prefix);
        flushed(sink.flush()).await;
    }
    let mut local = Vec::new();
    if !local_endpoints.is_empty() {
        let peers = PeerPolicy::same_user_and(options.config.local_peer_uids.iter().copied())?;
        let attach: Arc<dyn Attach> = Arc::new(LocalAttach(handle.clone()));
        for e in local_endpoints {
            let endpoint = LocalEndpoint::parse(e)?;
            local.push(LocalListener::bind(
                &endpoint,
                peers.clone(),
                options.config.max_frame_bytes,
                attach.clone(),
            )?);
        }
    }
    let zenoh = if zenoh_endpoints.is_empty() {
        None
    } else {
        let endpoints: Vec<String> = zenoh_endpoints.into_iter().cloned().collect();
        let zenoh = ZenohCentral::start(&endpoints, &security, handle.clone()).await?;
        if security.authenticators().any() {
            let _ = handle.router.set(zenoh.session().clone());
        }
        Some(zenoh)
    };
    let limits = handle.outbox_limits;
    let max_log_backlog = options.config.max_log_backlog.max(1) as usize;
    let task = tokio::spawn(drive(
        Driver::new(core, limits, journal, logged),
        max_log_backlog,
        rx,
        log,
    ));
    Ok(RunningCentral {
        handle,
        task,
        zenoh,
        local,
        restored,
        kept_log,
    })
}

/// Waits until the log writer has written and flushed what was handed to it before `done` was
/// asked for (at most 30 s: a writer that stopped has said why already).
async fn flushed(done: std::sync::mpsc::Receiver<()>) {
    let give_up = tokio::time::Instant::now() + Duration::from_secs(30);
    loop {
        match done.try_recv() {
            Ok(()) | Err(std::sync::mpsc::TryRecvError::Disconnected) => return,
            Err(std::sync::mpsc::TryRecvError::Empty) => {}
        }
        if tokio::time::Instant::now() > give_up {
            tracing::warn!("the traffic-log writer did not flush within 30 s");
            return;
        }
        tokio::time::sleep(Duration::from_millis(1)).await;
    }
}

/// Most inputs handled between two hand-overs to the log writer.
const MAX_BATCH: usize = 512;

/// How often central, waiting for its log writer to catch up, looks again.
const LOG_WAIT_POLL: Duration = Duration::from_millis(1);

/// Where the driver sends a link's frames.
struct Sink {
    tx: mpsc::UnboundedSender<Bytes>,
    /// The level of that outbox.
    gauge: Arc<Gauge>,
    /// The core was told the outbox went past its bound (the link is closing).
    full: bool,
}

/// Something the core must hear once the actions at hand are carried out.
#[derive(Debug)]
enum FollowUp {
    /// The level of a link's outbox, measured then (with every frame just sent in it).
    Measure(LinkId),
    /// A link's outbox went past its bound.
    Full(LinkId, OutboxUse),
}

/// What the driver owns besides the core.
struct Driver {
    core: Central,
    sinks: HashMap<LinkId, Sink>,
    limits: OutboxLimits,
    inboxes: HashMap<LinkId, Arc<Inbox>>,
    /// Links whose inboxes have something, served one item each in turn.
    ring: VecDeque<LinkId>,
    actions: Vec<Action>,
    /// What carrying out actions called for (outbox measurements), done next.
    follow: VecDeque<FollowUp>,
    records: Vec<tca_logs::LogRecord>,
    /// Outbox high-water marks, and inbox ones of links that closed.
    high: HighWater,
    /// The log writer is behind: frames wait in the inboxes until it catches up.
    log_wait: bool,
    /// Times that happened.
    log_waits: u64,
    stop: bool,
    /// The journal, if central keeps one: actions wait in `deferred` until the entries of the
    /// events that caused them are written.
    journal: Option<Journal>,
    /// Actions waiting for their causes to be journaled.
    deferred: Vec<Action>,
    /// Journal entries taken from the core, to write.
    entries: Vec<u8>,
    /// Records handed to the traffic log since central started.
    logged: u64,
}

impl Driver {
    fn new(core: Central, limits: OutboxLimits, journal: Option<Journal>, logged: u64) -> Self {
        Driver {
            core,
            sinks: HashMap::new(),
            limits,
            inboxes: HashMap::new(),
            ring: VecDeque::new(),
            actions: Vec::with_capacity(256),
            follow: VecDeque::new(),
            records: Vec::new(),
            high: HighWater::default(),
            log_wait: false,
            log_waits: 0,
            stop: false,
            journal,
            deferred: Vec::new(),
            entries: Vec::new(),
            logged,
        }
    }

    /// Handles one input from the channel.
    fn input(&mut self, now: u64, input: Input) {
        match input {
            Input::Event(Event::Closed(link)) => {
                // Everything the link sent before it closed is handled first.
                if let Some(inbox) = self.inboxes.get(&link).cloned() {
                    while let (Some(item), _) = inbox.take() {
                        self.item(now, link, item);
                    }
                }
                self.forget_inbox(link);
                self.sinks.remove(&link);
                self.event(now, Event::Closed(link));
            }
            Input::Event(event) => self.event(now, event),
            Input::Attach(link, tx, gauge, inbox) => {
                let sink = Sink {
                    tx,
                    gauge,
                    full: false,
                };
                self.sinks.insert(link, sink);
                self.inboxes.insert(link, inbox);
            }
            Input::Ready(link) => self.ring.push_back(link),
            Input::Drained(link) => self.drained(now, link),
            Input::Inspect(reply) => {
                let _ = reply.send(self.stats());
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
    /// keep their order; then what those actions called for (outbox levels), likewise.
    fn event(&mut self, now: u64, event: Event) {
        self.carry_out(now, event);
        while let Some(follow) = self.follow.pop_front() {
            if let Some(event) = self.follow_up(follow) {
                self.carry_out(now, event);
            }
        }
    }

    /// The event a follow-up calls for, measured now.
    fn follow_up(&self, follow: FollowUp) -> Option<Event> {
        Some(match follow {
            FollowUp::Measure(link) => {
                Event::OutboxLevel(link, self.sinks.get(&link)?.gauge.measure())
            }
            FollowUp::Full(link, used) => Event::OutboxFull(link, used),
        })
    }

    /// Hands one event to the core and carries out its actions, in order (with a journal:
    /// once the event is journaled, see [`Driver::settle`]).
    fn carry_out(&mut self, now: u64, event: Event) {
        if self.journal.is_some() {
            let from = self.deferred.len();
            self.core.handle(now, event, &mut self.deferred);
            // A link the core closed is served no more, though what it was sent waits.
            for action in &self.deferred[from..] {
                if let Action::Close(link) = action
                    && let Some(inbox) = self.inboxes.remove(link)
                {
                    fold_inbox(&mut self.high, &inbox);
                    inbox.close();
                }
            }
            return;
        }
        self.core.handle(now, event, &mut self.actions);
        self.execute();
    }

    /// Writes the journal entries of the events handled so far, then carries out the actions
    /// they caused, then the events those call for (outbox levels), until nothing waits.
    fn settle(&mut self, now: u64) {
        loop {
            self.write_journal();
            if self.deferred.is_empty() {
                return;
            }
            std::mem::swap(&mut self.actions, &mut self.deferred);
            self.execute();
            while let Some(follow) = self.follow.pop_front() {
                if let Some(event) = self.follow_up(follow) {
                    self.carry_out(now, event);
                }
            }
        }
    }

    /// Writes the entries the core has made.
    fn write_journal(&mut self) {
        let Some(journal) = self.journal.as_mut() else {
            return;
        };
        self.core.take_journal(&mut self.entries);
        if self.entries.is_empty() {
            return;
        }
        if let Err(e) = journal.append(&self.entries) {
            tracing::error!(
                journal = %journal.path().display(),
                error = %e,
                "the journal cannot be written; central goes on without it, and a crash now \
                 loses its task trees"
            );
            self.journal = None;
        }
        self.entries.clear();
    }

    /// Carries out `self.actions`, in order.
    fn execute(&mut self) {
        for action in self.actions.drain(..) {
            match action {
                Action::Send(link, frame) => {
                    if let Some(sink) = self.sinks.get_mut(&link) {
                        let (limits, high, follow) =
                            (self.limits, &mut self.high, &mut self.follow);
                        send(sink, link, frame, limits, high, follow);
                    }
                }
                Action::Log(record) => self.records.push(record),
                Action::Close(link) => {
                    self.sinks.remove(&link);
                    if let Some(inbox) = self.inboxes.remove(&link) {
                        fold_inbox(&mut self.high, &inbox);
                        inbox.close();
                    }
                }
                Action::Measure(link) => self.follow.push_back(FollowUp::Measure(link)),
            }
        }
    }

    /// A watched outbox was read down: the core hears its level (and may give the module
    /// work again).
    fn drained(&mut self, now: u64, link: LinkId) {
        let Some(sink) = self.sinks.get(&link) else {
            return;
        };
        if sink.full {
            return;
        }
        let used = sink.gauge.measure();
        self.event(now, Event::OutboxLevel(link, used));
    }

    /// Removes a link's inbox, keeping its high-water mark.
    fn forget_inbox(&mut self, link: LinkId) {
        if let Some(inbox) = self.inboxes.remove(&link) {
            fold_inbox(&mut self.high, &inbox);
            inbox.close();
        }
    }

    fn stats(&self) -> Stats {
        let mut s = stats(&self.core);
        let mut high = self.high;
        for inbox in self.inboxes.values() {
            fold_inbox(&mut high, inbox);
        }
        let queued = self.core.queued_high_water();
        high.queued_messages = queued.messages;
        high.queued_bytes = queued.bytes;
        s.high_water = high;
        s.log_waits = self.log_waits;
        s
    }
}

/// Puts a frame into a link's outbox, noting the level it reaches; past the bound the core
/// hears of it (and disconnects the module).
fn send(
    sink: &mut Sink,
    link: LinkId,
    frame: Bytes,
    limits: OutboxLimits,
    high: &mut HighWater,
    follow: &mut VecDeque<FollowUp>,
) {
    let (frames, bytes) = sink.gauge.added(frame.len());
    if sink.tx.send(frame).is_err() {
        // The receiver is gone: the module is gone; its Closed event follows.
        return;
    }
    high.outbox_frames = high.outbox_frames.max(frames);
    high.outbox_bytes = high.outbox_bytes.max(bytes);
    if sink.full {
        return;
    }
    if limits.over(frames, bytes) {
        sink.full = true;
        follow.push_back(FollowUp::Full(link, OutboxUse { frames, bytes }));
    }
}

fn fold_inbox(high: &mut HighWater, inbox: &Inbox) {
    let (frames, bytes) = inbox.high_water();
    high.inbox_frames = high.inbox_frames.max(frames);
    high.inbox_bytes = high.inbox_bytes.max(bytes);
}

/// The driver loop. While the log writer is `max_log_backlog` records behind, frames are
/// left in the inboxes (bounded: modules meet over-limit refusals) until it is back under half;
/// everything else (links opening and closing, statistics, deadlines) goes on.
async fn drive(
    mut d: Driver,
    max_log_backlog: usize,
    mut rx: mpsc::UnboundedReceiver<Input>,
    mut log: Option<LogSink>,
) -> Result<Stats> {
    while !d.stop {
        if d.ring.is_empty() || d.log_wait {
            // Idle (or waiting for the log writer): sleep until an input, the core's next
            // deadline (handled below) or the next look at the log writer.
            let deadline = d
                .core
                .next_deadline()
                .map(|at| Duration::from_nanos(at.saturating_sub(now_ns())));
            let wait = match (deadline, d.log_wait) {
                (Some(w), true) => Some(w.min(LOG_WAIT_POLL)),
                (None, true) => Some(LOG_WAIT_POLL),
                (w, false) => w,
            };
            let first = match wait {
                Some(w) => match tokio::time::timeout(w, rx.recv()).await {
                    Ok(input) => input.map(Some),
                    Err(_) => Some(None),
                },
                None => rx.recv().await.map(Some),
            };
            let Some(first) = first else { break };
            if let Some(input) = first {
                d.input(now_ns(), input);
            }
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
            if !d.log_wait {
                d.serve(now, MAX_BATCH);
            }
            if d.core.next_deadline().is_some_and(|at| at <= now) {
                d.event(now, Event::Tick);
            }
        }
        d.settle(now);
        if let Some(l) = log.as_mut() {
            d.logged += d.records.len() as u64;
            l.append_batch(std::mem::take(&mut d.records));
            let backlog = l.backlog();
            d.high.log_records = d.high.log_records.max(backlog as u64);
            if backlog >= max_log_backlog {
                d.log_waits += u64::from(!d.log_wait);
                d.log_wait = true;
            } else if backlog <= max_log_backlog / 2 {
                d.log_wait = false;
            }
        } else {
            d.records.clear();
        }
        finish_rewrite(&mut d);
        if d.journal.as_ref().is_some_and(Journal::wants_rewrite) {
            rewrite_journal(&mut d, log.as_mut());
        }
    }
    d.settle(now_ns());
    let final_stats = d.stats();
    let journal = d.journal.take();
    drop(d);
    if let Some(l) = log {
        l.finish()?;
    }
    // Stopped on purpose: the next central starts afresh.
    if let Some(journal) = journal
        && let Err(e) = journal.remove()
    {
        tracing::warn!(error = %e, "the journal could not be removed");
    }
    Ok(final_stats)
}

/// Starts rewriting the journal as central's state now; the new head is put in place once
/// the traffic log has written every record handed to it (the new head says how many: a
/// restart counts on them being in the log), off central's thread (see
/// `Journal::start_rewrite`).
fn rewrite_journal(d: &mut Driver, log: Option<&mut LogSink>) {
    let (logged, log_flushed) = match log {
        Some(l) => (Some(d.logged), Some(l.flush())),
        None => (None, None),
    };
    let Some(journal) = d.journal.as_mut() else {
        return;
    };
    let result = crate::journal::head(&d.core, journal.id(), logged, Vec::new())
        .map_err(|reason| reason.to_string())
        .and_then(|head| {
            journal
                .start_rewrite(&head, log_flushed)
                .map_err(|e| e.to_string())
        });
    if let Err(e) = result {
        journal_lost(d, &e);
    }
}

/// Puts a finished rewrite of the journal in place, if one is under way and done.
fn finish_rewrite(d: &mut Driver) {
    if let Some(Err(e)) = d.journal.as_mut().and_then(Journal::finish_rewrite) {
        journal_lost(d, &e.to_string());
    }
}

/// The journal could not be rewritten: central goes on without it.
fn journal_lost(d: &mut Driver, error: &str) {
    tracing::error!(
        error = %error,
        "the journal cannot be rewritten; central goes on without it, and a crash now loses \
         its task trees"
    );
    d.journal = None;
}

fn stats(core: &Central) -> Stats {
    Stats {
        counters: core.counters(),
        modules: core.connected_modules(),
        live_nodes: core.live_nodes(),
        tree: core.render_tree(),
        high_water: HighWater::default(),
        log_waits: 0,
        refused_by_router: 0,
    }
}
