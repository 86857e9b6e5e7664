//! Central's own control traffic. These travel as ordinary envelopes of class
//! [`Class::Control`](crate::Class::Control) with reserved `tca.` names, so the log records them
//! like everything else.

use serde::{Deserialize, Serialize};

use crate::class::Class;
use crate::envelope::{ConstraintSpec, NodeId};
use crate::format::DataFormat;
use crate::id::{MessageName, ModuleName};

/// Prefix of every control message name.
pub const CONTROL_PREFIX: &str = "tca.";

/// Control message names.
pub mod names {
    /// Module -> central: first frame on a link.
    pub const HELLO: &str = "tca.hello";
    /// Module -> central: first frame on a link, with credentials ([`super::AuthHello`]);
    /// central answers it like [`HELLO`] (welcome or refusal).
    pub const HELLO_AUTH: &str = "tca.helloAuth";
    /// Central -> module: the link is accepted ([`super::Welcome`]).
    pub const WELCOME: &str = "tca.welcome";
    /// Module -> central: register handlers ([`super::Register`]); answered with
    /// [`super::RegisterOutcome`].
    pub const REGISTER: &str = "tca.register";
    /// Module -> central: ask for the registry; answered with [`super::Registry`].
    pub const REGISTRY: &str = "tca.registry";
    /// Central -> module: stop the handler of a node that was killed ([`super::Cancel`]).
    pub const CANCEL: &str = "tca.cancel";
    /// Module -> central: the module is leaving.
    pub const BYE: &str = "tca.bye";
    /// Module -> central: kill a task tree or subtree ([`super::Kill`]).
    pub const KILL: &str = "tca.kill";
    /// Module -> central: add a temporal constraint ([`super::Constrain`]).
    pub const CONSTRAIN: &str = "tca.constrain";
    /// Module -> central: ask for the live task trees; answered with [`super::TreeView`].
    pub const TREE: &str = "tca.tree";
    /// Central -> sender: a goal or command it asked to hear about ended ([`super::TaskEnded`]).
    pub const TASK_ENDED: &str = "tca.taskEnded";
    /// Module -> central: attach the module as handler of an exception on a node
    /// ([`super::OnException`]).
    pub const ON_EXCEPTION: &str = "tca.onException";
    /// Module -> central: put a node back to waiting so it is handled again
    /// ([`super::Retry`]).
    pub const RETRY: &str = "tca.retry";
    /// Module -> central: monitor a node with a condition query ([`super::Monitor`]).
    pub const MONITOR: &str = "tca.monitor";
    /// Module -> central, on simulated time: the sending handler now waits for the end of a
    /// task ([`super::Await`]); no answer.
    pub const AWAIT: &str = "tca.await";
    /// Module -> central: kill the task tree node a goal or command created, by the id of its
    /// message ([`super::KillTask`]).
    pub const KILL_TASK: &str = "tca.killTask";
    /// Module -> central: kill every task tree (an emergency stop); answered with the number
    /// of trees killed (`u64`).
    pub const KILL_ALL: &str = "tca.killAll";
    /// Module -> central: copy to the module the traffic of some message names
    /// ([`super::Tap`]).
    pub const TAP: &str = "tca.tap";
    /// Central -> module: a copy of a message of a name it taps ([`super::Tapped`]).
    pub const TAPPED: &str = "tca.tapped";
    /// Module -> central: what became of goals and commands the module sent
    /// ([`super::TaskStatusRequest`]); answered with a list of [`super::TaskStatus`].
    pub const TASK_STATUS: &str = "tca.taskStatus";
}

/// Name of the pseudo-module central uses as sender of its own messages.
pub const CENTRAL: &str = "central";

/// First frame a module sends on a new link.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Hello {
    /// The module's name; at most one connected module has it.
    pub module: ModuleName,
    /// How many goals/commands the module handles at once (TCA's resource management); 0 is
    /// read as 1.
    pub capacity: u32,
    /// The module's process id, for diagnostics.
    pub pid: u32,
    /// The module's host name, for diagnostics.
    pub host: String,
    /// The module stamps its messages with simulated time. On a central that keeps simulated
    /// time, central follows such a module's handlers (their queries and ends) to know when
    /// the clock may move on.
    pub simulated_time: bool,
}

