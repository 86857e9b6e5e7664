//! Everything a caller can get wrong, with what to do about it.

use crate::constraint::Constraint;
use crate::id::{Nanos, NodeId};
use crate::state::NodeState;

/// The result type of this crate.
pub type Result<T, E = TreeError> = std::result::Result<T, E>;

/// Why a call on the tree was refused. A refused call changes nothing (except that its
/// `now` still counts as the latest time seen).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TreeError {
    /// The id was never assigned by this tree.
    #[error("no node {node} in this task tree (ids assigned so far: n1 to n{last}); check the id")]
    UnknownNode {
        /// The id given.
        node: NodeId,
        /// The highest id assigned so far (0 if none).
        last: u64,
    },
    /// The node finished and left the tree.
    #[error(
        "{node} has already finished (achieved, failed or killed) and was retired from the tree; nothing more can happen to it"
    )]
    Retired {
        /// The id given.
        node: NodeId,
    },
    /// The operation does not apply to the node in its current state.
    #[error("cannot {op} {node}: it is {state}; {hint}")]
    WrongState {
        /// The node.
        node: NodeId,
        /// The operation refused.
        op: &'static str,
        /// The node's state.
        state: NodeState,
        /// What would be allowed.
        hint: &'static str,
    },
    /// `start` of a node that is not ready.
    #[error("cannot start {node}: {reason}; dispatch it after its Ready event")]
    NotReady {
        /// The node.
        node: NodeId,
        /// What holds it back, e.g. the constraint that does not hold yet.
        reason: String,
    },
    /// The constraint would make the plan cyclic (counting the tree's implicit orderings).
    #[error(
        "constraint {constraint} would close the cycle {cycle}; drop or reverse a constraint on that cycle"
    )]
    Cycle {
        /// The refused constraint.
        constraint: Constraint,
        /// The points on the cycle, `a -> b` meaning `a` must come before `b`.
        cycle: String,
    },
    /// The constraint can never hold, because its `after` point has already passed.
    #[error("constraint {constraint} can never hold: {reason}")]
    Unsatisfiable {
        /// The refused constraint.
        constraint: Constraint,
        /// Why.
        reason: String,
    },
    /// A constraint names a query node.
    #[error(
        "constraint {constraint} names {node}, a query: queries are recorded as leaves and never scheduled by the tree, so they cannot be constrained"
    )]
    QueryConstrained {
        /// The refused constraint.
        constraint: Constraint,
        /// The query.
        node: NodeId,
    },
    /// A node spec that cannot be added.
    #[error("cannot add node {name:?}: {reason}")]
    BadSpec {
        /// The message name of the spec.
        name: String,
        /// What is wrong and what to do.
        reason: String,
    },
    /// `resume` of a node that is not suspended.
    #[error("{node} is not suspended; resume only what was suspended (once per suspend)")]
    NotSuspended {
        /// The node.
        node: NodeId,
    },
    /// A call carried an earlier time than a previous call.
    #[error(
        "time went backwards: {now} ns is earlier than the last time given, {last} ns; pass times from a monotonic clock"
    )]
    TimeWentBackwards {
        /// The time given.
        now: Nanos,
        /// The latest time seen before.
        last: Nanos,
    },
    /// Replaying an `AddNode` whose logged id differs from the one the tree would assign.
    #[error(
        "replay mismatch: the log says this node got id {logged}, but this tree would assign {assigned}; replay the whole log, from its start, into a fresh tree"
    )]
    ReplayMismatch {
        /// The id in the log.
        logged: NodeId,
        /// The id this tree would assign.
        assigned: NodeId,
    },
    /// Every u64 id has been used.
    #[error("node ids are exhausted; start a new tree")]
    IdsExhausted,
}
