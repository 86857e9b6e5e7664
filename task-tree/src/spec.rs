//! What the caller gives to create a node, and what a handler reports when it ends.

use serde::{Deserialize, Serialize};

use crate::constraint::NewConstraint;
use crate::id::NodeId;
use crate::state::NodeKind;

/// Everything needed to add a node to the tree.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct NodeSpec {
    /// The node whose handler issued this message (or the node being patched), or `None`
    /// for a new root.
    pub parent: Option<NodeId>,
    /// Goal, command or query.
    pub kind: NodeKind,
    /// The message name, e.g. `planGait`.
    pub name: String,
    /// The module that handles it, e.g. `gait-planner`.
    pub handler: String,
    /// Constraints relative to the new node, checked and added with it.
    pub constraints: Vec<NewConstraint>,
}

impl NodeSpec {
    /// A new root node of the given kind with no constraints; see [`NodeSpec::under`] and
    /// [`NodeSpec::with`].
    pub fn new(kind: NodeKind, name: impl Into<String>, handler: impl Into<String>) -> Self {
        NodeSpec {
            parent: None,
            kind,
            name: name.into(),
            handler: handler.into(),
            constraints: Vec::new(),
        }
    }

    /// A goal message `name` handled by module `handler`.
    pub fn goal(name: impl Into<String>, handler: impl Into<String>) -> Self {
        NodeSpec::new(NodeKind::Goal, name, handler)
    }

    /// A command message `name` handled by module `handler`.
    pub fn command(name: impl Into<String>, handler: impl Into<String>) -> Self {
        NodeSpec::new(NodeKind::Command, name, handler)
    }

    /// A query message `name` handled by module `handler`, recorded as a leaf.
    pub fn query(name: impl Into<String>, handler: impl Into<String>) -> Self {
        NodeSpec::new(NodeKind::Query, name, handler)
    }

    /// Places the node under `parent`.
    pub fn under(mut self, parent: NodeId) -> Self {
        self.parent = Some(parent);
        self
    }

    /// Adds a constraint relative to the new node.
    pub fn with(mut self, constraint: NewConstraint) -> Self {
        self.constraints.push(constraint);
        self
    }
}

/// How a handler ended.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum Outcome {
    /// The handler did its work.
    Success,
    /// The handler failed; the failure policy of the crate documentation applies.
    Failure {
        /// Why, in words for the operator.
        reason: String,
    },
}

impl Outcome {
    /// A failure with the given reason.
    pub fn failure(reason: impl Into<String>) -> Self {
        Outcome::Failure {
            reason: reason.into(),
        }
    }
}
