//! Node storage: fixed-size pages of slots, indexed by id.
//!
//! Ids are sequential, so nodes created together sit together in memory, and a page is
//! freed as soon as its last node retires, which keeps memory bounded by the live part of
//! the plan (plus at most one page per live node, in the worst case). Growing the table
//! never moves nodes: only the small page table is rehashed.

use std::mem::size_of;

use crate::hash::IdMap;
use crate::id::NodeId;
use crate::node::Node;

const PAGE_BITS: u32 = 8;
const PAGE_SLOTS: usize = 1 << PAGE_BITS;
const SLOT_MASK: u64 = PAGE_SLOTS as u64 - 1;

#[derive(Debug, Clone)]
struct Page {
    slots: Box<[Option<Node>]>,
    live: u32,
}

impl Page {
    fn new() -> Self {
        Page {
            slots: (0..PAGE_SLOTS).map(|_| None).collect(),
            live: 0,
        }
    }
}

/// The live nodes, by id.
#[derive(Debug, Clone, Default)]
pub(crate) struct NodeStore {
    pages: IdMap<u64, Page>,
    len: usize,
}

fn split(id: NodeId) -> (u64, usize) {
    (id.0 >> PAGE_BITS, (id.0 & SLOT_MASK) as usize)
}

impl NodeStore {
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub(crate) fn get(&self, id: &NodeId) -> Option<&Node> {
        let (page, slot) = split(*id);
        self.pages.get(&page)?.slots.get(slot)?.as_ref()
    }

    pub(crate) fn get_mut(&mut self, id: &NodeId) -> Option<&mut Node> {
        let (page, slot) = split(*id);
        self.pages.get_mut(&page)?.slots.get_mut(slot)?.as_mut()
    }

    pub(crate) fn contains_key(&self, id: &NodeId) -> bool {
        self.get(id).is_some()
    }

    pub(crate) fn insert(&mut self, id: NodeId, node: Node) {
        let (page, slot) = split(id);
        let page = self.pages.entry(page).or_insert_with(Page::new);
        if let Some(cell) = page.slots.get_mut(slot) {
            if cell.is_none() {
                page.live += 1;
                self.len += 1;
            }
            *cell = Some(node);
        }
    }

    pub(crate) fn remove(&mut self, id: &NodeId) -> Option<Node> {
        let (index, slot) = split(*id);
        let page = self.pages.get_mut(&index)?;
        let node = page.slots.get_mut(slot)?.take()?;
        page.live -= 1;
        self.len -= 1;
        if page.live == 0 {
            self.pages.remove(&index);
        }
        Some(node)
    }

    pub(crate) fn values(&self) -> impl Iterator<Item = &Node> + '_ {
        self.pages
            .values()
            .flat_map(|p| p.slots.iter().filter_map(Option::as_ref))
    }

    /// Bytes held by the pages and the page table, not counting what nodes point to.
    pub(crate) fn table_bytes(&self) -> usize {
        self.pages.len() * PAGE_SLOTS * size_of::<Option<Node>>()
            + self.pages.capacity() * (size_of::<(u64, Page)>() + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::NodeKind;

    fn node() -> Node {
        Node::new(NodeKind::Goal, "g".into(), "h".into(), None, 0)
    }

    #[test]
    fn pages_come_and_go_with_their_nodes() {
        let mut store = NodeStore::default();
        for i in 1..=600 {
            store.insert(NodeId(i), node());
        }
        assert_eq!(store.len(), 600);
        assert_eq!(store.pages.len(), 3);
        for i in 1..=599 {
            assert!(store.remove(&NodeId(i)).is_some());
        }
        assert!(store.remove(&NodeId(1)).is_none());
        assert_eq!(store.len(), 1);
        assert_eq!(store.pages.len(), 1);
        assert!(store.contains_key(&NodeId(600)));
        assert_eq!(store.values().count(), 1);
    }
}
