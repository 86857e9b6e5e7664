//! The tree itself: storage and the read-only queries.

use std::collections::{BTreeSet, VecDeque};

use crate::cycle::SearchScratch;
use crate::error::{Result, TreeError};
use crate::event::TreeEvent;
use crate::id::{Nanos, NodeId};
use crate::node::{Edge, Node};
use crate::propagate::Work;
use crate::store::NodeStore;
use crate::view::NodeView;

/// A forest of task trees with their temporal constraints. Pure bookkeeping: no I/O, no
/// clock, no threads; every call returns the events it caused.
#[derive(Debug, Clone)]
pub struct TaskTree {
    pub(crate) nodes: NodeStore,
    pub(crate) roots: BTreeSet<NodeId>,
    /// The number the next node will get.
    pub(crate) next_id: u64,
    pub(crate) last_now: Nanos,
    /// How many live nodes have a non-zero suspend count (0 makes suspension checks free).
    pub(crate) suspended_nodes: usize,
    pub(crate) peak_len: usize,
    pub(crate) events: Vec<TreeEvent>,
    pub(crate) work: VecDeque<Work>,
    pub(crate) search: SearchScratch,
    /// Reused by constraint release.
    pub(crate) scratch_edges: Vec<Edge>,
}

// Central owns the tree from one task and may move it between threads.
const _: fn() = || {
    fn send_and_sync<T: Send + Sync>() {}
    send_and_sync::<TaskTree>();
};

impl Default for TaskTree {
    fn default() -> Self {
        TaskTree::new()
    }
}

impl TaskTree {
    /// An empty tree; the first node will be `n1`.
    pub fn new() -> Self {
        TaskTree {
            nodes: NodeStore::default(),
            scratch_edges: Vec::new(),
            roots: BTreeSet::new(),
            next_id: 1,
            last_now: 0,
            suspended_nodes: 0,
            peak_len: 0,
            events: Vec::new(),
            work: VecDeque::new(),
            search: SearchScratch::default(),
        }
    }

    /// The number of live (not yet retired) nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True when no node is live.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The largest number of live nodes seen at once.
    pub fn peak_len(&self) -> usize {
        self.peak_len
    }

    /// The id the next [`TaskTree::add_node`] will assign.
    pub fn next_id(&self) -> NodeId {
        NodeId(self.next_id)
    }

    /// The latest `now` passed to a mutating call.
    pub fn last_time(&self) -> Nanos {
        self.last_now
    }

    /// The live roots, oldest first.
    pub fn roots(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.roots.iter().copied()
    }

    /// A read-only view of a live node, or `None` if the id is unknown or retired.
    pub fn get(&self, id: NodeId) -> Option<NodeView<'_>> {
        self.nodes
            .get(&id)
            .map(|node| NodeView::new(self, id, node))
    }

    /// True if the node is live.
    pub fn contains(&self, id: NodeId) -> bool {
        self.nodes.contains_key(&id)
    }

    /// True if this tree assigned the id and the node has since been retired.
    pub fn was_retired(&self, id: NodeId) -> bool {
        id.0 >= 1 && id.0 < self.next_id && !self.nodes.contains_key(&id)
    }

    /// The ancestors of a node, nearest first (empty for a root or an unknown id).
    pub fn ancestors(&self, id: NodeId) -> impl Iterator<Item = NodeId> + '_ {
        std::iter::successors(self.nodes.get(&id).and_then(|n| n.parent), move |p| {
            self.nodes.get(p).and_then(|n| n.parent)
        })
    }

    /// The live nodes of the subtree rooted at `id`, in pre-order (parents before
    /// children, children in creation order); empty if `id` is not live.
    pub fn subtree(&self, id: NodeId) -> Vec<NodeId> {
        self.subtree_ids(id)
    }

    /// True if the node may be dispatched to its handler now: it is waiting, not
    /// suspended (nor any ancestor), its parent's handling has started, every constraint
    /// on its handling start holds, and, for a command, every constraint on its own
    /// achievement start and on that of every ancestor whose achievement has not started.
    /// Queries are never ready: the tree does not dispatch them.
    pub fn is_ready(&self, id: NodeId) -> bool {
        self.readiness(id).is_ok()
    }

    /// Why the node is not ready, in words, or `None` if it is ready.
    pub fn why_not_ready(&self, id: NodeId) -> Option<String> {
        self.readiness(id).err().map(|b| b.describe(id))
    }

    pub(crate) fn check_time(&mut self, now: Nanos) -> Result<()> {
        if now < self.last_now {
            return Err(TreeError::TimeWentBackwards {
                now,
                last: self.last_now,
            });
        }
        self.last_now = now;
        Ok(())
    }

    /// Errors for ids that were never assigned.
    pub(crate) fn check_known(&self, id: NodeId) -> Result<()> {
        if id.0 == 0 || id.0 >= self.next_id {
            return Err(TreeError::UnknownNode {
                node: id,
                last: self.next_id.saturating_sub(1),
            });
        }
        Ok(())
    }

    /// The live node, or the error that says why there is none.
    pub(crate) fn live_node(&self, id: NodeId) -> Result<&Node> {
        self.check_known(id)?;
        self.nodes.get(&id).ok_or(TreeError::Retired { node: id })
    }

    pub(crate) fn take_events(&mut self) -> Vec<TreeEvent> {
        std::mem::take(&mut self.events)
    }

    /// Live children of a node, in creation order.
    pub(crate) fn live_children(&self, id: NodeId) -> Vec<NodeId> {
        self.nodes
            .get(&id)
            .map(|n| {
                n.children
                    .iter()
                    .copied()
                    .filter(|c| self.nodes.contains_key(c))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Live nodes of a subtree in pre-order.
    pub(crate) fn subtree_ids(&self, id: NodeId) -> Vec<NodeId> {
        let mut out = Vec::new();
        let mut stack = vec![id];
        while let Some(n) = stack.pop() {
            let Some(node) = self.nodes.get(&n) else {
                continue;
            };
            out.push(n);
            stack.extend(
                node.children
                    .iter()
                    .rev()
                    .copied()
                    .filter(|c| self.nodes.contains_key(c)),
            );
        }
        out
    }

    /// The nearest node, among `id` and its ancestors, with a pending suspension.
    pub(crate) fn suspended_at(&self, id: NodeId) -> Option<NodeId> {
        if self.suspended_nodes == 0 {
            return None;
        }
        let mut cur = Some(id);
        while let Some(c) = cur {
            let node = self.nodes.get(&c)?;
            if node.suspend_count > 0 {
                return Some(c);
            }
            cur = node.parent;
        }
        None
    }
}
