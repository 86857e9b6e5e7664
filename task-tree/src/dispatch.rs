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
        let parent = self.nodes.get_mut(&id).and_then(|n| {
            n.state = NodeState::Handling;
            n.announced = false;
            n.parent
        });
        if kind == NodeKind::Command {
            // The ancestors' achievement starts first (outermost first), then the command
            // starts, which is the start of its own achievement.
            if let Some(p) = parent {
                self.start_achievement(p, now);
            }
            self.occur(id, Point::HandlingStart, now);
            self.occur(id, Point::AchievementStart, now);
        } else {
            self.occur(id, Point::HandlingStart, now);
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

#[cfg(test)]
mod tests {
    use crate::testing::Bench;
    use crate::{
        Constraint, NewConstraint, NodeSpec, NodeState, Outcome, Point, TreeError, TreeEvent,
    };

    #[test]
    fn starting_a_blocked_node_says_which_constraint_blocks_it() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let leg = b.command(root, "moveArm", &[]);
        let body = b.command(
            root,
            "moveBase",
            &[NewConstraint::sequential_achievement_after(leg)],
        );
        let err = b.tree.start(body, b.now).expect_err("not ready");
        assert_eq!(
            err.to_string(),
            "cannot start n3: constraint end(achieve n2) <= start(achieve n3) does not hold \
             yet; dispatch it after its Ready event"
        );
        let child = b.goal(None, "other");
        let grandchild = b.goal(Some(child), "inner");
        let err = b
            .tree
            .start(grandchild, b.now)
            .expect_err("parent not started");
        assert!(
            matches!(&err, TreeError::NotReady { reason, .. } if reason.contains("parent n4")),
            "{err}"
        );
    }

    #[test]
    fn a_command_start_starts_the_achievement_of_its_ancestors_outermost_first() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let step = b.goal(Some(root), "step");
        b.start(step);
        let cmd = b.command(step, "move", &[]);
        let events = b.start(cmd);
        assert_eq!(
            events,
            vec![
                TreeEvent::AchievementStarted(root),
                TreeEvent::AchievementStarted(step),
                TreeEvent::HandlingStarted(cmd),
                TreeEvent::AchievementStarted(cmd),
            ]
        );
    }

    #[test]
    fn completion_climbs_the_tree_and_retires_it() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let cmd = b.command(root, "move", &[]);
        assert_eq!(
            b.tree.get(root).map(|v| v.state()),
            Some(NodeState::Handling)
        );
        b.start(cmd);
        b.succeed(root);
        assert_eq!(
            b.tree.get(root).map(|v| v.state()),
            Some(NodeState::Achieving)
        );
        let events = b.succeed(cmd);
        assert_eq!(
            events,
            vec![
                TreeEvent::HandlingEnded(cmd),
                TreeEvent::Achieved(cmd),
                TreeEvent::Retired(cmd),
                TreeEvent::Achieved(root),
                TreeEvent::Retired(root),
            ]
        );
        assert!(b.tree.is_empty());
    }

    #[test]
    fn a_goal_without_commands_starts_its_achievement_when_its_handler_finishes() {
        let mut b = Bench::new();
        let root = b.goal(None, "think");
        let events = b.run(root);
        assert_eq!(
            events,
            vec![
                TreeEvent::HandlingStarted(root),
                TreeEvent::HandlingEnded(root),
                TreeEvent::AchievementStarted(root),
                TreeEvent::Achieved(root),
                TreeEvent::Retired(root),
            ]
        );
    }

    #[test]
    fn a_constraint_on_a_handling_end_delays_the_end_not_the_handler() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let a = b.command(root, "a", &[]);
        let c = b.command(
            root,
            "c",
            &[NewConstraint::After {
                before: a.achievement_end(),
                point: Point::HandlingEnd,
            }],
        );
        b.start(c);
        let events = b.succeed(c);
        assert!(events.is_empty(), "{events:?}");
        let view = b.tree.get(c).expect("live");
        assert_eq!(view.state(), NodeState::Handling);
        assert!(view.finish_pending());
        let err = b.tree.finish(c, Outcome::Success, 20).expect_err("twice");
        assert!(matches!(err, TreeError::WrongState { .. }), "{err}");
        b.now = 20;
        let events = b.run(a);
        let ended = events
            .iter()
            .position(|e| *e == TreeEvent::HandlingEnded(c));
        let achieved = events.iter().position(|e| *e == TreeEvent::Achieved(a));
        assert!(ended.is_some() && achieved < ended, "{events:?}");
        assert!(events.contains(&TreeEvent::Achieved(c)), "{events:?}");
    }

    #[test]
    fn a_constraint_on_an_achievement_end_keeps_the_node_achieving() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let a = b.command(root, "a", &[]);
        let c = b.command(root, "c", &[]);
        b.tree
            .add_constraint(
                Constraint::new(a.achievement_end(), c.achievement_end()),
                10,
            )
            .expect("accepted");
        b.now = 10;
        b.run(c);
        assert_eq!(b.tree.get(c).map(|v| v.state()), Some(NodeState::Achieving));
        let events = b.run(a);
        assert!(events.contains(&TreeEvent::Achieved(c)), "{events:?}");
    }

    #[test]
    fn queries_are_recorded_never_dispatched_and_their_failure_stays_put() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let (q, events) = b
            .tree
            .add_node(NodeSpec::query("bodyPosition", "controller").under(root), 5)
            .expect("query");
        assert!(events.is_empty());
        assert!(!b.tree.is_ready(q));
        b.now = 5;
        b.start(q);
        b.succeed(root);
        // Its handler has finished: its achievement has started, and waits for the query.
        assert_eq!(
            b.tree.get(root).map(|v| v.state()),
            Some(NodeState::Achieving)
        );
        let events = b.fail(q, "timed out");
        assert!(events.contains(&TreeEvent::Achieved(root)), "{events:?}");
    }

    #[test]
    fn finishing_a_node_that_is_not_running_is_refused() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        let err = b
            .tree
            .finish(root, Outcome::Success, 5)
            .expect_err("waiting");
        assert!(
            matches!(
                err,
                TreeError::WrongState {
                    op: "finish",
                    state: NodeState::Waiting,
                    ..
                }
            ),
            "{err}"
        );
        let err = b.tree.start(root, 0).expect_err("time");
        assert!(matches!(err, TreeError::TimeWentBackwards { .. }), "{err}");
    }
}
