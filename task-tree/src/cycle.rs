//! Cycle detection over time points.
//!
//! The points of live nodes that have not occurred yet form a graph whose edges are the
//! pending constraints plus the tree's implicit orderings:
//!
//! - `start(handle n) -> end(handle n)`, `start(handle n) -> start(achieve n)` (goals),
//!   `end(handle n) -> end(achieve n)`, `start(achieve n) -> end(achieve n)`;
//! - `start(handle parent) -> start(handle child)` (a child is dispatched only after its
//!   parent's handler has started), `start(achieve parent) -> start(achieve child)` (a
//!   child's achievement starts its ancestors'), `end(achieve child) -> end(achieve
//!   parent)`.
//!
//! A command's handling start and achievement start are one point. Queries are left out.
//! Points that occurred, and points of finished or retired nodes, are left out too: no
//! edge runs from a point that has not occurred to one that has, so they cannot lie on a
//! cycle. A new constraint `before <= after` is refused when `after` already reaches
//! `before`. The search runs from both ends at once and always grows the smaller
//! frontier, so it costs about twice the smaller of the two reachable sets: adding a
//! constraint between a new node and an old one stays cheap however large the tree.

use std::collections::VecDeque;
use std::mem::size_of;

use crate::hash::IdMap;
use crate::point::{Endpoint, Point};
use crate::state::NodeKind;
use crate::tree::TaskTree;

/// Below this many entries a visited set is a plain list: most searches touch a handful
/// of points, and scanning a few words beats hashing them.
const LINEAR_LIMIT: usize = 32;

/// Visited points of one side of the search: point key -> the key it was reached from.
#[derive(Debug, Default, Clone)]
struct Visited {
    list: Vec<(u64, u64)>,
    map: IdMap<u64, u64>,
}

impl Visited {
    fn get(&self, key: u64) -> Option<u64> {
        if self.map.is_empty() {
            self.list.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
        } else {
            self.map.get(&key).copied()
        }
    }

    fn contains(&self, key: u64) -> bool {
        self.get(key).is_some()
    }

    fn insert(&mut self, key: u64, from: u64) {
        if self.map.is_empty() && self.list.len() < LINEAR_LIMIT {
            self.list.push((key, from));
            return;
        }
        if self.map.is_empty() {
            self.map.extend(self.list.drain(..));
        }
        self.map.insert(key, from);
    }

    fn len(&self) -> usize {
        self.list.len() + self.map.len()
    }

    fn capacity(&self) -> usize {
        self.list.capacity() + self.map.capacity()
    }

    fn clear(&mut self) {
        self.list.clear();
        self.map.clear();
    }
}

/// Scratch sets and queues reused across searches.
#[derive(Debug, Default, Clone)]
pub(crate) struct SearchScratch {
    /// Point key -> the point it was reached from (itself for the start).
    forward: Visited,
    /// Point key -> the point it leads to (itself for the goal).
    backward: Visited,
    forward_queue: VecDeque<u64>,
    backward_queue: VecDeque<u64>,
    buffer: Vec<u64>,
}

/// Above this many entries the scratch is dropped rather than cleared, so one huge search
/// does not make every later clear expensive.
const SCRATCH_KEEP: usize = 4096;

impl SearchScratch {
    fn reset(&mut self) {
        if self.forward.capacity() > SCRATCH_KEEP || self.backward.capacity() > SCRATCH_KEEP {
            *self = SearchScratch::default();
        } else {
            self.forward.clear();
            self.backward.clear();
            self.forward_queue.clear();
            self.backward_queue.clear();
            self.buffer.clear();
        }
    }

    pub(crate) fn estimated_bytes(&self) -> usize {
        (self.forward.capacity() + self.backward.capacity()) * (2 * size_of::<u64>() + 1)
            + (self.forward_queue.capacity()
                + self.backward_queue.capacity()
                + self.buffer.capacity())
                * size_of::<u64>()
    }

    /// The path from the forward start to the backward goal through `meet`.
    fn path_through(&self, meet: u64) -> Vec<Endpoint> {
        let limit = self.forward.len() + self.backward.len() + 1;
        let mut path = vec![meet];
        let mut k = meet;
        while let Some(prev) = self.forward.get(k) {
            if prev == k || path.len() > limit {
                break;
            }
            path.push(prev);
            k = prev;
        }
        path.reverse();
        let mut k = meet;
        while let Some(next) = self.backward.get(k) {
            if next == k || path.len() > 2 * limit {
                break;
            }
            path.push(next);
            k = next;
        }
        path.into_iter().map(Endpoint::from_key).collect()
    }
}

impl TaskTree {
    /// The one point a command's achievement start shares with its handling start.
    pub(crate) fn canonical(&self, ep: Endpoint) -> Endpoint {
        match self.nodes.get(&ep.node) {
            Some(node) if node.kind == NodeKind::Command && ep.point == Point::AchievementStart => {
                Endpoint::new(ep.node, Point::HandlingStart)
            }
            _ => ep,
        }
    }