/// This machine's host name as a [`Hello`] carries it (`$HOSTNAME`, else `/etc/hostname`,
/// else `unknown`).
pub fn this_host() -> String {
    std::env::var("HOSTNAME")
        .ok()
        .or_else(|| std::fs::read_to_string("/etc/hostname").ok())
        .map(|h| h.trim().to_owned())
        .unwrap_or_else(|| "unknown".into())
}

/// Who a module says it is, checked by central against its policy file. The secret travels in
/// the hello frame (central never logs it): use it on a trusted network or inside zenoh's
/// authenticated transport.
#[derive(Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Credentials {
    /// The identity named in central's policy file.
    pub identity: String,
    /// Its secret.
    pub secret: String,
}

impl std::fmt::Debug for Credentials {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Credentials {{ identity: {:?}, secret: *** }}",
            self.identity
        )
    }
}

/// A hello with credentials ([`names::HELLO_AUTH`]).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct AuthHello {
    /// The ordinary hello.
    pub hello: Hello,
    /// Who the module says it is.
    pub credentials: Credentials,
}

/// Central's acceptance of a link.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Welcome {
    /// The link number: the high 32 bits of every message id the module sends.
    pub link: u32,
    /// Central's version string.
    pub central_version: String,
    /// Central keeps the system's simulated clock: it releases messages in simulated-time
    /// order and follows each simulated module's handlers, which then tell it when an
    /// inform's handler ended and when a handler waits for a task's end.
    pub simulated_clock: bool,
    /// The id of the journal central keeps its task trees and queues in, if it keeps one. A
    /// central restarted on the same journal after a crash welcomes with the same id: a module
    /// that rejoins it knows that the tasks it sent live on there (and asks what became of
    /// them with [`TaskStatusRequest`]); a different id, or none, means they are lost.
    pub journal: Option<u64>,
}

/// One message a module offers to handle.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Registration {
    /// Message name.
    pub name: MessageName,
    /// Its class (query, goal, command, inform or exception).
    pub class: Class,
    /// Format of the message data.
    pub format: DataFormat,
    /// Format of the reply, for queries.
    pub reply: Option<DataFormat>,
    /// Take the name over from another module that registered it (swapping implementations,
    /// e.g. the simulator for the real controller).
    pub replace: bool,
}

/// A batch of registrations.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Register {
    /// The messages.
    pub entries: Vec<Registration>,
}

/// Central's answer to [`Register`].
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegisterOutcome {
    /// Names now routed to the module.
    pub accepted: Vec<MessageName>,
    /// Names refused, each with the reason.
    pub refused: Vec<(MessageName, String)>,
}

/// One entry of the registry.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegistryEntry {
    /// Message name.
    pub name: MessageName,
    /// Class.
    pub class: Class,
    /// The module that handles it.
    pub handler: ModuleName,
    /// Whether that module is connected now.
    pub connected: bool,
    /// Data format.
    pub format: DataFormat,
    /// Reply format, for queries.
    pub reply: Option<DataFormat>,
    /// Messages waiting in central for the handler.
    pub waiting: u32,
}

/// The registry: every registered message.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Registry {
    /// Entries sorted by name.
    pub entries: Vec<RegistryEntry>,
    /// Connected modules.
    pub modules: Vec<ModuleName>,
}

/// Tells a module to stop handling a node that has been killed.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Cancel {
    /// The node.
    pub node: NodeId,
}

/// Kill a node and its subtree (a root kills the whole tree).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Kill {
    /// The node.
    pub node: NodeId,
}

/// Attach the sending module as the handler of exception `name` raised at `node` or below.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct OnException {
    /// The node.
    pub node: NodeId,
    /// The exception name (registered by the sender, class exception).
    pub name: MessageName,
}

/// Put a node whose failure is held by an exception (or whose handler has finished) back to
/// waiting, so it is delivered again.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Retry {
    /// The node.
    pub node: NodeId,
}

/// What a monitor does when its condition holds.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MonitorAction {
    /// Raise this exception in the monitored node's context.
    Raise {
        /// Exception name.
        name: MessageName,
        /// Its data (postcard).
        data: Vec<u8>,
    },
    /// Send this goal, command or inform (goals and commands become children of the node).
    Send {
        /// Class (goal, command or inform).
        class: Class,
        /// Message name.
        name: MessageName,
        /// Its data (postcard).
        data: Vec<u8>,
    },
}

