//! Freeing finished subtrees, and an estimate of the memory the tree holds.

use std::mem::size_of;

use crate::event::TreeEvent;
use crate::id::NodeId;
use crate::node::Edge;
use crate::point::Endpoint;
use crate::tree::TaskTree;

/// Below this many children a parent's child list is not worth compacting.
const COMPACT_MIN: usize = 8;

impl TaskTree {
    /// Removes a finished node and whatever is left below it, and reports `Retired`.
    /// Constraints naming retired nodes count as satisfied from now on.
    pub(crate) fn retire(&mut self, id: NodeId) {
        let Some(node) = self.nodes.get(&id) else {
            return;
        };
        let parent = node.parent;
        if node.has_live_children() {
            for r in self.subtree_ids(id) {
                self.remove_node(r);
            }
        } else {
            self.remove_node(id);
        }
        match parent {
            Some(p) => self.note_retired_child(p),
            None => {
                self.roots.remove(&id);
            }
        }
        self.events.push(TreeEvent::Retired(id));
    }

    fn remove_node(&mut self, id: NodeId) {
        let Some(node) = self.nodes.remove(&id) else {
            return;
        };
        if node.suspend_count > 0 {
            self.suspended_nodes = self.suspended_nodes.saturating_sub(1);
        }
        // A finished node has no pending constraints left; stay safe if one slipped by.
        for e in node.gates {
            self.drop_wait(e.other, Endpoint::new(id, e.own), true);
        }
        for e in node.waits_on {
            self.drop_gate(e.other, Endpoint::new(id, e.own));
        }
    }

    /// Counts a retired child and compacts the child list once retired ids dominate it,
    /// so a long-lived parent's list stays proportional to its live children.
    fn note_retired_child(&mut self, parent: NodeId) {
        let Some(pn) = self.nodes.get_mut(&parent) else {
            return;
        };
        pn.retired_children += 1;
        if pn.children.len() < COMPACT_MIN || pn.retired_children as usize * 2 <= pn.children.len()
        {
            return;
        }
        let mut children = std::mem::take(&mut pn.children);
        children.retain(|c| self.nodes.contains_key(c));
        if children.capacity() > 4 * children.len().max(COMPACT_MIN) {
            children.shrink_to(2 * children.len().max(COMPACT_MIN));
        }
        if let Some(pn) = self.nodes.get_mut(&parent) {
            pn.children = children;
            pn.retired_children = 0;
        }
    }

    /// An estimate, in bytes, of the heap memory the tree holds: the node table at its
    /// current capacity, each node's strings and lists, the root set and the scratch space
    /// of the cycle search. Allocator overhead is not counted.
    pub fn estimated_bytes(&self) -> usize {
        let table = self.nodes.table_bytes();
        let per_node: usize = self
            .nodes
            .values()
            .map(|n| {
                n.name.len()
                    + n.handler.len()
                    + n.children.capacity() * size_of::<NodeId>()
                    + (n.waits_on.capacity() + n.gates.capacity()) * size_of::<Edge>()
                    + n.failure_reason.as_ref().map_or(0, |r| r.len())
            })
            .sum();
        // A B-tree set costs roughly its element plus a share of node overhead.
        let roots = self.roots.len() * (size_of::<NodeId>() + 16);
        let queues = self.events.capacity() * size_of::<TreeEvent>()
            + self.work.capacity() * size_of::<crate::propagate::Work>();
        table + per_node + roots + queues + self.search.estimated_bytes()
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::Bench;

    #[test]
    fn a_long_lived_parent_keeps_its_child_list_short() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        for i in 0..1000 {
            let c = b.command(root, &format!("step{i}"), &[]);
            b.run(c);
        }
        let node = b.tree.nodes.get(&root).expect("live");
        assert!(node.children.len() < 16, "{}", node.children.len());
        assert!(
            node.children.capacity() < 64,
            "{}",
            node.children.capacity()
        );
        assert_eq!(b.tree.len(), 1);
        assert!(b.tree.estimated_bytes() > 0);
    }
}
