//! A tree's whole state as data: [`TaskTree`] implements `Serialize` and `Deserialize`, so a
//! process that keeps task trees (central) can save them and carry on with them after a
//! restart.
//!
//! What is saved is every live node (its kind, names, parent, children, state, the times of
//! its points, the constraints still pending on it and the suspensions and failures it holds),
//! the roots, the next id and the latest time seen. Scratch space (event buffers, the cycle
//! search's sets) is not: it is empty between calls. A restored tree assigns the same ids,
//! gives the same events and renders the same text as the tree it was saved from, for every
//! call that follows.
//!
//! Restoring checks what it reads: ids within the saved next id, no node twice, parents,
//! children and constraint ends that name saved nodes (or retired ones), roots that are
//! parentless nodes. A save that breaks these is refused with the reason.

use std::collections::{BTreeSet, HashSet};

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::id::{Nanos, NodeId};
use crate::node::Node;
use crate::store::NodeStore;
use crate::tree::TaskTree;

/// The saved form, borrowed for writing.
#[derive(Serialize)]
struct SavedRef<'a> {
    nodes: Vec<(NodeId, &'a Node)>,
    roots: &'a BTreeSet<NodeId>,
    next_id: u64,
    last_now: Nanos,
    peak_len: usize,
}

/// The saved form, owned for reading.
#[derive(Deserialize)]
struct Saved {
    nodes: Vec<(NodeId, Node)>,
    roots: BTreeSet<NodeId>,
    next_id: u64,
    last_now: Nanos,
    peak_len: usize,
}

impl Serialize for TaskTree {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut nodes: Vec<(NodeId, &Node)> = self
            .roots
            .iter()
            .flat_map(|r| self.subtree_ids(*r))
            .filter_map(|id| self.nodes.get(&id).map(|n| (id, n)))
            .collect();
        // Every live node hangs under a live root; sort so that the form does not depend on
        // the walk.
        nodes.sort_by_key(|(id, _)| *id);
        SavedRef {
            nodes,
            roots: &self.roots,
            next_id: self.next_id,
            last_now: self.last_now,
            peak_len: self.peak_len,
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for TaskTree {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let saved = Saved::deserialize(d)?;
        TaskTree::restore(saved).map_err(D::Error::custom)
    }
}

impl TaskTree {
    fn restore(saved: Saved) -> Result<TaskTree, String> {
        let known = |id: NodeId| id.0 >= 1 && id.0 < saved.next_id;
        let mut ids = HashSet::with_capacity(saved.nodes.len());
        for (id, _) in &saved.nodes {
            if !known(*id) {
                return Err(format!(
                    "saved task tree: node {id} is outside the ids it assigned (next {})",
                    saved.next_id
                ));
            }
            if !ids.insert(*id) {
                return Err(format!("saved task tree: node {id} appears twice"));
            }
        }
        for (id, node) in &saved.nodes {
            if let Some(p) = node.parent
                && !ids.contains(&p)
            {
                return Err(format!(
                    "saved task tree: node {id} has parent {p}, which is not saved"
                ));
            }
            let ends = node
                .waits_on
                .iter()
                .chain(&node.gates)
                .map(|e| e.other.node);
            if let Some(bad) = node
                .children
                .iter()
                .copied()
                .chain(ends)
                .find(|n| !known(*n))
            {
                return Err(format!(
                    "saved task tree: node {id} names node {bad}, which was never assigned"
                ));
            }
        }
        for root in &saved.roots {
            let parentless = saved
                .nodes
                .iter()
                .any(|(id, n)| id == root && n.parent.is_none());
            if !parentless {
                return Err(format!(
                    "saved task tree: root {root} is not a saved node without a parent"
                ));
            }
        }
        let mut tree = TaskTree::new();
        tree.next_id = saved.next_id;
        tree.last_now = saved.last_now;
        tree.roots = saved.roots;
        let mut nodes = NodeStore::default();
        for (id, node) in saved.nodes {
            if node.suspend_count > 0 {
                tree.suspended_nodes += 1;
            }
            nodes.insert(id, node);
        }
        tree.nodes = nodes;
        tree.peak_len = saved.peak_len.max(tree.nodes.len());
        Ok(tree)
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::Bench;
    use crate::{NewConstraint, NodeSpec, Outcome, TaskTree, TreeEvent};

    fn roundtrip(tree: &TaskTree) -> TaskTree {
        let json = serde_json::to_string(tree).expect("saves");
        serde_json::from_str(&json).expect("restores")
    }

    #[test]
    fn a_restored_tree_goes_on_as_the_saved_one() {
        let mut b = Bench::new();
        let walk = b.goal(None, "walk");
        b.start(walk);
        let leg = b.command(walk, "legMove", &[]);
        let body = b.command(
            walk,
            "bodyMove",
            &[NewConstraint::sequential_achievement_after(leg)],
        );
        b.tree.suspend(walk, 5).unwrap();
        let mut restored = roundtrip(&b.tree);
        assert_eq!(restored.render_text(), b.tree.render_text());
        assert_eq!(restored.next_id(), b.tree.next_id());
        for tree in [&mut b.tree, &mut restored] {
            assert_eq!(
                tree.resume(walk, 6).unwrap(),
                vec![TreeEvent::Ready(leg)],
                "the suspension was kept"
            );
            tree.start(leg, 7).unwrap();
            let events = tree.finish(leg, Outcome::Success, 8).unwrap();
            assert!(events.contains(&TreeEvent::Ready(body)), "{events:?}");
            let (next, _) = tree
                .add_node(NodeSpec::command("scan", "ism").under(walk), 9)
                .unwrap();
            assert_eq!(next.0, 4);
        }
        assert_eq!(restored.render_text(), b.tree.render_text());
    }

    #[test]
    fn a_save_naming_unknown_nodes_is_refused() {
        let mut tree = TaskTree::new();
        tree.add_node(NodeSpec::goal("walk", "gait"), 0).unwrap();
        let json = serde_json::to_string(&tree).unwrap();
        let broken = json.replace("\"next_id\":2", "\"next_id\":1");
        let err = serde_json::from_str::<TaskTree>(&broken).expect_err("refused");
        assert!(err.to_string().contains("outside the ids"), "{err}");
    }
}
