//! What the tree reports back from each call.

use serde::{Deserialize, Serialize};

use crate::id::NodeId;
use crate::state::NodeState;

/// Something that happened in the tree during a call, in the order it happened. Every
/// event happened at the `now` of the call that returned it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum TreeEvent {
    /// The node has just become ready to dispatch to its handler. Emitted each time it
    /// becomes ready; call [`TaskTree::is_ready`](crate::TaskTree::is_ready) before
    /// dispatching, since a later constraint or suspension can take readiness away (a new
    /// `Ready` follows when it returns).
    Ready(NodeId),
    /// The node's handler was started (its handling-start point occurred).
    HandlingStarted(NodeId),
    /// The node's handling-end point occurred (its handler finished and no constraint holds
    /// the end back any longer).
    HandlingEnded(NodeId),
    /// The node's achievement-start point occurred.
    AchievementStarted(NodeId),
    /// The node's achievement-end point occurred: it is achieved.
    Achieved(NodeId),
    /// The node failed: its own handler reported failure, or a descendant's failure
    /// propagated to it (the reason then names the descendant).
    Failed {
        /// The failed node.
        node: NodeId,
        /// Why.
        reason: String,
    },
    /// The node failed because a descendant failed while its own handler is still
    /// running: central should send that handler a cancel notice.
    CancelHandler(NodeId),
    /// The node was killed. `was: Handling` means its handler is running and must get a
    /// cancel notice.
    Killed {
        /// The killed node.
        node: NodeId,
        /// Its state just before.
        was: NodeState,
    },
    /// The node and everything below it have left the tree (their memory is freed);
    /// constraints naming them count as satisfied from now on.
    Retired(NodeId),
}

impl TreeEvent {
    /// The node this event is about.
    pub fn node(&self) -> NodeId {
        match self {
            TreeEvent::Ready(n)
            | TreeEvent::HandlingStarted(n)
            | TreeEvent::HandlingEnded(n)
            | TreeEvent::AchievementStarted(n)
            | TreeEvent::Achieved(n)
            | TreeEvent::CancelHandler(n)
            | TreeEvent::Retired(n) => *n,
            TreeEvent::Failed { node, .. } | TreeEvent::Killed { node, .. } => *node,
        }
    }
}
