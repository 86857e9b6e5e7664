//! The engine: points occur, constraints are released, nodes advance.
//!
//! Every mutating call does its own change, queues work, and then runs the queue to a
//! fixed point. The queue is first-in first-out, which makes the order of events
//! deterministic (and deep trees cannot overflow the stack).

use crate::event::TreeEvent;
use crate::id::{Nanos, NodeId};
use crate::point::{Endpoint, Point};
use crate::state::{NodeKind, NodeState};
use crate::tree::TaskTree;

/// A unit of pending work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Work {
    /// Re-examine a node: readiness if waiting, completion otherwise.
    Advance(NodeId),
    /// The last pending constraint on this point was satisfied.
    Unblocked(Endpoint),
}

impl TaskTree {
    /// Runs the work queue until nothing is left.
    pub(crate) fn run(&mut self, now: Nanos) {
        while let Some(work) = self.work.pop_front() {
            match work {
                Work::Advance(id) => self.advance(id, now),
                Work::Unblocked(ep) => self.on_unblocked(ep),
            }
        }
    }

    fn on_unblocked(&mut self, ep: Endpoint) {
        let Some(node) = self.nodes.get(&ep.node) else {
            return;
        };
        if ep.point == Point::AchievementStart && node.kind == NodeKind::Goal {
            // A goal's achievement gate also gates every command below it. Scan even if
            // the achievement has started since the gate opened (in this same call):
            // commands below it have not been looked at yet.
            let ids = self.subtree_ids(ep.node);
            self.work.extend(ids.into_iter().map(Work::Advance));
        } else {
            self.work.push_back(Work::Advance(ep.node));
        }
    }

    pub(crate) fn advance(&mut self, id: NodeId, now: Nanos) {
        let Some(node) = self.nodes.get(&id) else {
            return;
        };
        match node.state {
            NodeState::Waiting => self.refresh_ready(id),
            NodeState::Handling | NodeState::Handled | NodeState::Achieving => {
                self.progress(id, now)
            }
            _ => {}
        }
    }

    /// Emits `Ready` if the node has just become ready.
    pub(crate) fn refresh_ready(&mut self, id: NodeId) {
        let ready = self.readiness(id).is_ok();
        if let Some(node) = self.nodes.get_mut(&id) {
            if ready && !node.announced {
                node.announced = true;
                self.events.push(TreeEvent::Ready(id));
            } else if !ready {
                node.announced = false;
            }
        }
    }

    /// Moves a started node on as far as its constraints allow: handling end, then
    /// achievement start (goals), then achievement end.
    fn progress(&mut self, id: NodeId, now: Nanos) {
        let Some(node) = self.nodes.get_mut(&id) else {
            return;
        };
        if node.kind == NodeKind::Query {
            return;
        }
        if node.state == NodeState::Handling
            && node.finish_pending
            && node.blockers[Point::HandlingEnd.index()] == 0
        {
            node.finish_pending = false;
            node.state = if node.occurred(Point::AchievementStart) {
                NodeState::Achieving
            } else {
                NodeState::Handled
            };
            self.occur(id, Point::HandlingEnd, now);
        }

        let Some(node) = self.nodes.get(&id) else {
            return;
        };
        if node.kind == NodeKind::Goal
            && node.handler_done
            && !node.occurred(Point::AchievementStart)
            && !node.is_finished()
            && self.achievement_gate(id).is_ok()
        {
            self.start_achievement(id, now);
        }

        let Some(node) = self.nodes.get(&id) else {
            return;
        };
        if matches!(node.state, NodeState::Handled | NodeState::Achieving)
            && node.occurred(Point::HandlingEnd)
            && node.occurred(Point::AchievementStart)
            && node.unfinished_children == 0
            && node.blockers[Point::AchievementEnd.index()] == 0
        {
            self.achieve(id, now);
        }
    }

    /// Starts the achievement of `id` and of every ancestor whose achievement has not
    /// started yet, outermost first. The caller has checked the gate.
    pub(crate) fn start_achievement(&mut self, id: NodeId, now: Nanos) {
        let mut chain = Vec::new();
        let mut cur = Some(id);
        while let Some(c) = cur {
            let Some(node) = self.nodes.get(&c) else {
                break;
            };
            if node.occurred(Point::AchievementStart) || node.kind == NodeKind::Query {
                break;
            }
            chain.push(c);
            cur = node.parent;
        }
        for c in chain.into_iter().rev() {
            if let Some(node) = self.nodes.get_mut(&c)
                && node.state == NodeState::Handled
            {
                node.state = NodeState::Achieving;
            }
            self.occur(c, Point::AchievementStart, now);
        }
    }

