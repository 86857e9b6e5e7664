//! A connected module: sending messages and running handlers.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bytes::Bytes;
use serde::Serialize;
use serde::de::DeserializeOwned;
use tca_messages::control::{
    Cancel, Constrain, Kill, Monitor, MonitorAction, OnException, Registry, Retry, TaskEnded,
    TaskOutcome, TreeView, names,
};
use tca_messages::{
    Class, ConstraintSpec, Envelope, Failure, Message, MessageId, MessageName, ModuleName, NodeId,
    RouteError, SendOptions, TaskRef, decode, decode_data, encode, encode_data, now_ns,
};
use tokio::sync::{mpsc, oneshot};
use tokio::task::AbortHandle;

use crate::connector::{FrameTx, Presence};
use crate::context::Context;
use crate::error::{ModuleError, Result};
use crate::handler::HandlerEntry;
use crate::rejoin::{Rejoiner, Verdict};

/// How long a query waits for its answer unless told otherwise.
pub const DEFAULT_QUERY_TIMEOUT: Duration = Duration::from_secs(30);

/// State shared by every handle to one connected module.
pub(crate) struct Shared {
    pub(crate) name: ModuleName,
    /// The link number central gave this module (new after rejoining a restarted central).
    link_no: AtomicU32,
    /// Registered with a live central (false while central is gone; see [`crate::rejoin`]).
    online: AtomicBool,
    seq: AtomicU32,
    tx: FrameTx,
    max_frame_bytes: usize,
    pending: Mutex<HashMap<MessageId, oneshot::Sender<Envelope>>>,
    watchers: Mutex<HashMap<MessageId, oneshot::Sender<Result<TaskOutcome>>>>,
    running: Mutex<HashMap<NodeId, AbortHandle>>,
    handlers: HashMap<MessageName, HandlerEntry>,
    pub(crate) query_timeout: Duration,
    /// Queries are sent again this many times when their answering module dies.
    requery_after_crash: u32,
    closed: AtomicBool,
    /// Stamp envelopes with simulated time (see [`Module::spend`]) instead of the wall clock.
    sim_time: bool,
    /// The module's simulated time: the latest time it has seen or reached, nanoseconds.
    base_clock: std::sync::atomic::AtomicU64,
    /// When its latest goal, command or exception handler finished (simulated ns): the
    /// next one cannot start earlier, as the module handles them in turn.
    busy_until: std::sync::atomic::AtomicU64,
    closed_signal: tokio::sync::watch::Sender<bool>,
    /// Changes when the module rejoins a restarted central.
    online_signal: tokio::sync::watch::Sender<bool>,
    /// Keeps the transport open while any handle lives (taken by [`Module::abort_link`]).
    keep: Mutex<Option<crate::connector::Keep>>,
}

/// A module connected to central. Cheap to clone; the connection closes when the last clone
/// (and every running handler) is gone, or on [`Module::close`].
#[derive(Clone)]
pub struct Module {
    pub(crate) shared: Arc<Shared>,
    /// The task node messages sent through this handle are attached to.
    pub(crate) context: Option<NodeId>,
    /// The running handler's simulated clock, when this handle belongs to one.
    pub(crate) clock: Option<Arc<std::sync::atomic::AtomicU64>>,
}

impl std::fmt::Debug for Module {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Module")
            .field("name", &self.shared.name)
            .field("context", &self.context)
            .finish()
    }
}

/// A goal or command that was sent.
#[derive(Debug)]
pub struct Task {
    id: MessageId,
    outcome: Option<oneshot::Receiver<Result<TaskOutcome>>>,
}

impl Task {
    /// The id of the message that created the task.
    pub fn id(&self) -> MessageId {
        self.id
    }

    /// A reference to the task for temporal constraints of later sends.
    pub fn task_ref(&self) -> TaskRef {
        TaskRef::Message(self.id)
    }

    /// Waits until the task is achieved, fails or is killed. Only for tasks sent with
    /// `notify` (see [`Module::send_task`]); others return an error at once.
    pub async fn outcome(self) -> Result<TaskOutcome> {
        match self.outcome {
            Some(rx) => rx.await.map_err(|_| ModuleError::Disconnected)?,
            None => Err(ModuleError::Usage(
                "this task was sent without notify; send it with SendOptions { notify: true, .. }"
                    .into(),
            )),
        }
    }
}

