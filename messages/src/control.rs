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
