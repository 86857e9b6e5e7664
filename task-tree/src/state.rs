//! What a node is (its kind) and where it stands (its state).

use std::fmt;

use serde::{Deserialize, Serialize};

/// The message class a node stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum NodeKind {
    /// A goal: its handler plans, typically by issuing child goals and commands.
    Goal,
    /// A command: its handler performs an action; running it is achieving it.
    Command,
    /// A query, recorded as a leaf for the record; the tree never dispatches it, never
    /// constrains it, and its failure does not propagate (the asker gets the error).
    Query,
}

impl fmt::Display for NodeKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NodeKind::Goal => "goal",
            NodeKind::Command => "command",
            NodeKind::Query => "query",
        })
    }
}

/// Where a node stands. See the crate documentation for the full life cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum NodeState {
    /// Created, handler not started. It may or may not be ready to dispatch.
    Waiting,
    /// Its handler is running (for a command this is also its achievement). A node whose
    /// handler has reported success but whose handling end is held back by a constraint
    /// also stays here, with `finish_pending` set in its view.
    Handling,
    /// Its handler has finished; its achievement has not started yet (no command below it
    /// has started, and a constraint holds back its achievement start).
    Handled,
    /// Its handler has finished and its achievement interval has started; it waits for its
    /// descendants, or for a constraint on its achievement end.
    Achieving,
    /// Its handler has finished, every descendant is achieved or killed, and its
    /// achievement end has occurred. Terminal.
    Achieved,
    /// Its handler reported failure, or a descendant's failure propagated to it. Terminal,
    /// unless the failure is held by a suspension and the node is then retried.
    Failed,
    /// Killed by [`TaskTree::kill`](crate::TaskTree::kill) or because an ancestor failed.
    /// Terminal.
    Killed,
}

impl NodeState {
    /// True for the terminal states: achieved, failed and killed.
    pub fn is_terminal(self) -> bool {
        matches!(
            self,
            NodeState::Achieved | NodeState::Failed | NodeState::Killed
        )
    }
}

impl fmt::Display for NodeState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NodeState::Waiting => "waiting",
            NodeState::Handling => "handling",
            NodeState::Handled => "handled",
            NodeState::Achieving => "achieving",
            NodeState::Achieved => "achieved",
            NodeState::Failed => "failed",
            NodeState::Killed => "killed",
        })
    }
}
