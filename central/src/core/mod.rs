//! The sans-I/O core of central control: `handle(event) -> actions`.
//!
//! The core owns all of central's state: links, modules, the registry, open queries, tasks and
//! the task tree. It never blocks, never does I/O and never reads a clock: the driver passes the
//! time with each event and carries out the [`Action`]s it returns (send a frame, append a log
//! record, close a link). This keeps it fast, deterministic and testable without sockets.
//!
//! Submodules, by concern:
//! - `links`: hello, bye, link closed, the module table;
//! - `registry`: registrations and their data formats;
//! - `routing`: queries, informs, exceptions and the answers to them;
//! - `tasks`: goals and commands, the task tree, capacity and dispatch;
//! - `waiting`: messages held for modules that are down, with their bounds;
//! - `quota`: per-sender accounting of what central holds, and its limits;
//! - `congestion`: modules that do not keep up with what central sends them (their outbox);
//! - `permissions`: the registration policy applied to what a module sends;
//! - `taps`: copies of some names' traffic for the modules that tap them, and the task
//!   controls of the command line (kill a task by its message, kill every tree);
//! - `tree`: the adapter to `tca-task-tree`;
//! - `clock`: the simulated clock, when central keeps one: events released in simulated-time
//!   order, one at a time, while every handler has finished or waits.
//! - `ends`: the ends of watched tasks, remembered so that a module that was away can ask what
//!   became of the tasks it sent (`tca.taskStatus`);
//! - `journal`: what the core gives its journal (every event, with the facts it looked up) and
//!   takes back from it (its saved state, the events replayed).

mod clock;
mod congestion;
mod ends;
mod event;
mod exceptions;
mod journal;
mod late;
mod links;
mod monitors;
mod permissions;
mod quota;
mod registry;
mod routing;
mod taps;
mod tasks;
mod tree;
mod waiting;

#[cfg(test)]
mod fuzz_tests;
#[cfg(test)]
mod journal_tests;
#[cfg(test)]
mod tests;

use std::collections::{BTreeMap, VecDeque};

use rustc_hash::FxHashMap as HashMap;

use bytes::Bytes;
use serde::{Deserialize, Serialize};
use tca_logs::{Direction, FrameRecord, LogRecord, ProblemRecord, RecordKind};
use tca_messages::control::{CENTRAL, ControlKind, Hello};
use tca_messages::{
    Class, Envelope, MessageId, MessageName, ModuleName, RouteError, SendOptions, encode,
    encode_data,
};

pub use event::{Action, Event, InboxUse, LinkId, OutboxUse};
pub use journal::{Fact, JournalEntry, JournaledEvent, RestoreError, SavedGrant};
pub use quota::Usage;

use crate::config::CentralConfig;
use crate::policy::Grant;
use registry::Entry;
use routing::OpenQuery;
use tasks::Task;
use tca_link::OutboxLimits;
use tree::Tree;
use waiting::Waiting;

/// Whether an envelope is an event of the simulated clock (released in simulated-time order)
/// rather than bookkeeping answered at once.
fn clock_event(envelope: &Envelope) -> bool {
    match envelope.class {
        Class::Control => {
            ControlKind::from_name(envelope.name.as_str()).is_some_and(ControlKind::acts_on_tasks)
        }
        Class::Error => false,
        _ => true,
    }
}

