//! A read-only window on one live node.

use crate::constraint::Constraint;
use crate::id::{Nanos, NodeId};
use crate::node::Node;
use crate::point::{Endpoint, Point};
use crate::state::{NodeKind, NodeState};
use crate::tree::TaskTree;

/// A live node as the tree sees it. Obtained from [`TaskTree::get`].
#[derive(Debug, Clone, Copy)]
pub struct NodeView<'a> {
    tree: &'a TaskTree,
    id: NodeId,
    node: &'a Node,
}

impl<'a> NodeView<'a> {
    pub(crate) fn new(tree: &'a TaskTree, id: NodeId, node: &'a Node) -> Self {
        NodeView { tree, id, node }
    }

    /// The node's id.
    pub fn id(&self) -> NodeId {
        self.id
    }

    /// Goal, command or query.
    pub fn kind(&self) -> NodeKind {
        self.node.kind
    }

    /// The message name.
    pub fn name(&self) -> &'a str {
        &self.node.name
    }

    /// The module that handles it.
    pub fn handler(&self) -> &'a str {
        &self.node.handler
    }

    /// The parent, or `None` for a root.
    pub fn parent(&self) -> Option<NodeId> {
        self.node.parent
    }

    /// The live children, in creation order (finished children are retired at once).
    pub fn children(&self) -> impl Iterator<Item = NodeId> + 'a {
        let tree = self.tree;
        self.node
            .children
            .iter()
            .copied()
            .filter(move |c| tree.contains(*c))
    }

    /// The node's state.
    pub fn state(&self) -> NodeState {
        self.node.state
    }

    /// When the point occurred, if it has.
    pub fn time(&self, point: Point) -> Option<Nanos> {
        self.node.time(point)
    }

    /// When the node was added.
    pub fn created_at(&self) -> Nanos {
        self.node.created_at
    }

    /// When it reached a terminal state, if it has.
    pub fn ended_at(&self) -> Option<Nanos> {
        self.node.ended_at
    }

    /// True if the node itself has a pending suspension.
    pub fn is_suspended(&self) -> bool {
        self.node.suspend_count > 0
    }

    /// True if the node is ready to dispatch (see [`TaskTree::is_ready`]).
    pub fn is_ready(&self) -> bool {
        self.tree.is_ready(self.id)
    }

    /// True if plan-first is set on the node.
    pub fn plan_first(&self) -> bool {
        self.node.plan_first
    }

    /// True if its handler reported success but a constraint holds back its handling end.
    pub fn finish_pending(&self) -> bool {
        self.node.finish_pending
    }

    /// True if it failed under a suspension and the failure waits for the exception
    /// handling (retry, kill, or resume to let it propagate).
    pub fn failure_held(&self) -> bool {
        self.node.failure_held
    }

    /// Why it failed, if it did.
    pub fn failure_reason(&self) -> Option<&'a str> {
        self.node.failure_reason.as_deref()
    }

    /// The pending constraints that hold back one of this node's points, in the order
    /// they were added.
    pub fn waiting_on(&self) -> impl Iterator<Item = Constraint> + 'a {
        let id = self.id;
        self.node
            .waits_on
            .iter()
            .map(move |e| Constraint::new(e.other, Endpoint::new(id, e.own)))
    }

    /// The pending constraints that wait for one of this node's points.
    pub fn gating(&self) -> impl Iterator<Item = Constraint> + 'a {
        let id = self.id;
        self.node
            .gates
            .iter()
            .map(move |e| Constraint::new(Endpoint::new(id, e.own), e.other))
    }
}
