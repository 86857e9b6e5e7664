//! Errors central returns to a sender (class [`Class::Error`](crate::Class::Error)).

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Why central could not route or accept a message. Each says what to do about it.
#[derive(Clone, Debug, PartialEq, Eq, Error, Serialize, Deserialize)]
#[non_exhaustive]
pub enum RouteError {
    /// Nobody registered the name.
    #[error("no module handles message {name:?}{}; check the name and that its module registered it (`tca registry` lists what is registered)", suggestion.as_ref().map(|s| format!(" (did you mean {s:?}?)")).unwrap_or_default())]
    UnknownMessage {
        /// The name.
        name: String,
        /// A registered name that differs only in case or separators.
        suggestion: Option<String>,
    },
    /// The message was sent with a class other than the one registered.
    #[error("message {name:?} is registered as a {registered}, but was sent as a {sent}")]
    WrongClass {
        /// The name.
        name: String,
        /// Registered class.
        registered: String,
        /// Class sent.
        sent: String,
    },
    /// The handler module is down and too many messages already wait for it.
    #[error(
        "module {module} is down and {waiting} messages already wait for it (limit {limit}); restart it or raise max_waiting"
    )]
    QueueFull {
        /// Handler module.
        module: String,
        /// Messages waiting.
        waiting: u32,
        /// The limit.
        limit: u32,
    },
    /// The message waited too long for its handler module to come back.
    #[error(
        "message waited {waited_ms} ms for module {module}, which did not come back (limit {limit_ms} ms); restart it or raise max_wait"
    )]
    Expired {
        /// Handler module.
        module: String,
        /// How long it waited.
        waited_ms: u64,
        /// The limit.
        limit_ms: u64,
    },
    /// The handler module disconnected or crashed while handling a query.
    #[error(
        "module {module} went down while handling this query; its answer is lost, ask again when it is back"
    )]
    HandlerDied {
        /// Handler module.
        module: String,
    },
    /// The message data did not decode with the registered format.
    #[error("data of {name:?} does not match its registered format: {reason}")]
    BadData {
        /// Message name.
        name: String,
        /// What was wrong.
        reason: String,
    },
    /// The frame could not be decoded or broke the protocol.
    #[error("bad frame: {reason}")]
    BadFrame {
        /// What was wrong.
        reason: String,
    },
    /// The request was refused (registration, policy, state).
    #[error("{reason}")]
    Refused {
        /// What was refused and why.
        reason: String,
    },
    /// A task-tree operation failed (unknown node, constraint cycle, ...).
    #[error("task tree: {reason}")]
    Tree {
        /// What was wrong.
        reason: String,
    },
    /// The module's identity is not allowed to send or register this message by central's
    /// registration policy. Nothing of it was routed.
    #[error(
        "module {module} (identity {identity}) may not {action} {name:?}: {rule}; ask the operator to extend the policy file if it should"
    )]
    NotPermitted {
        /// The module.
        module: String,
        /// The identity it authenticated as.
        identity: String,
        /// What it tried: "send" or "register".
        action: String,
        /// The message name.
        name: String,
        /// The policy rule that decided, e.g. `identity "gait": send = ["ltm*", "moveArm"]`.
        rule: String,
    },
    /// The sending module is over one of its resource limits in central; the message was
    /// refused (not routed). Slow down, or raise the limit in central's configuration.
    #[error(
        "module {module} is over its limit of {limit} {what} (has {used}); the message was refused: send more slowly, wait for answers, or raise {setting} in central's configuration"
    )]
    OverLimit {
        /// The module.
        module: String,
        /// What is limited, e.g. "queued messages in central".
        what: String,
        /// How much it uses.
        used: u64,
        /// The limit.
        limit: u64,
        /// The configuration key that sets the limit.
        setting: String,
    },
}