/// TCA execution monitoring: a condition query checked once when a node starts (point
/// monitor, `period_ms: None`) or every `period_ms` while it is active (polling monitor).
/// The query's reply must be a `bool`; `true` triggers the action, once. The monitor ends
/// with its node.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Monitor {
    /// The monitored node.
    pub node: NodeId,
    /// The condition: a registered query whose reply is `bool`.
    pub query: MessageName,
    /// The query's data (postcard).
    pub query_data: Vec<u8>,
    /// Polling period in milliseconds; `None` for a point monitor.
    pub period_ms: Option<u64>,
    /// What to do when the condition holds.
    pub action: MonitorAction,
}

/// The sending handler waits for the end of a goal or command it sent with notification (on
/// a central that keeps simulated time, so that central knows the handler will send nothing
/// more until that task's end reaches it).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Await {
    /// The id of the message that created the task.
    pub task: crate::id::MessageId,
}

/// Kill the task-tree node a goal or command created, and its subtree.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct KillTask {
    /// The id of the message that created the task.
    pub task: crate::id::MessageId,
}

/// Copy to the sending module every message of these names that modules send central or
/// central sends on its own (queries, goals, commands, informs, exceptions and their answers
/// and errors; never control traffic), as [`Tapped`] notices, until the module leaves. A new
/// tap replaces the module's previous one.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tap {
    /// The names; empty for every name.
    pub names: Vec<MessageName>,
}

/// Ask central what became of goals and commands the asking module sent (by the ids of their
/// messages): a module that rejoins a central restarted on its journal asks this for the tasks
/// whose ends it waits for, since ends told while it was away did not reach it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TaskStatusRequest {
    /// The ids of the messages that created the tasks.
    pub tasks: Vec<crate::id::MessageId>,
}

/// What central knows of one task a module asked about ([`TaskStatusRequest`]).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TaskStatus {
    /// The id of the message that created the task.
    pub task: crate::id::MessageId,
    /// Where it stands.
    pub state: TaskState,
}

/// Where a task a module asked about stands.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TaskState {
    /// Central holds it (waiting, running or waiting for its children): its end will be told.
    Live,
    /// It ended, this way (central remembers the latest few thousand ends it told or could not
    /// tell).
    Ended(TaskOutcome),
    /// Central has no such task from this module: it never reached central, or it ended too
    /// long ago to be remembered.
    Unknown,
}

/// A copy of a tapped message.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tapped {
    /// The message as central received (or sent) it.
    pub envelope: crate::envelope::Envelope,
}

/// Add a temporal constraint between existing nodes.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Constrain {
    /// The constraint (`TaskRef::This` is not meaningful here).
    pub constraint: ConstraintSpec,
}

/// The live task trees, rendered by central.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TreeView {
    /// Indented text, one line per node.
    pub text: String,
    /// Live node count.
    pub nodes: u64,
}

/// How a goal or command ended, sent to senders that asked (`SendOptions::notify`) and to the
/// originator of every root task.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TaskOutcome {
    /// Achieved.
    Achieved,
    /// Failed, with the reason.
    Failed(String),
    /// Killed.
    Killed,
}

/// Notification that a task ended.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TaskEnded {
    /// The node.
    pub node: NodeId,
    /// Its outcome.
    pub outcome: TaskOutcome,
}

/// The kinds of control request a module sends central, by wire name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ControlKind {
    /// [`names::HELLO`].
    Hello,
    /// [`names::HELLO_AUTH`].
    HelloAuth,
    /// [`names::REGISTER`].
    Register,
    /// [`names::REGISTRY`].
    Registry,
    /// [`names::TREE`].
    Tree,
    /// [`names::BYE`].
    Bye,
    /// [`names::KILL`].
    Kill,
    /// [`names::CONSTRAIN`].
    Constrain,
    /// [`names::ON_EXCEPTION`].
    OnException,
    /// [`names::RETRY`].
    Retry,
    /// [`names::MONITOR`].
    Monitor,
    /// [`names::AWAIT`].
    Await,
    /// [`names::KILL_TASK`].
    KillTask,
    /// [`names::KILL_ALL`].
    KillAll,
    /// [`names::TAP`].
    Tap,
    /// [`names::TASK_STATUS`].
    TaskStatus,
}

