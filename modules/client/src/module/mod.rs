//! A connected module. Split by job:
//!
//! - this file: [`Module`], the state its handles share, and the [`Task`] handles of sent
//!   goals and commands;
//! - [`send`]: sending queries, goals, commands, informs and exceptions, typed and raw;
//! - [`control`]: central's control requests (registry, tree, kill, constraints, exception
//!   handlers, monitors) and the link's life cycle (close, abort, offline and online);
//! - [`receive`]: the receive loop and the dispatch of what central sends to handlers;
//! - [`clock`]: the module's simulated clock.

mod clock;
mod control;
mod receive;
mod send;

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tca_link::FrameSender;
use tca_messages::control::TaskOutcome;
use tca_messages::{
    Envelope, HandlingClock, MessageId, MessageName, ModuleName, NodeId, RouteError, TaskRef,
    decode_data,
};
use tokio::sync::oneshot;
use tokio::task::AbortHandle;

use crate::error::{ModuleError, Result};
use crate::handler::HandlerEntry;

pub use control::Tapping;
pub use send::{raise_action, send_action};

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
    tx: FrameSender,
    max_frame_bytes: usize,
    /// Queries and control requests waiting for their answer.
    pending: Mutex<HashMap<MessageId, oneshot::Sender<Envelope>>>,
    /// Tasks sent with notification, waiting for their end.
    watchers: Mutex<HashMap<MessageId, oneshot::Sender<Result<TaskOutcome>>>>,
    /// Running handlers of task nodes, to stop them when central cancels the node.
    running: Mutex<HashMap<NodeId, AbortHandle>>,
    /// Where copies of tapped messages go (see [`Module::tap`]).
    tap: Mutex<Option<tokio::sync::mpsc::UnboundedSender<Envelope>>>,
    handlers: HashMap<MessageName, HandlerEntry>,
    pub(crate) query_timeout: Duration,
    /// Queries are sent again this many times when their answering module dies.
    requery_after_crash: u32,
    closed: AtomicBool,
    /// Stamp envelopes with simulated time (see [`Module::spend`]) instead of the wall clock.
    sim_time: bool,
    /// Central keeps the system's simulated clock (its welcome said so): it decides when each
    /// handler starts, and hears when an inform's handler ended or a handler awaits a task.
    central_clock: AtomicBool,
    /// The module's simulated time: the latest time it has seen or reached, nanoseconds.
    base_clock: AtomicU64,
    /// When its handlers start in simulated time.
    handling: HandlingClock,
    closed_signal: tokio::sync::watch::Sender<bool>,
    /// Changes when the module rejoins a restarted central.
    online_signal: tokio::sync::watch::Sender<bool>,
    /// The journal central keeps its tasks in, as its latest welcome said (see
    /// [`crate::rejoin`]): while it is the same, the ends of tasks this module waits for
    /// survive central's restarts.
    journal: Mutex<Option<u64>>,
    /// Keeps the transport open while any handle lives (taken by [`Module::abort_link`]).
    keep: Mutex<Option<Box<dyn std::any::Any + Send>>>,
}

/// What [`Module::new`] needs besides the link.
pub(crate) struct Settings {
    pub(crate) name: ModuleName,
    pub(crate) link_no: u32,
    pub(crate) first_seq: u32,
    pub(crate) handlers: HashMap<MessageName, HandlerEntry>,
    pub(crate) query_timeout: Duration,
    pub(crate) requery_after_crash: u32,
    pub(crate) max_frame_bytes: usize,
    pub(crate) sim_time: bool,
    pub(crate) central_clock: bool,
    pub(crate) journal: Option<u64>,
}

/// A module connected to central. Cheap to clone; the connection closes when the last clone
/// (and every running handler) is gone, or on [`Module::close`].
#[derive(Clone)]
pub struct Module {
    pub(crate) shared: Arc<Shared>,
    /// The task node messages sent through this handle are attached to.
    pub(crate) context: Option<NodeId>,
    /// The running handler's simulated clock, when this handle belongs to one.
    pub(crate) clock: Option<Arc<AtomicU64>>,
    /// The delivered message whose handler this handle belongs to (stamped on what it sends as
    /// the envelope's `cause`).
    pub(crate) handling: Option<MessageId>,
}

