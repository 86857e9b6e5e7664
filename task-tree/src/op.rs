//! Mutations as data: what central logs, and what replay feeds back in.

use serde::{Deserialize, Serialize};

use crate::constraint::Constraint;
use crate::error::{Result, TreeError};
use crate::event::TreeEvent;
use crate::id::{Nanos, NodeId};
use crate::spec::{NodeSpec, Outcome};
use crate::tree::TaskTree;

/// One mutating call on a [`TaskTree`], with its time. Applying the same sequence of ops
/// to a fresh tree reproduces the same ids, states and events exactly.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum TreeOp {
    /// [`TaskTree::add_node`]; `id` is the id the node got.
    AddNode {
        /// The id assigned when the op was first applied.
        id: NodeId,
        /// The node.
        spec: NodeSpec,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::add_constraint`].
    AddConstraint {
        /// The constraint.
        constraint: Constraint,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::plan_first`].
    PlanFirst {
        /// The node.
        node: NodeId,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::start`].
    Start {
        /// The node.
        node: NodeId,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::finish`].
    Finish {
        /// The node.
        node: NodeId,
        /// How its handler ended.
        outcome: Outcome,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::kill`].
    Kill {
        /// The node.
        node: NodeId,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::suspend`].
    Suspend {
        /// The node.
        node: NodeId,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::resume`].
    Resume {
        /// The node.
        node: NodeId,
        /// When.
        now: Nanos,
    },
    /// [`TaskTree::retry`].
    Retry {
        /// The node.
        node: NodeId,
        /// When.
        now: Nanos,
    },
}

impl TreeOp {
    /// The time the op carries.
    pub fn now(&self) -> Nanos {
        match self {
            TreeOp::AddNode { now, .. }
            | TreeOp::AddConstraint { now, .. }
            | TreeOp::PlanFirst { now, .. }
            | TreeOp::Start { now, .. }
            | TreeOp::Finish { now, .. }
            | TreeOp::Kill { now, .. }
            | TreeOp::Suspend { now, .. }
            | TreeOp::Resume { now, .. }
            | TreeOp::Retry { now, .. } => *now,
        }
    }
}

impl TaskTree {
    /// Applies one op: the same as calling the method it names. For `AddNode`, the id
    /// in the op must be the one this tree assigns next (else [`TreeError::ReplayMismatch`]
    /// and nothing changes).
    pub fn apply(&mut self, op: &TreeOp) -> Result<Vec<TreeEvent>> {
        match op {
            TreeOp::AddNode { id, spec, now } => {
                if *id != self.next_id() {
                    return Err(TreeError::ReplayMismatch {
                        logged: *id,
                        assigned: self.next_id(),
                    });
                }
                self.add_node(spec.clone(), *now).map(|(_, events)| events)
            }
            TreeOp::AddConstraint { constraint, now } => self.add_constraint(*constraint, *now),
            TreeOp::PlanFirst { node, now } => self.plan_first(*node, *now),
            TreeOp::Start { node, now } => self.start(*node, *now),
            TreeOp::Finish { node, outcome, now } => self.finish(*node, outcome.clone(), *now),
            TreeOp::Kill { node, now } => self.kill(*node, *now),
            TreeOp::Suspend { node, now } => self.suspend(*node, *now),
            TreeOp::Resume { node, now } => self.resume(*node, *now),
            TreeOp::Retry { node, now } => self.retry(*node, *now),
        }
    }

    /// Builds a tree by applying `ops` in order to a fresh one, stopping at the first op
    /// that fails. Returns the tree and every event, in order.
    pub fn replay<'a>(
        ops: impl IntoIterator<Item = &'a TreeOp>,
    ) -> Result<(TaskTree, Vec<TreeEvent>)> {
        let mut tree = TaskTree::new();
        let mut events = Vec::new();
        for op in ops {
            events.extend(tree.apply(op)?);
        }
        Ok((tree, events))
    }
}