/// Central control's state machine.
///
/// It serializes to its whole state but its configuration (see [`Central::save`]); that form
/// is central's own and changes between versions.
#[derive(Serialize, Deserialize)]
pub struct Central {
    #[serde(skip)]
    config: CentralConfig,
    links: HashMap<LinkId, Link>,
    /// The highest link number seen (see [`Central::highest_link`]).
    max_link: LinkId,
    modules: HashMap<ModuleName, ModuleState>,
    registry: BTreeMap<MessageName, Entry>,
    folded: HashMap<String, MessageName>,
    queries: HashMap<MessageId, OpenQuery>,
    tasks: HashMap<MessageId, Box<Task>>,
    /// Answers that may come late without anyone being at fault.
    late: late::LateAnswers,
    node_task: HashMap<u64, MessageId>,
    tree: Tree,
    attachments: exceptions::Attachments,
    exceptions: HashMap<MessageId, exceptions::OpenException>,
    monitors: Vec<monitors::MonitorState>,
    /// What each module taps (see `taps`).
    taps: HashMap<ModuleName, taps::TapSet>,
    /// What each sending module has held in central (see `quota`).
    queued: HashMap<ModuleName, Usage>,
    /// The most one sender has had held at once (messages and bytes, each on its own).
    queued_high: Usage,
    /// How the latest watched tasks ended (see `ends`).
    ends: ends::RecentEnds,
    #[serde(skip, default = "central_name")]
    central_name: ModuleName,
    /// The marks of every link's outbox.
    #[serde(skip, default = "default_outbox_limits")]
    outbox_limits: OutboxLimits,
    seq: u32,
    now: u64,
    /// Timestamp of the envelope being handled: what it releases (a task whose constraints or
    /// capacity it satisfies) cannot have happened earlier on the sender's clock, which matters
    /// when modules run on simulated time.
    cause_stamp: u64,
    /// The simulated clock and its event queue (off unless `simulated_time`).
    clock: clock::SimClock,
    counters: Counters,
    /// What goes to the journal, and what comes back from it (not saved).
    #[serde(skip)]
    journal: journal::Recorder,
}

fn central_name() -> ModuleName {
    ModuleName::new(CENTRAL).unwrap_or_else(|_| unreachable!())
}

fn default_outbox_limits() -> OutboxLimits {
    let c = CentralConfig::default();
    OutboxLimits::new(c.max_outbox_frames, c.max_outbox_bytes)
}

/// Running totals, for statistics and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counters {
    /// Frames received.
    pub frames_in: u64,
    /// Frames sent.
    pub frames_out: u64,
    /// Frames refused as malformed.
    pub bad_frames: u64,
    /// Errors sent to senders.
    pub errors_sent: u64,
    /// Messages refused by the registration policy (sends and registrations).
    pub not_permitted: u64,
    /// Messages refused because their sender was over a resource limit.
    pub over_limit: u64,
    /// Times a link's outbox reached half its bound, so that central held new work for its
    /// module until the module had read it down.
    pub congestions: u64,
    /// Modules disconnected because their outbox went past its bound (they did not read).
    pub too_slow: u64,
}

/// A transport link.
#[derive(Debug, Serialize, Deserialize)]
struct Link {
    module: Option<ModuleName>,
    /// The identity its transport authenticated (None: the transport knows no identity).
    identity: Option<String>,
    /// Its outbox is at half its bound or more, or may be (see `congestion`): no new work goes
    /// to it.
    congested: bool,
    /// Its outbox as last measured, plus every frame sent to it since: at least what it holds.
    #[serde(with = "journal::outbox_serde")]
    unread: OutboxUse,
}

/// What central knows of a module, connected or not.
#[derive(Debug, Serialize, Deserialize)]
struct ModuleState {
    link: Option<LinkId>,
    hello: Hello,
    capacity: usize,
    running: usize,
    /// Tasks whose constraints hold, in the order they became ready.
    ready: VecDeque<MessageId>,
    /// Queries, informs and exceptions held while the module is down.
    waiting: VecDeque<Waiting>,
    /// When the module went down (None while connected).
    down_since: Option<u64>,
    /// What the policy lets it do (None: no policy, everything).
    #[serde(with = "journal::grant_serde")]
    grant: Option<Grant>,
}