impl Module {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        name: ModuleName,
        link_no: u32,
        first_seq: u32,
        tx: FrameTx,
        handlers: HashMap<MessageName, HandlerEntry>,
        query_timeout: Duration,
        requery_after_crash: u32,
        max_frame_bytes: usize,
        sim_time: bool,
        keep: crate::connector::Keep,
    ) -> Self {
        Module {
            shared: Arc::new(Shared {
                name,
                link_no: AtomicU32::new(link_no),
                online: AtomicBool::new(true),
                seq: AtomicU32::new(first_seq),
                tx,
                max_frame_bytes,
                pending: Mutex::new(HashMap::new()),
                watchers: Mutex::new(HashMap::new()),
                running: Mutex::new(HashMap::new()),
                handlers,
                query_timeout,
                requery_after_crash,
                closed: AtomicBool::new(false),
                sim_time,
                base_clock: std::sync::atomic::AtomicU64::new(0),
                busy_until: std::sync::atomic::AtomicU64::new(0),
                closed_signal: tokio::sync::watch::channel(false).0,
                online_signal: tokio::sync::watch::channel(true).0,
                keep: Mutex::new(Some(keep)),
            }),
            context: None,
            clock: None,
        }
    }

    /// The module's name.
    pub fn name(&self) -> &ModuleName {
        &self.shared.name
    }

    /// The task node this handle sends in the context of, if any.
    pub fn context(&self) -> Option<NodeId> {
        self.context
    }

    /// A handle that sends in the context of `node` (its goals and commands become children).
    pub fn in_context(&self, node: Option<NodeId>) -> Module {
        Module {
            shared: self.shared.clone(),
            context: node,
            clock: self.clock.clone(),
        }
    }

    /// Whether this module stamps its messages with simulated time.
    pub fn simulated_time(&self) -> bool {
        self.shared.sim_time
    }

    /// The time this handle stamps on what it sends, in nanoseconds: simulated time (for a
    /// module built with `simulated_time(true)`: the time its handler has reached, following
    /// the time of every message it received), otherwise the wall clock (since the epoch).
    pub fn time_ns(&self) -> u64 {
        if !self.shared.sim_time {
            return now_ns();
        }
        match &self.clock {
            Some(c) => c.load(Ordering::Relaxed),
            None => self.shared.base_clock.load(Ordering::Relaxed),
        }
    }

    /// Charges `duration` of simulated time to the running handler (a move, a computation).
    /// Does nothing for modules on the wall clock.
    pub fn spend(&self, duration: Duration) {
        if !self.shared.sim_time {
            return;
        }
        let d = u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX);
        let t = match &self.clock {
            Some(c) => c.fetch_add(d, Ordering::Relaxed).saturating_add(d),
            None => self
                .shared
                .base_clock
                .fetch_add(d, Ordering::Relaxed)
                .saturating_add(d),
        };
        self.shared.base_clock.fetch_max(t, Ordering::Relaxed);
    }

    /// Moves simulated time forward to at least `t_ns` (a message from later arrived).
    pub(crate) fn observe(&self, t_ns: u64) {
        if !self.shared.sim_time {
            return;
        }
        if let Some(c) = &self.clock {
            c.fetch_max(t_ns, Ordering::Relaxed);
        }
        self.shared.base_clock.fetch_max(t_ns, Ordering::Relaxed);
    }

    /// Sends a query and waits for the reply (at most the module's query timeout).
    pub async fn query<Q: Message>(&self, query: &Q) -> Result<Q::Reply> {
        self.query_with_timeout(query, self.shared.query_timeout)
            .await
    }

    /// Sends a query and waits at most `timeout` for the reply.
    pub async fn query_with_timeout<Q: Message>(
        &self,
        query: &Q,
        timeout: Duration,
    ) -> Result<Q::Reply> {
        expect_class::<Q>(Class::Query)?;
        let mut data = Some(encode_data(query)?);
        let mut crashes = 0;
        let answer = loop {
            // Keep a copy only while the query may have to be sent again.
            let payload = if crashes < self.shared.requery_after_crash {
                data.clone()
            } else {
                data.take()
            }
            .unwrap_or_default();
            let envelope = self.envelope(Class::Query, Q::NAME, payload, None)?;
            let answer = self.request(envelope, timeout).await?;
            if answer.class == Class::Error
                && crashes < self.shared.requery_after_crash
                && let ModuleError::Route(RouteError::HandlerDied { .. }) = route_error(&answer)
            {
                crashes += 1;
                tracing::info!(
                    name = Q::NAME,
                    attempt = crashes,
                    "the module answering died; asking again"
                );
                continue;
            }
            break answer;
        };
        match answer.class {
            Class::Reply => Ok(decode_data(&answer.data)?),
            Class::Failure => Err(ModuleError::HandlerFailed {
                name: Q::NAME.into(),
                reason: decode_data::<Failure>(&answer.data)
                    .map(|f| f.reason)
                    .unwrap_or_else(|e| e.to_string()),
            }),
            _ => Err(route_error(&answer)),
        }
    }

    /// Sends a goal (non-blocking): it becomes a task-tree node under this handle's context.
    pub fn goal<G: Message>(&self, goal: &G) -> Result<Task> {
        expect_class::<G>(Class::Goal)?;
        self.send_task(goal, SendOptions::default())
    }

    /// Sends a command (non-blocking).
    pub fn command<C: Message>(&self, command: &C) -> Result<Task> {
        expect_class::<C>(Class::Command)?;
        self.send_task(command, SendOptions::default())
    }

    /// Sends a goal or command with temporal constraints and/or a request to be told how it
    /// ends.
    pub fn send_task<M: Message>(&self, message: &M, options: SendOptions) -> Result<Task> {
        if !M::CLASS.is_task() {
            return Err(ModuleError::Usage(format!(
                "{} is a {}, not a goal or command",
                M::NAME,
                M::CLASS
            )));
        }
        let notify = options.notify;
        let envelope = self.envelope(M::CLASS, M::NAME, encode_data(message)?, Some(options))?;
        self.transmit_task(&envelope, notify)
    }

    /// Sends a task's envelope; with `notify`, watches for its outcome (the watch is dropped
    /// again if the send fails).
    fn transmit_task(&self, envelope: &Envelope, notify: bool) -> Result<Task> {
        let id = envelope.id;
        let outcome = notify.then(|| {
            let (tx, rx) = oneshot::channel();
            lock(&self.shared.watchers).insert(id, tx);
            rx
        });
        if let Err(e) = self.transmit(envelope) {
            lock(&self.shared.watchers).remove(&id);
            return Err(e);
        }
        Ok(Task { id, outcome })
    }

    /// Sends an inform (one-way).
    pub fn inform<I: Message>(&self, inform: &I) -> Result<()> {
        expect_class::<I>(Class::Inform)?;
        let envelope = self.envelope(Class::Inform, I::NAME, encode_data(inform)?, None)?;
        self.transmit(&envelope)
    }

    /// Raises an exception in the context of this handle's task node: central routes it to the
    /// nearest handler registered for its name up the task tree (§3.2).
    pub fn raise<E: Message>(&self, exception: &E) -> Result<()> {
        expect_class::<E>(Class::Exception)?;
        let envelope = self.envelope(Class::Exception, E::NAME, encode_data(exception)?, None)?;
        self.transmit(&envelope)
    }

    /// Sends a query given by name and postcard data, and waits at most `timeout` (the
    /// module's query timeout if `None`) for the reply's postcard data. For tools that do not
    /// know the message's Rust type (`tca log replay`); modules use [`Module::query`].
    pub async fn query_raw(
        &self,
        name: &str,
        data: Vec<u8>,
        timeout: Option<Duration>,
    ) -> Result<Vec<u8>> {
        let envelope = self.envelope(Class::Query, name, data, None)?;
        let answer = self
            .request(envelope, timeout.unwrap_or(self.shared.query_timeout))
            .await?;
        match answer.class {
            Class::Reply => Ok(answer.data),
            Class::Failure => Err(ModuleError::HandlerFailed {
                name: name.into(),
                reason: decode_data::<Failure>(&answer.data)
                    .map(|f| f.reason)
                    .unwrap_or_else(|e| e.to_string()),
            }),
            _ => Err(route_error(&answer)),
        }
    }

    /// Sends a goal, command, inform or exception given by class, name and postcard data, in
    /// this handle's context (an exception is raised there). `options` (constraints, notify)
    /// apply to goals and commands only; for informs and exceptions they must be the default.
    /// The returned [`Task`] names the message sent; its outcome is known only for a goal or
    /// command sent with `notify`. For tools that do not know the message's Rust type
    /// (`tca log replay`); modules use [`Module::goal`], [`Module::raise`] and the like.
    pub fn send_raw(
        &self,
        class: Class,
        name: &str,
        data: Vec<u8>,
        options: SendOptions,
    ) -> Result<Task> {
        match class {
            Class::Goal | Class::Command => {}
            Class::Inform | Class::Exception if options == SendOptions::default() => {}
            Class::Inform | Class::Exception => {
                return Err(ModuleError::Usage(format!(
                    "{name} is a {class}: constraints and notify apply to goals and commands only"
                )));
            }
            other => {
                return Err(ModuleError::Usage(format!(
                    "send_raw sends goals, commands, informs and exceptions; {name} is a {other} \
                     (use query_raw for queries)"
                )));
            }
        }
        let notify = options.notify && class.is_task();
        let envelope = self.envelope(class, name, data, Some(options))?;
        self.transmit_task(&envelope, notify)
    }

    /// [`Module::on_exception`] for an exception given by name (tools that do not know its
    /// Rust type).
    pub async fn on_exception_raw(&self, node: NodeId, name: &str) -> Result<()> {
        let name = MessageName::new(name).map_err(|e| ModuleError::Usage(e.to_string()))?;
        self.control(names::ON_EXCEPTION, &OnException { node, name })
            .await
    }

    /// The registry of every registered message.
    pub async fn registry(&self) -> Result<Registry> {
        self.control(names::REGISTRY, &()).await
    }

    /// The live task trees, as text.
    pub async fn tree(&self) -> Result<TreeView> {
        self.control(names::TREE, &()).await
    }

    /// Kills a node and its subtree.
    pub async fn kill(&self, node: NodeId) -> Result<()> {
        self.control(names::KILL, &Kill { node }).await
    }

    /// Attaches this module as the handler of exception `E` raised at `node` or below (it must
    /// have registered a handler for `E`). The handler gets the exception with its context's
    /// node = `node` and [`Context::origin`](crate::Context::origin) = the raising node.
    pub async fn on_exception<E: Message>(&self, node: NodeId) -> Result<()> {
        expect_class::<E>(Class::Exception)?;
        let name = MessageName::new(E::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?;
        self.control(names::ON_EXCEPTION, &OnException { node, name })
            .await
    }

    /// Puts a node back to waiting so it is delivered again (in an exception handler: after
    /// the raising node failed).
    pub async fn retry(&self, node: NodeId) -> Result<()> {
        self.control(names::RETRY, &Retry { node }).await
    }

    /// Installs a point monitor on `node`: when its handler starts, central asks `condition`
    /// (a query answering `bool`) once; `true` triggers `action`.
    pub async fn point_monitor<Q: Message<Reply = bool>>(
        &self,
        node: NodeId,
        condition: &Q,
        action: MonitorAction,
    ) -> Result<()> {
        self.monitor(node, condition, None, action).await
    }

    /// Installs a polling monitor on `node`: while it is active, central asks `condition` every
    /// `period`; the first `true` triggers `action`. It ends with the node.
    pub async fn polling_monitor<Q: Message<Reply = bool>>(
        &self,
        node: NodeId,
        condition: &Q,
        period: Duration,
        action: MonitorAction,
    ) -> Result<()> {
        let period_ms = u64::try_from(period.as_millis()).unwrap_or(u64::MAX).max(1);
        self.monitor(node, condition, Some(period_ms), action).await
    }

    async fn monitor<Q: Message<Reply = bool>>(
        &self,
        node: NodeId,
        condition: &Q,
        period_ms: Option<u64>,
        action: MonitorAction,
    ) -> Result<()> {
        expect_class::<Q>(Class::Query)?;
        let monitor = Monitor {
            node,
            query: MessageName::new(Q::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?,
            query_data: encode_data(condition)?,
            period_ms,
            action,
        };
        self.control(names::MONITOR, &monitor).await
    }

    /// Adds a temporal constraint between existing tasks.
    pub async fn constrain(&self, constraint: ConstraintSpec) -> Result<()> {
        self.control(names::CONSTRAIN, &Constrain { constraint })
            .await
    }

    /// Says goodbye to central and waits (at most 2 s) for it to acknowledge, so nothing sent
    /// before is lost; later sends fail with [`ModuleError::Disconnected`].
    pub async fn close(&self) {
        if let Ok(env) = self.envelope(
            Class::Control,
            names::BYE,
            encode_data(&()).unwrap_or_default(),
            None,
        ) {
            let _ = self.request(env, Duration::from_secs(2)).await;
        }
        self.shared.closed.store(true, Ordering::Relaxed);
        self.shared.closed_signal.send_replace(true);
    }

    /// Drops the link to central at once, without a goodbye, and stops every running handler:
    /// what central sees when a module crashes. For testing recovery.
    pub fn abort_link(&self) {
        self.shared.closed.store(true, Ordering::Relaxed);
        for (_, h) in lock(&self.shared.running).drain() {
            h.abort();
        }
        drop(lock(&self.shared.keep).take());
        self.shared.closed_signal.send_replace(true);
    }

    /// Resolves when the link to central closes (central stopped, or it closed the link).
    pub async fn closed(&self) {
        let mut closed = self.shared.closed_signal.subscribe();
        let _ = closed.wait_for(|c| *c).await;
    }

    /// Whether the link to central is closed.
    pub fn is_closed(&self) -> bool {
        self.shared.closed.load(Ordering::Relaxed)
    }

    async fn control<T: Serialize, R: DeserializeOwned>(&self, name: &str, body: &T) -> Result<R> {
        let envelope = self.envelope(Class::Control, name, encode_data(body)?, None)?;
        let answer = self.request(envelope, self.shared.query_timeout).await?;
        match answer.class {
            Class::Reply => Ok(decode_data(&answer.data)?),
            _ => Err(route_error(&answer)),
        }
    }

    /// Sends and waits for the envelope that answers it.
    async fn request(&self, envelope: Envelope, timeout: Duration) -> Result<Envelope> {
        let (tx, rx) = oneshot::channel();
        let id = envelope.id;
        lock(&self.shared.pending).insert(id, tx);
        if let Err(e) = self.transmit(&envelope) {
            lock(&self.shared.pending).remove(&id);
            return Err(e);
        }
        match tokio::time::timeout(timeout, rx).await {
            Ok(Ok(answer)) => {
                self.observe(answer.timestamp_ns);
                Ok(answer)
            }
            Ok(Err(_)) if !self.is_online() => Err(ModuleError::CentralLost),
            Ok(Err(_)) => Err(ModuleError::Disconnected),
            Err(_) => {
                lock(&self.shared.pending).remove(&id);
                Err(ModuleError::Timeout {
                    name: envelope.name.to_string(),
                    timeout,
                })
            }
        }
    }

    pub(crate) fn next_id(&self) -> MessageId {
        let seq = self.shared.seq.fetch_add(1, Ordering::Relaxed);
        MessageId::new(self.shared.link_no.load(Ordering::Relaxed), seq)
    }

    pub(crate) fn envelope(
        &self,
        class: Class,
        name: &str,
        data: Vec<u8>,
        options: Option<SendOptions>,
    ) -> Result<Envelope> {
        Ok(Envelope {
            id: self.next_id(),
            class,
            name: MessageName::new(name).map_err(|e| ModuleError::Usage(e.to_string()))?,
            sender: self.shared.name.clone(),
            context: self.context,
            node: None,
            correlation: None,
            timestamp_ns: self.time_ns(),
            options: options.unwrap_or_default(),
            redelivery: 0,
            data,
        })
    }

    pub(crate) fn transmit(&self, envelope: &Envelope) -> Result<()> {
        if self.is_closed() {
            return Err(ModuleError::Disconnected);
        }
        if !self.is_online() {
            return Err(ModuleError::CentralLost);
        }
        self.send_frame(envelope)
    }

    /// Sends a hello or registration, online or not.
    pub(crate) fn send_bootstrap(&self, envelope: &Envelope) -> Result<()> {
        if self.is_closed() {
            return Err(ModuleError::Disconnected);
        }
        self.send_frame(envelope)
    }

    fn send_frame(&self, envelope: &Envelope) -> Result<()> {
        let frame = encode(envelope)?;
        if frame.len() > self.shared.max_frame_bytes {
            return Err(ModuleError::Codec(tca_messages::CodecError::TooLarge {
                size: frame.len(),
                limit: self.shared.max_frame_bytes,
            }));
        }
        self.shared.tx.send(Bytes::from(frame))
    }

    /// Reads frames from central until the link closes. Holds the module weakly, so the link
    /// closes when the last [`Module`] handle is dropped (as when a module process dies). Over
    /// zenoh it also follows central's presence and rejoins a restarted central
    /// ([`crate::rejoin`]).
    pub(crate) async fn receive_loop(
        shared: std::sync::Weak<Shared>,
        mut rx: tca_central::FrameReceiver,
        mut presence: Option<mpsc::UnboundedReceiver<Presence>>,
        mut rejoiner: Option<Rejoiner>,
        early: Vec<Envelope>,
    ) {
        let upgrade = |shared: &std::sync::Weak<Shared>| {
            shared.upgrade().map(|shared| Module {
                shared,
                context: None,
                clock: None,
            })
        };
        // What central delivered while the module was still registering comes first.
        if let Some(module) = upgrade(&shared) {
            for envelope in early {
                module.on_envelope(envelope);
            }
        }
        loop {
            let deadline = rejoiner.as_ref().and_then(Rejoiner::deadline);
            tokio::select! {
                frame = rx.recv() => {
                    let Some(frame) = frame else { break };
                    let Some(module) = upgrade(&shared) else { return };
                    let envelope = match decode(&frame, usize::MAX) {
                        Ok(envelope) => envelope,
                        Err(e) => {
                            tracing::warn!(module = %module.shared.name, error = %e, "bad frame from central");
                            continue;
                        }
                    };
                    match rejoiner.as_mut().map(|r| r.on_envelope(&module, &envelope)) {
                        None | Some(Verdict::Handle) => module.on_envelope(envelope),
                        Some(Verdict::Consumed) => {}
                        Some(Verdict::Online(held)) => {
                            for envelope in held {
                                module.on_envelope(envelope);
                            }
                        }
                        Some(Verdict::Refused(reason)) => {
                            tracing::error!(module = %module.shared.name, %reason, "central refused this module when it rejoined; it stops");
                            break;
                        }
                    }
                }
                p = next_presence(&mut presence) => {
                    let Some(module) = upgrade(&shared) else { return };
                    match (p, rejoiner.as_mut()) {
                        (Some(p), Some(r)) => r.on_presence(&module, p),
                        (Some(_), None) => {}
                        (None, _) => presence = None,
                    }
                }
                _ = sleep_until(deadline) => {
                    let Some(module) = upgrade(&shared) else { return };
                    if let Some(r) = rejoiner.as_mut() {
                        r.on_timer(&module);
                    }
                }
            }
        }
        let Some(shared) = shared.upgrade() else {
            return;
        };
        shared.closed.store(true, Ordering::Relaxed);
        shared.closed_signal.send_replace(true);
        // Fail everything still waiting: dropping the senders wakes the waiters.
        fail_in_flight(&shared, || ModuleError::Disconnected);
        tracing::info!(module = %shared.name, "link to central closed");
    }

    /// Central is gone: what was in flight went with it. Waiting queries and task watchers fail
    /// with [`ModuleError::CentralLost`], running handlers stop, new sends are refused until
    /// the module has rejoined.
    pub(crate) fn go_offline(&self) {
        self.shared.online.store(false, Ordering::Relaxed);
        fail_in_flight(&self.shared, || ModuleError::CentralLost);
    }

    /// Registered again with a new central.
    pub(crate) fn go_online(&self) {
        self.shared.online.store(true, Ordering::Relaxed);
        self.shared.online_signal.send_replace(true);
    }

    /// The link number of a new central's welcome.
    pub(crate) fn set_link(&self, link: u32) {
        self.shared.link_no.store(link, Ordering::Relaxed);
    }

    /// Whether the module is registered with a live central. False while central is gone and
    /// until the module has rejoined it (zenoh only; see [`crate::rejoin`]).
    pub fn is_online(&self) -> bool {
        self.shared.online.load(Ordering::Relaxed)
    }

    /// Waits until the module is registered with a live central (at once when it is), or for
    /// at most `timeout`; returns whether it is.
    pub async fn wait_online(&self, timeout: Duration) -> bool {
        let mut online = self.shared.online_signal.subscribe();
        let wait = online.wait_for(|_| self.is_online());
        matches!(tokio::time::timeout(timeout, wait).await, Ok(Ok(_)))
    }

    fn on_envelope(&self, envelope: Envelope) {
        match envelope.class {
            Class::Query | Class::Goal | Class::Command | Class::Inform | Class::Exception => {
                self.run_handler(envelope)
            }
            Class::Reply | Class::Failure | Class::Error => {
                let Some(id) = envelope.correlation else {
                    tracing::warn!(?envelope, "answer without correlation");
                    return;
                };
                if let Some(tx) = lock(&self.shared.pending).remove(&id) {
                    let _ = tx.send(envelope);
                } else if let Some(tx) = lock(&self.shared.watchers).remove(&id) {
                    let _ = tx.send(Err(route_error(&envelope)));
                } else if envelope.class == Class::Error {
                    tracing::warn!(module = %self.shared.name, error = %route_error(&envelope), about = %id, "central reported an error");
                }
            }
            Class::Control => self.on_control(envelope),
            other => tracing::warn!(class = %other, "unexpected class from central"),
        }
    }

    fn on_control(&self, envelope: Envelope) {
        match envelope.name.as_str() {
            names::CANCEL => {
                if let Ok(cancel) = decode_data::<Cancel>(&envelope.data)
                    && let Some(h) = lock(&self.shared.running).remove(&cancel.node)
                {
                    tracing::info!(node = %cancel.node, "handler cancelled by central");
                    h.abort();
                }
            }
            names::TASK_ENDED => {
                if let (Some(id), Ok(ended)) = (
                    envelope.correlation,
                    decode_data::<TaskEnded>(&envelope.data),
                ) {
                    self.observe(envelope.timestamp_ns);
                    if let Some(tx) = lock(&self.shared.watchers).remove(&id) {
                        let _ = tx.send(Ok(ended.outcome));
                    }
                }
            }
            other => tracing::debug!(name = other, "control message ignored"),
        }
    }

    fn run_handler(&self, envelope: Envelope) {
        let Some(entry) = self.shared.handlers.get(&envelope.name).cloned() else {
            // Central only routes what we registered; answer so nobody waits forever.
            let reason = format!(
                "module {} has no handler for {}",
                self.shared.name, envelope.name
            );
            self.answer(&envelope, Err(reason));
            return;
        };
        let node = envelope.node;
        // Each handler runs on its own simulated clock: a query or inform is answered as of
        // the time it was sent; a goal, command or exception starts when it was sent or when
        // the module's previous one finished, whichever is later.
        let is_task = matches!(
            envelope.class,
            Class::Goal | Class::Command | Class::Exception
        );
        let clock = self.shared.sim_time.then(|| {
            let start = if is_task {
                self.shared
                    .busy_until
                    .load(Ordering::Relaxed)
                    .max(envelope.timestamp_ns)
            } else {
                envelope.timestamp_ns
            };
            Arc::new(std::sync::atomic::AtomicU64::new(start))
        });
        let handler_module = Module {
            shared: self.shared.clone(),
            context: node,
            clock,
        };
        let ctx = Context::new(
            handler_module.clone(),
            envelope.redelivery,
            envelope.context,
            crate::context::Incoming {
                sender: envelope.sender.clone(),
                id: envelope.id,
                class: envelope.class,
            },
        );
        let call = entry.call.clone();
        let data = envelope.data.clone();
        // Hold the table while spawning so the handler cannot finish (and remove itself)
        // before it is entered.
        let mut running = lock(&self.shared.running);
        let task = tokio::spawn(async move {
            let result = call(ctx, data).await;
            if let Some(n) = node {
                lock(&handler_module.shared.running).remove(&n);
            }
            if is_task {
                let end = handler_module.time_ns();
                handler_module
                    .shared
                    .busy_until
                    .fetch_max(end, Ordering::Relaxed);
            }
            handler_module.answer(&envelope, result.map_err(|e| e.reason));
        });
        if let Some(n) = node {
            running.insert(n, task.abort_handle());
        }
    }

    /// Sends the end of a handler: reply, success or failure.
    fn answer(&self, request: &Envelope, result: std::result::Result<Vec<u8>, String>) {
        let (class, data) = match (request.class, result) {
            (Class::Query, Ok(data)) => (Class::Reply, data),
            (Class::Goal | Class::Command | Class::Exception, Ok(_)) => {
                (Class::Success, encode_data(&()).unwrap_or_default())
            }
            (Class::Inform, Ok(_)) => return,
            (_, Ok(_)) => return,
            (Class::Inform, Err(reason)) => {
                tracing::warn!(name = %request.name, %reason, "inform handler failed");
                return;
            }
            (_, Err(reason)) => {
                tracing::debug!(name = %request.name, %reason, "handler failed");
                (
                    Class::Failure,
                    encode_data(&Failure { reason }).unwrap_or_default(),
                )
            }
        };
        let mut envelope =
            match self
                .in_context(request.node)
                .envelope(class, request.name.as_str(), data, None)
            {
                Ok(e) => e,
                Err(e) => {
                    tracing::error!(error = %e, "cannot build answer");
                    return;
                }
            };
        envelope.correlation = Some(request.id);
        envelope.node = request.node;
        if let Err(e) = self.transmit(&envelope) {
            tracing::warn!(error = %e, name = %request.name, "answer not sent");
        }
    }
}

/// Fails every waiting query (dropping its sender), task watcher and running handler.
fn fail_in_flight(shared: &Shared, error: impl Fn() -> ModuleError) {
    lock(&shared.pending).clear();
    for (_, w) in lock(&shared.watchers).drain() {
        let _ = w.send(Err(error()));
    }
    for (_, h) in lock(&shared.running).drain() {
        h.abort();
    }
}

/// The next change of central's presence; never, without a presence feed.
async fn next_presence(
    presence: &mut Option<mpsc::UnboundedReceiver<Presence>>,
) -> Option<Presence> {
    match presence {
        Some(rx) => rx.recv().await,
        None => std::future::pending().await,
    }
}

/// Sleeps until the deadline; forever without one.
async fn sleep_until(deadline: Option<tokio::time::Instant>) {
    match deadline {
        Some(d) => tokio::time::sleep_until(d).await,
        None => std::future::pending().await,
    }
}

fn route_error(envelope: &Envelope) -> ModuleError {
    match decode_data::<RouteError>(&envelope.data) {
        Ok(e) => ModuleError::Route(e),
        Err(e) => ModuleError::Connect(format!("unreadable error from central: {e}")),
    }
}

fn expect_class<M: Message>(class: Class) -> Result<()> {
    if M::CLASS == class {
        Ok(())
    } else {
        Err(ModuleError::Usage(format!(
            "{} is declared as a {}, not a {class}",
            M::NAME,
            M::CLASS
        )))
    }
}

pub(crate) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// A monitor action raising exception `exception` in the monitored node's context.
pub fn raise_action<E: Message>(exception: &E) -> Result<MonitorAction> {
    expect_class::<E>(Class::Exception)?;
    Ok(MonitorAction::Raise {
        name: MessageName::new(E::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?,
        data: encode_data(exception)?,
    })
}

/// A monitor action sending `message` (a goal, command or inform; goals and commands become
/// children of the monitored node).
pub fn send_action<M: Message>(message: &M) -> Result<MonitorAction> {
    if !matches!(M::CLASS, Class::Goal | Class::Command | Class::Inform) {
        return Err(ModuleError::Usage(format!(
            "a monitor may send a goal, command or inform; {} is a {}",
            M::NAME,
            M::CLASS
        )));
    }
    Ok(MonitorAction::Send {
        class: M::CLASS,
        name: MessageName::new(M::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?,
        data: encode_data(message)?,
    })
}
