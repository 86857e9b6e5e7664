//! Handlers starting and finishing.

use crate::error::{Result, TreeError};
use crate::event::TreeEvent;
use crate::id::{Nanos, NodeId};
use crate::point::Point;
use crate::propagate::Work;
use crate::spec::Outcome;
use crate::state::{NodeKind, NodeState};
use crate::tree::TaskTree;

impl TaskTree {
    /// Records that the node's handler has started. The node must be ready (see
    /// [`TaskTree::is_ready`]); the error says what blocks it otherwise. A query may be
    /// started whenever it is waiting: the tree does not schedule queries.
    ///
    /// For a command this is also the start of its achievement, and of the achievement
    /// of every ancestor whose achievement had not started.
    pub fn start(&mut self, id: NodeId, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        let node = self.live_node(id)?;
        let kind = node.kind;
        if kind == NodeKind::Query {
            if node.state != NodeState::Waiting {
                return Err(TreeError::WrongState {
                    node: id,
                    op: "start",
                    state: node.state,
                    hint: "a query is started once",
                });
            }
        } else if let Err(blocker) = self.readiness(id) {
            return Err(TreeError::NotReady {
                node: id,
                reason: blocker.describe(id),
            });
        }
        if let Some(n) = self.nodes.get_mut(&id) {
            n.state = NodeState::Handling;
            n.announced = false;
        }
        self.occur(id, Point::HandlingStart, now);
        if kind == NodeKind::Command {
            self.start_achievement(id, now);
        }
        // Children patched in under a node that had not started can now be ready.
        for c in self.live_children(id) {
            self.work.push_back(Work::Advance(c));
        }
        self.run(now);
        Ok(self.take_events())
    }

    /// Records that the node's handler has ended.
    ///
    /// On success the handling end occurs (unless a constraint holds it back: the node
    /// then stays `Handling` with `finish_pending` until the constraint holds), and the
    /// node is achieved as soon as its descendants are and its constraints allow. On
    /// failure the failure policy of the crate documentation applies.
    pub fn finish(&mut self, id: NodeId, outcome: Outcome, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        let node = self.live_node(id)?;
        if node.state != NodeState::Handling || node.finish_pending {
            return Err(TreeError::WrongState {
                node: id,
                op: "finish",
                state: node.state,
                hint: "only a node whose handler was started and has not reported an end can be finished",
            });
        }
        let kind = node.kind;
        match outcome {
            Outcome::Success if kind == NodeKind::Query => {
                if let Some(n) = self.nodes.get_mut(&id) {
                    n.handler_done = true;
                    n.state = NodeState::Achieved;
                    n.ended_at = Some(now);
                }
                self.occur(id, Point::HandlingEnd, now);
                self.occur(id, Point::AchievementEnd, now);
                self.settle_finished(id);
            }
            Outcome::Success => {
                if let Some(n) = self.nodes.get_mut(&id) {
                    n.handler_done = true;
                    n.finish_pending = true;
                }
                self.work.push_back(Work::Advance(id));
            }
            Outcome::Failure { reason } => self.fail(id, reason, now),
        }
        self.run(now);
        Ok(self.take_events())
    }
}