/// A handle that does not keep the module connected ([`Module::downgrade`]): for a task
/// beside the module's handlers (a periodic publisher) that must end with the module instead
/// of keeping its link open.
#[derive(Clone, Debug)]
pub struct WeakModule {
    shared: std::sync::Weak<Shared>,
}

impl WeakModule {
    /// The module, while any [`Module`] handle to it lives.
    pub fn upgrade(&self) -> Option<Module> {
        self.shared.upgrade().map(|shared| Module {
            shared,
            context: None,
            clock: None,
            handling: None,
        })
    }
}

impl std::fmt::Debug for Module {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Module")
            .field("name", &self.shared.name)
            .field("context", &self.context)
            .finish()
    }
}

/// A goal or command that was sent. See [`WatchedTask`] for one whose end is awaited.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Task {
    id: MessageId,
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
}

/// A goal or command sent with notification ([`Module::send_watched`]): central tells the
/// module how it ends.
#[derive(Debug)]
pub struct WatchedTask {
    task: Task,
    outcome: oneshot::Receiver<Result<TaskOutcome>>,
    /// The handler that sent it, which tells central it waits (simulated clock only).
    waiter: Option<Module>,
}

impl WatchedTask {
    /// The id of the message that created the task.
    pub fn id(&self) -> MessageId {
        self.task.id
    }

    /// A reference to the task for temporal constraints of later sends.
    pub fn task_ref(&self) -> TaskRef {
        self.task.task_ref()
    }

    /// The task, without its outcome.
    pub fn task(&self) -> Task {
        self.task
    }

    /// Waits until the task is achieved, fails or is killed. Fails only when central refused
    /// the task ([`ModuleError::Route`]), went away ([`ModuleError::CentralLost`]) or the link
    /// closed ([`ModuleError::Disconnected`]).
    pub async fn outcome(self) -> Result<TaskOutcome> {
        if let Some(handler) = &self.waiter {
            handler.awaiting(self.task.id)?;
        }
        self.outcome.await.map_err(|_| ModuleError::Disconnected)?
    }
}

impl Module {
    pub(crate) fn new(
        settings: Settings,
        tx: FrameSender,
        keep: Box<dyn std::any::Any + Send>,
    ) -> Self {
        Module {
            shared: Arc::new(Shared {
                name: settings.name,
                link_no: AtomicU32::new(settings.link_no),
                online: AtomicBool::new(true),
                seq: AtomicU32::new(settings.first_seq),
                tx,
                max_frame_bytes: settings.max_frame_bytes,
                pending: Mutex::new(HashMap::new()),
                watchers: Mutex::new(HashMap::new()),
                running: Mutex::new(HashMap::new()),
                tap: Mutex::new(None),
                handlers: settings.handlers,
                query_timeout: settings.query_timeout,
                requery_after_crash: settings.requery_after_crash,
                closed: AtomicBool::new(false),
                sim_time: settings.sim_time,
                central_clock: AtomicBool::new(settings.central_clock),
                base_clock: AtomicU64::new(0),
                handling: HandlingClock::new(),
                closed_signal: tokio::sync::watch::channel(false).0,
                online_signal: tokio::sync::watch::channel(true).0,
                journal: Mutex::new(settings.journal),
                keep: Mutex::new(Some(keep)),
            }),
            context: None,
            clock: None,
            handling: None,
        }
    }

    /// A handle that does not keep the module connected: the link closes when the last
    /// [`Module`] handle is dropped, whatever weak handles remain.
    pub fn downgrade(&self) -> WeakModule {
        WeakModule {
            shared: Arc::downgrade(&self.shared),
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
            handling: self.handling,
        }
    }
}

/// The error central's error envelope carries.
pub(crate) fn route_error(envelope: &Envelope) -> ModuleError {
    match decode_data::<RouteError>(&envelope.data) {
        Ok(e) => ModuleError::Route(e),
        Err(e) => ModuleError::Protocol(format!("unreadable error from central: {e}")),
    }
}

pub(crate) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}