    fn achieve(&mut self, id: NodeId, now: Nanos) {
        if let Some(node) = self.nodes.get_mut(&id) {
            node.state = NodeState::Achieved;
            node.ended_at = Some(now);
        }
        self.occur(id, Point::AchievementEnd, now);
        self.settle_finished(id);
    }

    /// Records that a point occurred, reports it, and releases the constraints that
    /// waited for it.
    pub(crate) fn occur(&mut self, id: NodeId, point: Point, now: Nanos) {
        let Some(node) = self.nodes.get_mut(&id) else {
            return;
        };
        node.times[point.index()] = now;
        self.events.push(match point {
            Point::HandlingStart => TreeEvent::HandlingStarted(id),
            Point::HandlingEnd => TreeEvent::HandlingEnded(id),
            Point::AchievementStart => TreeEvent::AchievementStarted(id),
            Point::AchievementEnd => TreeEvent::Achieved(id),
        });
        self.release_gates(id, Some(point));
    }

    /// Satisfies the pending constraints that wait for `point` of `id` (all of its points
    /// when `None`).
    pub(crate) fn release_gates(&mut self, id: NodeId, point: Option<Point>) {
        let Some(node) = self.nodes.get_mut(&id) else {
            return;
        };
        if node.gates.is_empty() {
            return;
        }
        let mut released = std::mem::take(&mut self.scratch_edges);
        released.clear();
        node.gates.retain(|e| {
            if point.is_none_or(|p| e.own == p) {
                released.push(*e);
                false
            } else {
                true
            }
        });
        for e in released.drain(..) {
            self.drop_wait(e.other, Endpoint::new(id, e.own), true);
        }
        self.scratch_edges = released;
    }

    /// Removes the pending constraint `source <= target` from `target`'s node; when that
    /// frees the point and `notify` is set, queues the news.
    pub(crate) fn drop_wait(&mut self, target: Endpoint, source: Endpoint, notify: bool) {
        let Some(node) = self.nodes.get_mut(&target.node) else {
            return;
        };
        let Some(pos) = node
            .waits_on
            .iter()
            .position(|e| e.own == target.point && e.other == source)
        else {
            return;
        };
        node.waits_on.remove(pos);
        let count = &mut node.blockers[target.point.index()];
        *count = count.saturating_sub(1);
        if *count == 0 && notify {
            self.work.push_back(Work::Unblocked(target));
        }
    }

    /// Removes the pending constraint `source <= target` from `source`'s node.
    pub(crate) fn drop_gate(&mut self, source: Endpoint, target: Endpoint) {
        if let Some(node) = self.nodes.get_mut(&source.node)
            && let Some(pos) = node
                .gates
                .iter()
                .position(|e| e.own == source.point && e.other == target)
        {
            node.gates.remove(pos);
        }
    }

    /// A node is dead (killed, or failed for good): every constraint waiting for one of its
    /// points is satisfied now, and the constraints it waited on are dropped.
    pub(crate) fn release_dead(&mut self, id: NodeId) {
        self.release_gates(id, None);
        let Some(node) = self.nodes.get_mut(&id) else {
            return;
        };
        let waits = std::mem::take(&mut node.waits_on);
        node.blockers = [0; 4];
        for e in waits {
            self.drop_gate(e.other, Endpoint::new(id, e.own));
        }
    }

    /// A node just finished (achieved, killed, or failed for good) under a live parent, or
    /// as a root: the parent stops waiting for it, and it is retired.
    pub(crate) fn settle_finished(&mut self, id: NodeId) {
        let parent = self.nodes.get(&id).and_then(|n| n.parent);
        if let Some(p) = parent
            && let Some(pn) = self.nodes.get_mut(&p)
            && !pn.is_finished()
        {
            pn.unfinished_children = pn.unfinished_children.saturating_sub(1);
            if pn.unfinished_children == 0 {
                self.work.push_back(Work::Advance(p));
            }
        }
        self.retire(id);
    }
}