    fn push_point(&self, out: &mut Vec<u64>, ep: Endpoint) {
        let Some(node) = self.nodes.get(&ep.node) else {
            return;
        };
        let point = match (node.kind, ep.point) {
            (NodeKind::Query, _) => return,
            (NodeKind::Command, Point::AchievementStart) => Point::HandlingStart,
            (_, p) => p,
        };
        if !node.is_finished() && !node.occurred(point) {
            out.push(Endpoint::new(ep.node, point).key());
        }
    }

    /// The points that must come after `ep` (which is canonical).
    fn successors(&self, ep: Endpoint, out: &mut Vec<u64>) {
        let Some(node) = self.nodes.get(&ep.node) else {
            return;
        };
        let id = ep.node;
        let merged = node.kind == NodeKind::Command && ep.point == Point::HandlingStart;
        for point in Point::ALL {
            if point != ep.point && !(merged && point == Point::AchievementStart) {
                continue;
            }
            match point {
                Point::HandlingStart => {
                    self.push_point(out, id.handling_end());
                    if node.kind == NodeKind::Goal {
                        self.push_point(out, id.achievement_start());
                    }
                    for c in &node.children {
                        self.push_point(out, c.handling_start());
                    }
                }
                Point::HandlingEnd => self.push_point(out, id.achievement_end()),
                Point::AchievementStart => {
                    self.push_point(out, id.achievement_end());
                    for c in &node.children {
                        self.push_point(out, c.achievement_start());
                    }
                }
                Point::AchievementEnd => {
                    if let Some(p) = node.parent {
                        self.push_point(out, p.achievement_end());
                    }
                }
            }
            for e in node.gates.iter().filter(|e| e.own == point) {
                self.push_point(out, e.other);
            }
        }
    }

    /// The points that must come before `ep` (which is canonical).
    fn predecessors(&self, ep: Endpoint, out: &mut Vec<u64>) {
        let Some(node) = self.nodes.get(&ep.node) else {
            return;
        };
        let id = ep.node;
        let merged = node.kind == NodeKind::Command && ep.point == Point::HandlingStart;
        for point in Point::ALL {
            if point != ep.point && !(merged && point == Point::AchievementStart) {
                continue;
            }
            match point {
                Point::HandlingStart => {
                    if let Some(p) = node.parent {
                        self.push_point(out, p.handling_start());
                    }
                }
                Point::HandlingEnd => self.push_point(out, id.handling_start()),
                Point::AchievementStart => {
                    if node.kind == NodeKind::Goal {
                        self.push_point(out, id.handling_start());
                    }
                    if let Some(p) = node.parent {
                        self.push_point(out, p.achievement_start());
                    }
                }
                Point::AchievementEnd => {
                    self.push_point(out, id.handling_end());
                    self.push_point(out, id.achievement_start());
                    for c in &node.children {
                        self.push_point(out, c.achievement_end());
                    }
                }
            }
            for e in node.waits_on.iter().filter(|e| e.own == point) {
                self.push_point(out, e.other);
            }
        }
    }

    /// A chain of orderings from `from` to `to` (both canonical, in the graph), if any.
    pub(crate) fn find_path(&mut self, from: Endpoint, to: Endpoint) -> Option<Vec<Endpoint>> {
        let mut scratch = std::mem::take(&mut self.search);
        let found = self.search_both_ways(&mut scratch, from, to);
        scratch.reset();
        self.search = scratch;
        found
    }

    fn search_both_ways(
        &self,
        s: &mut SearchScratch,
        from: Endpoint,
        to: Endpoint,
    ) -> Option<Vec<Endpoint>> {
        let (a, b) = (from.key(), to.key());
        if a == b {
            return Some(vec![from]);
        }
        s.forward.insert(a, a);
        s.backward.insert(b, b);
        s.forward_queue.push_back(a);
        s.backward_queue.push_back(b);
        let mut buffer = std::mem::take(&mut s.buffer);
        let found = loop {
            if s.forward_queue.is_empty() || s.backward_queue.is_empty() {
                break None;
            }
            buffer.clear();
            if s.forward_queue.len() <= s.backward_queue.len() {
                let Some(k) = s.forward_queue.pop_front() else {
                    break None;
                };
                self.successors(Endpoint::from_key(k), &mut buffer);
                let mut meet = None;
                for &n in &buffer {
                    if s.forward.contains(n) {
                        continue;
                    }
                    s.forward.insert(n, k);
                    if s.backward.contains(n) {
                        meet = Some(n);
                        break;
                    }
                    s.forward_queue.push_back(n);
                }
                if let Some(m) = meet {
                    break Some(s.path_through(m));
                }
            } else {
                let Some(k) = s.backward_queue.pop_front() else {
                    break None;
                };
                self.predecessors(Endpoint::from_key(k), &mut buffer);
                let mut meet = None;
                for &n in &buffer {
                    if s.backward.contains(n) {
                        continue;
                    }
                    s.backward.insert(n, k);
                    if s.forward.contains(n) {
                        meet = Some(n);
                        break;
                    }
                    s.backward_queue.push_back(n);
                }
                if let Some(m) = meet {
                    break Some(s.path_through(m));
                }
            }
        };
        s.buffer = buffer;
        found
    }
}