impl ControlKind {
    /// Every kind of control request.
    pub const ALL: [ControlKind; 16] = [
        ControlKind::Hello,
        ControlKind::HelloAuth,
        ControlKind::Register,
        ControlKind::Registry,
        ControlKind::Tree,
        ControlKind::Bye,
        ControlKind::Kill,
        ControlKind::Constrain,
        ControlKind::OnException,
        ControlKind::Retry,
        ControlKind::Monitor,
        ControlKind::Await,
        ControlKind::KillTask,
        ControlKind::KillAll,
        ControlKind::Tap,
        ControlKind::TaskStatus,
    ];

    /// The wire name.
    pub fn name(self) -> &'static str {
        match self {
            ControlKind::Hello => names::HELLO,
            ControlKind::HelloAuth => names::HELLO_AUTH,
            ControlKind::Register => names::REGISTER,
            ControlKind::Registry => names::REGISTRY,
            ControlKind::Tree => names::TREE,
            ControlKind::Bye => names::BYE,
            ControlKind::Kill => names::KILL,
            ControlKind::Constrain => names::CONSTRAIN,
            ControlKind::OnException => names::ON_EXCEPTION,
            ControlKind::Retry => names::RETRY,
            ControlKind::Monitor => names::MONITOR,
            ControlKind::Await => names::AWAIT,
            ControlKind::KillTask => names::KILL_TASK,
            ControlKind::KillAll => names::KILL_ALL,
            ControlKind::Tap => names::TAP,
            ControlKind::TaskStatus => names::TASK_STATUS,
        }
    }

    /// The kind a wire name names, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// A hello: the first frame on a link.
    pub fn is_hello(self) -> bool {
        matches!(self, ControlKind::Hello | ControlKind::HelloAuth)
    }

    /// Whether central answers the request (all but [`ControlKind::Await`]).
    pub fn is_answered(self) -> bool {
        self != ControlKind::Await
    }

    /// Whether the request acts on the task trees (kill, constrain, exception handlers, retry,
    /// monitors). The others (hellos, registration, registry and tree inspection, goodbye, a
    /// handler's await) are the link's bookkeeping: every connected module may send them
    /// without a policy rule, and they move no module's simulated clock.
    pub fn acts_on_tasks(self) -> bool {
        matches!(
            self,
            ControlKind::Kill
                | ControlKind::KillTask
                | ControlKind::KillAll
                | ControlKind::Constrain
                | ControlKind::OnException
                | ControlKind::Retry
                | ControlKind::Monitor
        )
    }
}

impl std::fmt::Display for ControlKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A control request a module sends central, with its data: the one type both the module
/// library (which encodes it) and central (which decodes and routes it) use.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ControlRequest {
    /// The first frame on a link; answered with a [`Welcome`] or a refusal.
    Hello(Hello),
    /// The first frame on a link, with credentials; answered like [`ControlRequest::Hello`].
    HelloAuth(AuthHello),
    /// Register handlers; answered with a [`RegisterOutcome`].
    Register(Register),
    /// Ask for the registry; answered with a [`Registry`].
    Registry,
    /// Ask for the live task trees; answered with a [`TreeView`].
    Tree,
    /// The module is leaving; answered with `()`.
    Bye,
    /// Kill a node and its subtree; answered with `()`.
    Kill(Kill),
    /// Add a temporal constraint; answered with `()`.
    Constrain(Constrain),
    /// Attach the sender as handler of an exception on a node; answered with `()`.
    OnException(OnException),
    /// Put a node back to waiting; answered with `()`.
    Retry(Retry),
    /// Monitor a node with a condition query; answered with `()`.
    Monitor(Monitor),
    /// The sending handler waits for a task's end (simulated time); not answered.
    Await(Await),
    /// Kill the node a goal or command created, and its subtree; answered with `()`.
    KillTask(KillTask),
    /// Kill every task tree; answered with the number of trees killed (`u64`).
    KillAll,
    /// Copy the traffic of some names to the sender; answered with `()`.
    Tap(Tap),
    /// What became of tasks the sender sent; answered with a list of [`TaskStatus`].
    TaskStatus(TaskStatusRequest),
}

