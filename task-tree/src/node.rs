//! The record the tree keeps for each live node.

use serde::{Deserialize, Serialize};

use crate::id::Nanos;
use crate::id::NodeId;
use crate::point::{Endpoint, Point};
use crate::state::{NodeKind, NodeState};

/// The time stored for a point that has not occurred.
pub(crate) const NOT_YET: Nanos = Nanos::MAX;

/// One end of a pending constraint, stored on a node.
///
/// In a node's `waits_on` list, `own` is the node's point that waits and `other` the point
/// it waits for (`other <= own`). In its `gates` list, `own` is the node's point that must
/// come first and `other` the point that waits for it (`own <= other`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) struct Edge {
    pub(crate) own: Point,
    pub(crate) other: Endpoint,
}

/// A live node.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct Node {
    pub(crate) kind: NodeKind,
    pub(crate) name: Box<str>,
    pub(crate) handler: Box<str>,
    pub(crate) parent: Option<NodeId>,
    /// Children in creation order (ascending ids). May still hold ids of retired
    /// children; they are compacted away once they are the majority.
    pub(crate) children: Vec<NodeId>,
    /// How many ids in `children` are retired.
    pub(crate) retired_children: u32,
    /// Children that are not finished yet (achieved, killed, or failed for good).
    pub(crate) unfinished_children: u32,
    pub(crate) state: NodeState,
    /// When each point occurred, indexed by [`Point::index`]; [`NOT_YET`] if it has not.
    pub(crate) times: [Nanos; 4],
    pub(crate) created_at: Nanos,
    /// When the node reached a terminal state (achieved, failed or killed).
    pub(crate) ended_at: Option<Nanos>,
    /// Pending constraints per point that still hold it back.
    pub(crate) blockers: [u32; 4],
    /// Pending constraints on this node's points.
    pub(crate) waits_on: Vec<Edge>,
    /// Pending constraints that wait for this node's points.
    pub(crate) gates: Vec<Edge>,
    /// How many `suspend` calls on this node are not yet matched by a `resume`.
    pub(crate) suspend_count: u32,
    /// The handler reported success (its handling end may still be held back).
    pub(crate) handler_done: bool,
    /// The handler reported success but a constraint holds back its handling end.
    pub(crate) finish_pending: bool,
    /// The node failed while suspended: the failure waits for the exception handling.
    pub(crate) failure_held: bool,
    pub(crate) failure_reason: Option<Box<str>>,
    /// Plan-first is set on this node.
    pub(crate) plan_first: bool,
    /// A `Ready` event was emitted and is still valid.
    pub(crate) announced: bool,
}

impl Node {
    pub(crate) fn new(
        kind: NodeKind,
        name: String,
        handler: String,
        parent: Option<NodeId>,
        now: Nanos,
    ) -> Self {
        Node {
            kind,
            name: name.into_boxed_str(),
            handler: handler.into_boxed_str(),
            parent,
            children: Vec::new(),
            retired_children: 0,
            unfinished_children: 0,
            state: NodeState::Waiting,
            times: [NOT_YET; 4],
            created_at: now,
            ended_at: None,
            blockers: [0; 4],
            waits_on: Vec::new(),
            gates: Vec::new(),
            suspend_count: 0,
            handler_done: false,
            finish_pending: false,
            failure_held: false,
            failure_reason: None,
            plan_first: false,
            announced: false,
        }
    }

    pub(crate) fn time(&self, point: Point) -> Option<Nanos> {
        let t = self.times[point.index()];
        (t != NOT_YET).then_some(t)
    }

    pub(crate) fn occurred(&self, point: Point) -> bool {
        self.times[point.index()] != NOT_YET
    }

    /// True if the node has children that are not retired.
    pub(crate) fn has_live_children(&self) -> bool {
        self.children.len() > self.retired_children as usize
    }

    /// Achieved, killed, or failed with the failure no longer held: nothing more will
    /// happen to it, and every point of it counts as occurred.
    pub(crate) fn is_finished(&self) -> bool {
        match self.state {
            NodeState::Achieved | NodeState::Killed => true,
            NodeState::Failed => !self.failure_held,
            _ => false,
        }
    }

    /// The first pending constraint on `point`, as `(before, after)`.
    pub(crate) fn first_wait(&self, id: NodeId, point: Point) -> Option<(Endpoint, Endpoint)> {
        self.waits_on
            .iter()
            .find(|e| e.own == point)
            .map(|e| (e.other, Endpoint::new(id, point)))
    }
}
