//! When a node may be dispatched, and in words why not.

use crate::constraint::Constraint;
use crate::id::NodeId;
use crate::point::Point;
use crate::state::{NodeKind, NodeState};
use crate::tree::TaskTree;

/// The first thing found that keeps a node from being ready.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Blocker {
    Gone,
    Query,
    NotWaiting(NodeState),
    Suspended(NodeId),
    ParentNotStarted(NodeId),
    Constraint(Constraint),
}

impl Blocker {
    pub(crate) fn describe(&self, id: NodeId) -> String {
        match self {
            Blocker::Gone => format!("{id} is not in the tree"),
            Blocker::Query => {
                "it is a query, which the tree never dispatches (start it directly)".to_string()
            }
            Blocker::NotWaiting(state) => format!("it is {state}, not waiting"),
            Blocker::Suspended(s) if *s == id => "it is suspended; resume it first".to_string(),
            Blocker::Suspended(s) => format!("its ancestor {s} is suspended; resume {s} first"),
            Blocker::ParentNotStarted(p) => {
                format!("its parent {p} has not started handling yet")
            }
            Blocker::Constraint(c) => format!("constraint {c} does not hold yet"),
        }
    }
}

impl TaskTree {
    /// `Ok` if the node is ready, else the first blocker found.
    pub(crate) fn readiness(&self, id: NodeId) -> Result<(), Blocker> {
        let node = self.nodes.get(&id).ok_or(Blocker::Gone)?;
        if node.kind == NodeKind::Query {
            return Err(Blocker::Query);
        }
        if node.state != NodeState::Waiting {
            return Err(Blocker::NotWaiting(node.state));
        }
        if let Some(s) = self.suspended_at(id) {
            return Err(Blocker::Suspended(s));
        }
        if let Some(p) = node.parent
            && let Some(parent) = self.nodes.get(&p)
            && !parent.occurred(Point::HandlingStart)
        {
            return Err(Blocker::ParentNotStarted(p));
        }
        if node.blockers[Point::HandlingStart.index()] > 0 {
            return Err(blocker_on(self, id, Point::HandlingStart));
        }
        if node.kind == NodeKind::Command {
            self.achievement_gate(id)?;
        }
        Ok(())
    }

    /// `Ok` if nothing holds back the achievement start of `id`: no pending constraint on
    /// it, nor on the achievement start of any ancestor whose achievement has not started
    /// (starting `id`'s achievement would start theirs).
    pub(crate) fn achievement_gate(&self, id: NodeId) -> Result<(), Blocker> {
        let mut cur = Some(id);
        while let Some(c) = cur {
            let Some(node) = self.nodes.get(&c) else {
                break;
            };
            if node.occurred(Point::AchievementStart) {
                break;
            }
            if node.blockers[Point::AchievementStart.index()] > 0 {
                return Err(blocker_on(self, c, Point::AchievementStart));
            }
            cur = node.parent;
        }
        Ok(())
    }
}

fn blocker_on(tree: &TaskTree, id: NodeId, point: Point) -> Blocker {
    match tree.nodes.get(&id).and_then(|n| n.first_wait(id, point)) {
        Some((before, after)) => Blocker::Constraint(Constraint::new(before, after)),
        None => Blocker::Gone,
    }
}