/// Why a control request could not be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ControlError {
    /// No control request has this name.
    #[error(
        "unknown control message {name:?}; this central understands {}",
        ControlKind::ALL.map(ControlKind::name).join(", ")
    )]
    Unknown {
        /// The name given.
        name: String,
    },
    /// The data does not decode as the request's.
    #[error("bad {kind} data: {reason}")]
    BadData {
        /// The request.
        kind: ControlKind,
        /// The decoder's complaint.
        reason: String,
    },
}

impl ControlRequest {
    /// Its kind.
    pub fn kind(&self) -> ControlKind {
        match self {
            ControlRequest::Hello(_) => ControlKind::Hello,
            ControlRequest::HelloAuth(_) => ControlKind::HelloAuth,
            ControlRequest::Register(_) => ControlKind::Register,
            ControlRequest::Registry => ControlKind::Registry,
            ControlRequest::Tree => ControlKind::Tree,
            ControlRequest::Bye => ControlKind::Bye,
            ControlRequest::Kill(_) => ControlKind::Kill,
            ControlRequest::Constrain(_) => ControlKind::Constrain,
            ControlRequest::OnException(_) => ControlKind::OnException,
            ControlRequest::Retry(_) => ControlKind::Retry,
            ControlRequest::Monitor(_) => ControlKind::Monitor,
            ControlRequest::Await(_) => ControlKind::Await,
            ControlRequest::KillTask(_) => ControlKind::KillTask,
            ControlRequest::KillAll => ControlKind::KillAll,
            ControlRequest::Tap(_) => ControlKind::Tap,
            ControlRequest::TaskStatus(_) => ControlKind::TaskStatus,
        }
    }

    /// The wire name.
    pub fn name(&self) -> &'static str {
        self.kind().name()
    }

    /// The data, postcard-encoded.
    pub fn encode_data(&self) -> Result<Vec<u8>, crate::CodecError> {
        use crate::codec::encode_data as enc;
        match self {
            ControlRequest::Hello(h) => enc(h),
            ControlRequest::HelloAuth(h) => enc(h),
            ControlRequest::Register(r) => enc(r),
            ControlRequest::Registry
            | ControlRequest::Tree
            | ControlRequest::Bye
            | ControlRequest::KillAll => enc(&()),
            ControlRequest::Kill(k) => enc(k),
            ControlRequest::Constrain(c) => enc(c),
            ControlRequest::OnException(o) => enc(o),
            ControlRequest::Retry(r) => enc(r),
            ControlRequest::Monitor(m) => enc(m),
            ControlRequest::Await(a) => enc(a),
            ControlRequest::KillTask(k) => enc(k),
            ControlRequest::Tap(t) => enc(t),
            ControlRequest::TaskStatus(t) => enc(t),
        }
    }

    /// Reads a request from its wire name and data. Requests without data (registry, tree,
    /// goodbye, kill all) ignore what they carry.
    pub fn decode(name: &str, data: &[u8]) -> Result<Self, ControlError> {
        let kind = ControlKind::from_name(name).ok_or_else(|| ControlError::Unknown {
            name: name.to_owned(),
        })?;
        fn dec<T: serde::de::DeserializeOwned>(
            kind: ControlKind,
            data: &[u8],
        ) -> Result<T, ControlError> {
            crate::codec::decode_data(data).map_err(|e| ControlError::BadData {
                kind,
                reason: e.to_string(),
            })
        }
        Ok(match kind {
            ControlKind::Hello => ControlRequest::Hello(dec(kind, data)?),
            ControlKind::HelloAuth => ControlRequest::HelloAuth(dec(kind, data)?),
            ControlKind::Register => ControlRequest::Register(dec(kind, data)?),
            ControlKind::Registry => ControlRequest::Registry,
            ControlKind::Tree => ControlRequest::Tree,
            ControlKind::Bye => ControlRequest::Bye,
            ControlKind::Kill => ControlRequest::Kill(dec(kind, data)?),
            ControlKind::Constrain => ControlRequest::Constrain(dec(kind, data)?),
            ControlKind::OnException => ControlRequest::OnException(dec(kind, data)?),
            ControlKind::Retry => ControlRequest::Retry(dec(kind, data)?),
            ControlKind::Monitor => ControlRequest::Monitor(dec(kind, data)?),
            ControlKind::Await => ControlRequest::Await(dec(kind, data)?),
            ControlKind::KillTask => ControlRequest::KillTask(dec(kind, data)?),
            ControlKind::KillAll => ControlRequest::KillAll,
            ControlKind::Tap => ControlRequest::Tap(dec(kind, data)?),
            ControlKind::TaskStatus => ControlRequest::TaskStatus(dec(kind, data)?),
        })
    }
}

