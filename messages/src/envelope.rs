//! The envelope: what travels between a module and central, and what the log records.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::class::Class;
use crate::id::{MessageId, MessageName, ModuleName};

/// A task-tree node, as named on the wire. Central assigns node ids.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct NodeId(pub u64);

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "n{}", self.0)
    }
}

impl fmt::Debug for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

/// One endpoint of a node's two intervals (§3.2): handling (its handler runs; planning, for a
/// goal) and achievement (it and all its descendants are carried out).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TimePoint {
    /// The handler starts.
    HandlingStart,
    /// The handler ends.
    HandlingEnd,
    /// Achievement starts.
    AchievementStart,
    /// The node and all its descendants are done.
    AchievementEnd,
}

/// Which task a constraint point refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TaskRef {
    /// The goal or command being sent.
    This,
    /// The node created by an earlier goal or command, named by that message's id (known to its
    /// sender at once, before central has assigned a node id).
    Message(MessageId),
    /// A node by its node id.
    Node(NodeId),
}

/// A time point of a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct PointRef {
    /// The task.
    pub task: TaskRef,
    /// The point.
    pub point: TimePoint,
}

/// A temporal constraint `before <= after`: `after` may not occur until `before` has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ConstraintSpec {
    /// The earlier point.
    pub before: PointRef,
    /// The later point.
    pub after: PointRef,
}

impl ConstraintSpec {
    /// `end(point_a of a) <= point_b of b`, the general form.
    pub fn points(a: TaskRef, pa: TimePoint, b: TaskRef, pb: TimePoint) -> Self {
        ConstraintSpec {
            before: PointRef { task: a, point: pa },
            after: PointRef { task: b, point: pb },
        }
    }

    /// `a` is achieved before `b` starts being achieved.
    pub fn sequential_achievement(a: TaskRef, b: TaskRef) -> Self {
        Self::points(a, TimePoint::AchievementEnd, b, TimePoint::AchievementStart)
    }

    /// `b` is not handled (planned) until `a` is achieved.
    pub fn delay_planning(a: TaskRef, b: TaskRef) -> Self {
        Self::points(a, TimePoint::AchievementEnd, b, TimePoint::HandlingStart)
    }

    /// `b` is handled only after `a`'s handling has started (invocation order).
    pub fn invocation_order(a: TaskRef, b: TaskRef) -> Self {
        Self::points(a, TimePoint::HandlingStart, b, TimePoint::HandlingStart)
    }
}

/// Options a sender attaches to a message.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SendOptions {
    /// Temporal constraints on the goal or command being sent.
    pub constraints: Vec<ConstraintSpec>,
    /// Ask central to tell the sender when the goal or command is achieved or fails.
    pub notify: bool,
}

/// Why a handler ended a goal, command, query or exception with failure.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Failure {
    /// A sentence saying what went wrong.
    pub reason: String,
}

/// A message with its routing header. Its `data` is the postcard encoding of the message value.
#[derive(Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Envelope {
    /// Unique id, chosen by the sender (see [`MessageId`]).
    pub id: MessageId,
    /// The message class.
    pub class: Class,
    /// The message name.
    pub name: MessageName,
    /// The module that sent it (central for messages it originates: `central`).
    pub sender: ModuleName,
    /// The sender's current task node: the node whose handler sent this message, if any.
    pub context: Option<NodeId>,
    /// The task node this message creates (a goal or command as delivered to its handler) or ends
    /// (success, failure), set by central.
    pub node: Option<NodeId>,
    /// The message this one answers (reply, success, failure, error, control answers).
    pub correlation: Option<MessageId>,
    /// The delivered message whose handler sent this one (`None` for what a module sends
    /// outside its handlers). On simulated time central follows handlers by it: a handler
    /// waiting for the answer to its query cannot send anything earlier.
    pub cause: Option<MessageId>,
    /// When the sender sent it: nanoseconds since the UNIX epoch on the sender's clock.
    pub timestamp_ns: u64,
    /// Sender's options (constraints, notification).
    pub options: SendOptions,
    /// How many times central has delivered this message before (after a handler crashed).
    pub redelivery: u32,
    /// The message data, postcard-encoded.
    #[serde(with = "crate::codec::bytes_field")]
    pub data: Vec<u8>,
}

impl fmt::Debug for Envelope {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {} {} from {}",
            self.id, self.class, self.name, self.sender
        )?;
        if let Some(n) = self.node {
            write!(f, " node {n}")?;
        }
        if let Some(c) = self.context {
            write!(f, " ctx {c}")?;
        }
        if let Some(c) = self.correlation {
            write!(f, " re {c}")?;
        }
        write!(f, " ({} data bytes)", self.data.len())
    }
}

/// Current time as nanoseconds since the UNIX epoch.
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}