impl Central {
    /// A central with the given configuration and no links.
    pub fn new(config: CentralConfig) -> Self {
        let outbox_limits = OutboxLimits::new(config.max_outbox_frames, config.max_outbox_bytes);
        let clock = clock::SimClock::new(config.simulated_time);
        Central {
            config,
            links: HashMap::default(),
            max_link: 0,
            modules: HashMap::default(),
            registry: BTreeMap::new(),
            folded: HashMap::default(),
            queries: HashMap::default(),
            late: late::LateAnswers::default(),
            tasks: HashMap::default(),
            node_task: HashMap::default(),
            tree: Tree::default(),
            attachments: HashMap::default(),
            exceptions: HashMap::default(),
            monitors: Vec::new(),
            taps: HashMap::default(),
            queued: HashMap::default(),
            queued_high: Usage::default(),
            ends: ends::RecentEnds::default(),
            central_name: central_name(),
            outbox_limits,
            seq: 0,
            now: 0,
            cause_stamp: 0,
            clock,
            counters: Counters::default(),
            journal: journal::Recorder::default(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &CentralConfig {
        &self.config
    }

    /// Running totals.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Handles one event at time `now_ns` (nanoseconds since the UNIX epoch), appending the
    /// resulting actions to `out`.
    pub fn handle(&mut self, now_ns: u64, event: Event, out: &mut Vec<Action>) {
        let journaled = self.journal_begin(now_ns, &event);
        self.now = self.now.max(now_ns);
        match event {
            Event::Opened(link) => self.link_opened(link, out),
            Event::Identified(link, identity) => self.link_identified(link, identity),
            Event::Frame(link, frame) => self.frame(link, frame, out),
            Event::Closed(link) => self.link_closed(link, out),
            Event::Tick => {
                self.expire_waiting(out);
                self.poll_monitors(out);
            }
            Event::InboxFull(link, frame, used) => self.inbox_full(link, frame, used, out),
            Event::InboxDropped(link, count) => self.inbox_dropped(link, count, out),
            Event::OutboxLevel(link, used) => self.outbox_level(link, used, out),
            Event::OutboxFull(link, used) => self.outbox_full(link, used, out),
        }
        self.pump(out);
        self.journal_end(now_ns, journaled);
    }

    /// The time task-tree operations happen at: the simulated clock's when central keeps one
    /// (so that the tree, and the log of its operations, hold simulated times), else the wall
    /// clock's.
    fn tree_now(&self) -> u64 {
        if self.clock.on {
            self.clock.now
        } else {
            self.now
        }
    }

    /// The simulated clock's time (nanoseconds), when central keeps one.
    pub fn simulated_now(&self) -> Option<u64> {
        self.clock.on.then_some(self.clock.now)
    }

    /// Events waiting for their simulated time, and handlers central follows.
    pub fn simulated_backlog(&self) -> (usize, usize) {
        (self.clock.queued(), self.clock.handlers())
    }

    /// When the core next needs a [`Event::Tick`], if ever.
    pub fn next_deadline(&self) -> Option<u64> {
        match (self.earliest_expiry(), self.next_poll()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Connected module names, sorted.
    pub fn connected_modules(&self) -> Vec<ModuleName> {
        let mut names: Vec<ModuleName> = self
            .modules
            .iter()
            .filter(|(_, m)| m.link.is_some())
            .map(|(n, _)| n.clone())
            .collect();
        names.sort();
        names
    }

    /// Live task-tree nodes.
    pub fn live_nodes(&self) -> usize {
        self.tree.len()
    }

    /// The task trees as indented text.
    pub fn render_tree(&self) -> String {
        self.tree.render()
    }

    fn frame(&mut self, link: LinkId, frame: Bytes, out: &mut Vec<Action>) {
        self.counters.frames_in += 1;
        let Some(state) = self.links.get(&link) else {
            // A frame on a link nobody opened: treat it as opened now (zenoh may deliver the
            // first frame before the liveliness event).
            self.link_opened(link, out);
            return self.frame(link, frame, out);
        };
        let peer = state.module.clone();
        let envelope = match tca_messages::decode(&frame, self.config.max_frame_bytes) {
            Ok(e) => e,
            Err(err) => {
                self.counters.bad_frames += 1;
                self.problem(Some(link), peer.clone(), err.to_string(), &frame, out);
                // Answer with an error envelope when the sender is known; close otherwise.
                match peer {
                    Some(_) => {
                        let error = RouteError::BadFrame {
                            reason: err.to_string(),
                        };
                        self.send_error_raw(link, None, error, out);
                    }
                    None => out.push(Action::Close(link)),
                }
                return;
            }
        };
        // What central sends because of this envelope carries its time (simulated time when
        // modules run on it). Hellos and registrations (stamped with the wall clock before the
        // module knows any other time), and requests that release no task (registry, tree,
        // goodbye: tools on the wall clock send them while simulated walks run) must not move
        // anyone's clock.
        let control = (envelope.class == Class::Control)
            .then(|| ControlKind::from_name(envelope.name.as_str()))
            .flatten();
        if control.is_none_or(ControlKind::acts_on_tasks) {
            self.cause_stamp = envelope.timestamp_ns;
        }
        let frame = if control == Some(ControlKind::HelloAuth) {
            // Never write a secret to the log (nor the journal).
            let redacted = permissions::redacted_hello(&envelope).unwrap_or_default();
            self.journal_redacted(&redacted);
            redacted
        } else {
            frame
        };
        self.log_frame(Direction::In, link, peer.clone(), &envelope, frame, out);
        let Some(module) = peer else {
            return self.before_hello(link, envelope, out);
        };
        if envelope.sender != module {
            let reason = format!(
                "the frame says it is from {}, but this link belongs to module {module}",
                envelope.sender
            );
            self.problem(Some(link), Some(module), reason.clone(), &[], out);
            return self.send_error(link, &envelope, RouteError::BadFrame { reason }, out);
        }
        if envelope.id.link() != link {
            let reason = format!(
                "message id {} does not carry this link's number {link}; use the link number \
                 from the welcome",
                envelope.id
            );
            self.problem(Some(link), Some(module), reason.clone(), &[], out);
            return self.send_error(link, &envelope, RouteError::BadFrame { reason }, out);
        }
        if let Err(error) = self.permit(link, &module, &envelope, out) {
            return self.send_error(link, &envelope, error, out);
        }
        if self.clock.on && self.clock.sent(&envelope) {
            // An inform's acknowledgement or a handler's await: bookkeeping only.
            return;
        }
        self.tap_copy(&envelope, out);
        if self.kill_acts_now(&envelope) {
            // On the clock's time, so that nothing it sends moves a simulated clock.
            self.cause_stamp = self.clock.now;
        } else if self.clock.on && clock_event(&envelope) {
            let stamp = self.clock.release_stamp(envelope.timestamp_ns);
            self.clock.push(
                stamp,
                clock::Deferred::Frame {
                    link,
                    module,
                    envelope,
                },
            );
            return;
        }
        self.route(link, module, envelope, out);
    }

    /// Routes an envelope by its class (at once, or when the simulated clock releases it).
    fn route(
        &mut self,
        link: LinkId,
        module: ModuleName,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        match envelope.class {
            Class::Query | Class::Inform => self.route_by_name(link, module, envelope, out),
            Class::Exception => self.raise(link, module, envelope, out),
            Class::Goal | Class::Command => self.new_task(link, module, envelope, out),
            Class::Reply => self.answer_query(link, module, envelope, out),
            Class::Success | Class::Failure => self.handler_done(link, module, envelope, out),
            Class::Control => self.control(link, module, envelope, out),
            Class::Error => {
                let reason = "modules may not send class error; answer a query with reply or \
                              failure"
                    .to_owned();
                self.send_error(link, &envelope, RouteError::BadFrame { reason }, out)
            }
            other => {
                let reason = format!("class {other} is not understood by this central");
                self.send_error(link, &envelope, RouteError::BadFrame { reason }, out)
            }
        }
    }

    /// Releases the simulated clock's events while the system is quiescent.
    fn pump(&mut self, out: &mut Vec<Action>) {
        if !self.clock.on {
            return;
        }
        while let Some((now, event)) = self.clock.next() {
            self.cause_stamp = now;
            match event {
                clock::Deferred::Frame {
                    link,
                    module,
                    envelope,
                } => self.route(link, module, envelope, out),
                clock::Deferred::Deliver { module, envelope } => {
                    self.release_delivery(module, envelope, out)
                }
                clock::Deferred::Poll { .. } => self.poll_monitors(out),
            }
        }
    }

    /// Delivers a queued message to its module's handler, if it is still due: the module is
    /// there (else what waits for it is held), and a task is still the one to run.
    fn release_delivery(&mut self, module: ModuleName, envelope: Envelope, out: &mut Vec<Action>) {
        if envelope.class.is_task() {
            let due = self.tasks.get(&envelope.id).is_some_and(|t| {
                t.running
                    && t.handler == module
                    && Some(tca_messages::NodeId(t.node)) == envelope.node
            });
            if !due {
                tracing::debug!(id = %envelope.id, "a queued delivery of a task that stopped meanwhile; dropped");
                return;
            }
        }
        let Some(link) = self.modules.get(&module).and_then(|m| m.link) else {
            self.hand_back(&module, envelope);
            return;
        };
        self.clock.releasing = true;
        self.send(link, &envelope, out);
        self.clock.releasing = false;
    }

    /// A queued message for a module that went away waits for it like any message for a module
    /// that is down (queries and tasks are failed or requeued by the module's departure).
    pub(super) fn hand_back(&mut self, module: &ModuleName, envelope: Envelope) {
        if matches!(envelope.class, Class::Inform)
            && let Err(e) = self.hold(module, Waiting::new(envelope, self.now))
        {
            tracing::debug!(%module, error = %e, "an inform for a module that went away was dropped");
        }
    }

    /// A fresh id for a message central originates.
    fn next_id(&mut self) -> MessageId {
        self.seq = self.seq.wrapping_add(1);
        MessageId::new(0, self.seq)
    }

    /// Builds an envelope sent by central.
    fn central_envelope(
        &mut self,
        class: Class,
        name: MessageName,
        correlation: Option<MessageId>,
        data: Vec<u8>,
    ) -> Envelope {
        Envelope {
            id: self.next_id(),
            class,
            name,
            sender: self.central_name.clone(),
            context: None,
            node: None,
            correlation,
            cause: None,
            // On the clock of the message being handled, so central's answers never move a
            // module's (possibly simulated) clock.
            timestamp_ns: self.cause_stamp,
            options: SendOptions::default(),
            redelivery: 0,
            data,
        }
    }

    /// Encodes and sends an envelope on a link, logging it. On the simulated clock, a message
    /// for a simulated module's handler waits in the queue for its turn instead.
    fn send(&mut self, link: LinkId, envelope: &Envelope, out: &mut Vec<Action>) {
        let target = self.links.get(&link).and_then(|l| l.module.clone());
        let followed = self.clock.on
            && envelope.class.is_handled()
            && target
                .as_ref()
                .and_then(|m| self.modules.get(m))
                .is_some_and(|m| m.hello.simulated_time);
        if followed && !self.clock.releasing {
            let mut deferred = envelope.clone();
            deferred.timestamp_ns = self.clock.release_stamp(deferred.timestamp_ns);
            let Some(module) = target else { return };
            self.clock.push(
                deferred.timestamp_ns,
                clock::Deferred::Deliver {
                    module,
                    envelope: deferred,
                },
            );
            return;
        }
        if self.clock.on
            && let Some(module) = &target
        {
            self.clock.delivered(envelope, module);
            if followed {
                self.clock.started(envelope, module);
            }
        }
        if envelope.sender == self.central_name {
            self.tap_copy(envelope, out);
        }
        match encode(envelope) {
            Ok(frame) => {
                let frame = Bytes::from(frame);
                let peer = self.links.get(&link).and_then(|l| l.module.clone());
                self.log_frame(Direction::Out, link, peer, envelope, frame.clone(), out);
                self.counters.frames_out += 1;
                let len = frame.len();
                out.push(Action::Send(link, frame));
                self.count_out(link, len, out);
            }
            Err(err) => self.problem(Some(link), None, err.to_string(), &[], out),
        }
    }

    /// Sends `error` about `about` back on `link`.
    fn send_error(
        &mut self,
        link: LinkId,
        about: &Envelope,
        error: RouteError,
        out: &mut Vec<Action>,
    ) {
        self.send_error_named(link, Some((about.id, about.name.clone())), error, out);
    }

    fn send_error_raw(
        &mut self,
        link: LinkId,
        about: Option<MessageId>,
        error: RouteError,
        out: &mut Vec<Action>,
    ) {
        let name = MessageName::new("tca.error").unwrap_or_else(|_| unreachable!());
        self.send_error_named(link, about.map(|id| (id, name)), error, out);
    }

    fn send_error_named(
        &mut self,
        link: LinkId,
        about: Option<(MessageId, MessageName)>,
        error: RouteError,
        out: &mut Vec<Action>,
    ) {
        tracing::debug!(link, %error, "error to sender");
        self.counters.errors_sent += 1;
        match error {
            RouteError::NotPermitted { .. } => self.counters.not_permitted += 1,
            RouteError::OverLimit { .. } => self.counters.over_limit += 1,
            _ => {}
        }
        let data = encode_data(&error).unwrap_or_default();
        let (correlation, name) = match about {
            Some((id, name)) => (Some(id), name),
            None => (
                None,
                MessageName::new("tca.error").unwrap_or_else(|_| unreachable!()),
            ),
        };
        let env = self.central_envelope(Class::Error, name, correlation, data);
        self.send(link, &env, out);
    }

    /// Sends an error to a module by name, if it is connected.
    fn send_error_to_module(
        &mut self,
        module: &ModuleName,
        about: &Envelope,
        error: RouteError,
        out: &mut Vec<Action>,
    ) {
        if let Some(link) = self.modules.get(module).and_then(|m| m.link) {
            self.send_error(link, about, error, out);
        }
    }

    fn log_frame(
        &mut self,
        direction: Direction,
        link: LinkId,
        peer: Option<ModuleName>,
        envelope: &Envelope,
        frame: Bytes,
        out: &mut Vec<Action>,
    ) {
        out.push(Action::Log(LogRecord {
            at_ns: self.now,
            kind: RecordKind::Frame(FrameRecord {
                direction,
                link,
                peer,
                name: envelope.name.clone(),
                class: envelope.class,
                frame,
            }),
        }));
    }

    fn problem(
        &mut self,
        link: Option<LinkId>,
        module: Option<ModuleName>,
        error: String,
        frame: &[u8],
        out: &mut Vec<Action>,
    ) {
        tracing::warn!(?link, ?module, %error, "bad input");
        self.record_problem(link, module, error, frame, out);
    }

    /// Logs a problem (a `Problem` record in the traffic log) without printing it.
    fn record_problem(
        &mut self,
        link: Option<LinkId>,
        module: Option<ModuleName>,
        error: String,
        frame: &[u8],
        out: &mut Vec<Action>,
    ) {
        out.push(Action::Log(LogRecord {
            at_ns: self.now,
            kind: RecordKind::Problem(ProblemRecord {
                link,
                module,
                error,
                frame_prefix: frame.iter().take(64).copied().collect(),
            }),
        }));
    }
}
