//! Priority-queue entries ordered smallest key first, with total order on `f64`.

use std::cmp::Ordering;

/// A two-part key compared lexicographically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Key(pub(crate) f64, pub(crate) f64);

impl Key {
    pub(crate) fn cmp_key(&self, other: &Key) -> Ordering {
        self.0
            .total_cmp(&other.0)
            .then_with(|| self.1.total_cmp(&other.1))
    }

    pub(crate) fn lt(&self, other: &Key) -> bool {
        self.cmp_key(other) == Ordering::Less
    }
}

/// A heap entry; `BinaryHeap` is a max-heap, so the order is reversed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    pub(crate) key: Key,
    pub(crate) vertex: usize,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .key
            .cmp_key(&self.key)
            .then_with(|| other.vertex.cmp(&self.vertex))
    }
}