/// A control notice central sends a module unasked: the one type central (which encodes it)
/// and the module library (which decodes it) use.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ControlNotice {
    /// The link is accepted (the answer to a hello).
    Welcome(Welcome),
    /// Stop the handler of a node that was killed.
    Cancel(Cancel),
    /// A goal or command the module asked to hear about ended.
    TaskEnded(TaskEnded),
    /// A copy of a message of a name the module taps.
    Tapped(Box<Tapped>),
}

impl ControlNotice {
    /// The wire name.
    pub fn name(&self) -> &'static str {
        match self {
            ControlNotice::Welcome(_) => names::WELCOME,
            ControlNotice::Cancel(_) => names::CANCEL,
            ControlNotice::TaskEnded(_) => names::TASK_ENDED,
            ControlNotice::Tapped(_) => names::TAPPED,
        }
    }

    /// The data, postcard-encoded.
    pub fn encode_data(&self) -> Result<Vec<u8>, crate::CodecError> {
        use crate::codec::encode_data as enc;
        match self {
            ControlNotice::Welcome(w) => enc(w),
            ControlNotice::Cancel(c) => enc(c),
            ControlNotice::TaskEnded(t) => enc(t),
            ControlNotice::Tapped(t) => enc(t.as_ref()),
        }
    }

    /// Reads a notice from its wire name and data; `None` for a name that is not a notice
    /// (answers to requests carry the request's name) or data that does not decode.
    pub fn decode(name: &str, data: &[u8]) -> Option<Self> {
        use crate::codec::decode_data as dec;
        Some(match name {
            names::WELCOME => ControlNotice::Welcome(dec(data).ok()?),
            names::CANCEL => ControlNotice::Cancel(dec(data).ok()?),
            names::TASK_ENDED => ControlNotice::TaskEnded(dec(data).ok()?),
            names::TAPPED => ControlNotice::Tapped(Box::new(dec(data).ok()?)),
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_has_one_name_and_is_found_by_it() {
        for kind in ControlKind::ALL {
            assert!(kind.name().starts_with(CONTROL_PREFIX));
            assert_eq!(ControlKind::from_name(kind.name()), Some(kind));
        }
        assert_eq!(ControlKind::from_name("tca.nope"), None);
    }

    #[test]
    fn requests_round_trip_through_name_and_data() {
        let requests = [
            ControlRequest::Kill(Kill { node: NodeId(4) }),
            ControlRequest::Retry(Retry { node: NodeId(2) }),
            ControlRequest::Registry,
            ControlRequest::Bye,
            ControlRequest::KillAll,
            ControlRequest::KillTask(KillTask {
                task: crate::id::MessageId::new(3, 7),
            }),
            ControlRequest::Tap(Tap {
                names: vec![MessageName::new("bodyMove").unwrap()],
            }),
            ControlRequest::TaskStatus(TaskStatusRequest {
                tasks: vec![crate::id::MessageId::new(3, 8)],
            }),
        ];
        for r in requests {
            let data = r.encode_data().unwrap();
            assert_eq!(ControlRequest::decode(r.name(), &data).unwrap(), r);
        }
    }

    #[test]
    fn unknown_names_and_bad_data_say_what_is_wrong() {
        let err = ControlRequest::decode("tca.frobnicate", &[]).unwrap_err();
        assert!(err.to_string().contains("tca.kill"), "{err}");
        let err = ControlRequest::decode(names::KILL, &[]).unwrap_err();
        assert!(err.to_string().starts_with("bad tca.kill data"), "{err}");
    }

    #[test]
    fn notices_round_trip() {
        let n = ControlNotice::Cancel(Cancel { node: NodeId(9) });
        let data = n.encode_data().unwrap();
        assert_eq!(ControlNotice::decode(n.name(), &data), Some(n));
        assert_eq!(ControlNotice::decode(names::KILL, &data), None);
    }
}
