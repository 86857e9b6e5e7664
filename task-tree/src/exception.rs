//! Failure, kill, and the tools central uses to handle exceptions: suspend, resume,
//! retry.

use tracing::debug;

use crate::constraint::Constraint;
use crate::error::{Result, TreeError};
use crate::event::TreeEvent;
use crate::id::{Nanos, NodeId};
use crate::propagate::Work;
use crate::state::{NodeKind, NodeState};
use crate::tree::TaskTree;

impl TaskTree {
    /// Kills a node and its whole subtree (nodes already achieved are not touched; they
    /// are retired with it). Each killed node is reported as `Killed { was }`; `was:
    /// Handling` means its handler is running and should get a cancel notice. The node
    /// then counts as finished for its parent, and the subtree is retired: a `finish` that
    /// a cancelled handler sends afterwards gets [`TreeError::Retired`], which central can
    /// ignore.
    pub fn kill(&mut self, id: NodeId, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        self.live_node(id)?;
        self.kill_subtree(id, now);
        self.settle_finished(id);
        self.run(now);
        Ok(self.take_events())
    }

    /// Stops dispatch in the node's subtree: no node in it is ready (and no `Ready` is
    /// emitted) until a matching [`TaskTree::resume`]. Running handlers go on. A handler
    /// in the subtree that fails meanwhile has its failure held (see the crate
    /// documentation). Suspensions nest: each `suspend` needs its own `resume`.
    pub fn suspend(&mut self, id: NodeId, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        let node = self.live_node(id)?;
        if node.kind == NodeKind::Query {
            return Err(TreeError::WrongState {
                node: id,
                op: "suspend",
                state: node.state,
                hint: "queries are not dispatched by the tree",
            });
        }
        let ids = self.subtree_ids(id);
        if let Some(n) = self.nodes.get_mut(&id) {
            n.suspend_count += 1;
            if n.suspend_count == 1 {
                self.suspended_nodes += 1;
            }
        }
        for d in ids {
            if let Some(n) = self.nodes.get_mut(&d) {
                n.announced = false;
            }
        }
        Ok(self.take_events())
    }

    /// Undoes one [`TaskTree::suspend`]. When nothing above or at a node is suspended any
    /// more, its held failure (if any) propagates now, and ready nodes get `Ready`.
    pub fn resume(&mut self, id: NodeId, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        let node = self.live_node(id)?;
        if node.suspend_count == 0 {
            return Err(TreeError::NotSuspended { node: id });
        }
        if let Some(n) = self.nodes.get_mut(&id) {
            n.suspend_count -= 1;
            if n.suspend_count == 0 {
                self.suspended_nodes = self.suspended_nodes.saturating_sub(1);
            }
        }
        if self.suspended_at(id).is_none() {
            let ids = self.subtree_ids(id);
            for &d in &ids {
                let held = self
                    .nodes
                    .get(&d)
                    .is_some_and(|n| n.state == NodeState::Failed && n.failure_held);
                if held && self.suspended_at(d).is_none() {
                    self.finalize_failure(d, now);
                }
            }
            for d in ids {
                if self.nodes.contains_key(&d) {
                    self.work.push_back(Work::Advance(d));
                }
            }
            self.run(now);
        }
        Ok(self.take_events())
    }

    /// Puts a node whose failure is held, or whose handler has finished (handled or
    /// achieving), back to `Waiting` so that it is dispatched again. Its descendants are
    /// killed and retired; its four points are cleared. Constraints already satisfied by
    /// its earlier points stay satisfied; constraints still pending on it stay pending.
    pub fn retry(&mut self, id: NodeId, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        let node = self.live_node(id)?;
        let allowed = node.kind != NodeKind::Query
            && match node.state {
                NodeState::Failed => node.failure_held,
                NodeState::Handled | NodeState::Achieving => true,
                NodeState::Handling => node.finish_pending,
                _ => false,
            };
        if !allowed {
            return Err(TreeError::WrongState {
                node: id,
                op: "retry",
                state: node.state,
                hint: "only a node whose failure is held by a suspension, or whose handler has finished, can be retried; kill a running one instead",
            });
        }
        let kind = node.kind;
        self.kill_children(id, now);
        if let Some(n) = self.nodes.get_mut(&id) {
            n.state = NodeState::Waiting;
            n.times = [crate::node::NOT_YET; 4];
            n.ended_at = None;
            n.handler_done = false;
            n.finish_pending = false;
            n.failure_held = false;
            n.failure_reason = None;
            n.announced = false;
            n.unfinished_children = 0;
            n.children.clear();
            n.retired_children = 0;
        }
        if kind == NodeKind::Goal {
            self.relink_plan_first(id);
        }
        self.work.push_back(Work::Advance(id));
        self.run(now);
        Ok(self.take_events())
    }

    /// After a retry, a goal under plan-first nodes is held back again by them.
    fn relink_plan_first(&mut self, id: NodeId) {
        let own = self.nodes.get(&id).is_some_and(|n| n.plan_first);
        let mut linked = Vec::new();
        let mut result = Ok(());
        if own {
            result = self.link(
                Constraint::new(id.handling_end(), id.achievement_start()),
                &mut linked,
            );
        }
        if result.is_ok() {
            result = self.link_plan_first_ancestors(id, &mut linked);
        }
        if let Err(e) = result {
            // Cannot happen with an acyclic plan; keep what was linked rather than fail a
            // retry that has already been carried out.
            tracing::warn!(node = %id, error = %e, "plan-first not restored after retry");
        }
        for c in &linked {
            self.after_blocked(c.after);
        }
    }

    /// A handler reported failure.
    pub(crate) fn fail(&mut self, id: NodeId, reason: String, now: Nanos) {
        let Some(node) = self.nodes.get_mut(&id) else {
            return;
        };
        node.state = NodeState::Failed;
        node.ended_at = Some(now);
        node.finish_pending = false;
        node.handler_done = false;
        node.announced = false;
        node.failure_reason = Some(reason.clone().into_boxed_str());
        let kind = node.kind;
        self.events.push(TreeEvent::Failed { node: id, reason });
        if kind == NodeKind::Query {
            // The asker gets the error as its reply; the tree only records it.
            self.settle_finished(id);
            return;
        }
        self.kill_children(id, now);
        if let Some(s) = self.suspended_at(id) {
            debug!(node = %id, suspended = %s, "failure held for exception handling");
            if let Some(n) = self.nodes.get_mut(&id) {
                n.failure_held = true;
            }
            return;
        }
        self.finalize_failure(id, now);
    }

    /// A failure that is not (or no longer) held: the node dies, and the failure
    /// propagates to each ancestor in turn up to the root, killing whatever else is live
    /// below them; the root's tree is then retired.
    pub(crate) fn finalize_failure(&mut self, id: NodeId, now: Nanos) {
        let (origin_name, origin_reason) = match self.nodes.get(&id) {
            Some(n) => (n.name.clone(), n.failure_reason.clone().unwrap_or_default()),
            None => return,
        };
        let mut cur = id;
        loop {
            if let Some(n) = self.nodes.get_mut(&cur) {
                n.failure_held = false;
            }
            self.release_dead(cur);
            let parent = self.nodes.get(&cur).and_then(|n| n.parent);
            let Some(p) = parent.filter(|p| self.nodes.get(p).is_some_and(|pn| !pn.is_finished()))
            else {
                break;
            };
            let reason = format!("descendant {id} ({origin_name}) failed: {origin_reason}");
            let Some(pn) = self.nodes.get_mut(&p) else {
                break;
            };
            let running = pn.state == NodeState::Handling && !pn.finish_pending;
            pn.state = NodeState::Failed;
            pn.ended_at = Some(now);
            pn.finish_pending = false;
            pn.handler_done = false;
            pn.announced = false;
            pn.failure_held = false;
            pn.failure_reason = Some(reason.clone().into_boxed_str());
            self.events.push(TreeEvent::Failed { node: p, reason });
            if running {
                self.events.push(TreeEvent::CancelHandler(p));
            }
            for c in self.live_children(p) {
                if c != cur {
                    self.kill_subtree(c, now);
                }
            }
            cur = p;
        }
        // `cur` is the root of the failed tree, or a node under a finished parent.
        self.settle_finished(cur);
    }

    /// Kills every live child subtree of `id` and retires it.
    pub(crate) fn kill_children(&mut self, id: NodeId, now: Nanos) {
        for c in self.live_children(id) {
            self.kill_subtree(c, now);
            self.retire(c);
        }
        if let Some(n) = self.nodes.get_mut(&id) {
            n.unfinished_children = 0;
        }
    }

    /// Marks every unfinished node of a subtree killed (pre-order) and releases the
    /// constraints that waited on them.
    pub(crate) fn kill_subtree(&mut self, id: NodeId, now: Nanos) {
        for d in self.subtree_ids(id) {
            let Some(n) = self.nodes.get_mut(&d) else {
                continue;
            };
            if n.is_finished() {
                continue;
            }
            let was = n.state;
            n.state = NodeState::Killed;
            n.ended_at = Some(now);
            n.finish_pending = false;
            n.failure_held = false;
            n.announced = false;
            self.events.push(TreeEvent::Killed { node: d, was });
            self.release_dead(d);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::Bench;
    use crate::{Constraint, NewConstraint, NodeSpec, NodeState, TreeError, TreeEvent};

    #[test]
    fn a_failure_propagates_to_the_root_killing_the_rest() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let step = b.goal(Some(root), "step");
        let other = b.goal(Some(root), "other");
        b.start(step);
        let leg = b.command(step, "moveArm", &[]);
        let body = b.command(
            step,
            "moveBase",
            &[NewConstraint::sequential_achievement_after(leg)],
        );
        b.succeed(step);
        b.start(leg);
        let events = b.fail(leg, "foot slipped");
        let reason = "descendant n4 (moveArm) failed: foot slipped".to_string();
        assert_eq!(
            events,
            vec![
                TreeEvent::Failed {
                    node: leg,
                    reason: "foot slipped".into()
                },
                TreeEvent::Failed {
                    node: step,
                    reason: reason.clone()
                },
                TreeEvent::Killed {
                    node: body,
                    was: NodeState::Waiting
                },
                TreeEvent::Failed { node: root, reason },
                TreeEvent::CancelHandler(root),
                TreeEvent::Killed {
                    node: other,
                    was: NodeState::Waiting
                },
                TreeEvent::Retired(root),
            ]
        );
        assert!(b.tree.is_empty());
    }

    #[test]
    fn a_held_failure_can_be_retried_and_the_plan_completes() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let leg = b.command(root, "moveArm", &[]);
        let body = b.command(
            root,
            "moveBase",
            &[NewConstraint::sequential_achievement_after(leg)],
        );
        b.succeed(root);
        b.start(leg);
        b.tree.suspend(leg, b.now).expect("suspend");
        let events = b.fail(leg, "slip");
        assert_eq!(
            events,
            vec![TreeEvent::Failed {
                node: leg,
                reason: "slip".into()
            }]
        );
        let view = b.tree.get(leg).expect("held");
        assert!(view.failure_held());
        assert!(!b.tree.is_ready(body), "moveBase still waits for moveArm");
        let events = b.tree.retry(leg, b.now).expect("retry");
        assert!(events.is_empty(), "still suspended: {events:?}");
        let events = b.tree.resume(leg, b.now).expect("resume");
        assert_eq!(events, vec![TreeEvent::Ready(leg)]);
        let events = b.run(leg);
        assert!(events.contains(&TreeEvent::Ready(body)), "{events:?}");
        b.run(body);
        assert!(b.tree.is_empty());
    }

    #[test]
    fn resuming_with_the_failure_still_held_lets_it_propagate() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let leg = b.command(root, "moveArm", &[]);
        b.start(leg);
        b.tree.suspend(root, b.now).expect("suspend");
        b.fail(leg, "slip");
        assert_eq!(b.tree.len(), 2);
        let events = b.tree.resume(root, b.now).expect("resume");
        assert!(
            events.contains(&TreeEvent::Failed {
                node: root,
                reason: "descendant n2 (moveArm) failed: slip".into()
            }),
            "{events:?}"
        );
        assert!(b.tree.is_empty());
        let err = b.tree.resume(root, b.now).expect_err("retired");
        assert!(matches!(err, TreeError::Retired { .. }), "{err}");
    }

    #[test]
    fn an_exception_handled_two_levels_up_patches_the_plan_and_completes() {
        let mut b = Bench::new();
        let walk = b.goal(None, "walk");
        b.start(walk);
        let step = b.goal(Some(walk), "step");
        b.start(step);
        let leg_goal = b.goal(Some(step), "moveArmGoal");
        let body = b.command(
            step,
            "moveBase",
            &[NewConstraint::sequential_achievement_after(leg_goal)],
        );
        b.succeed(step);
        b.start(leg_goal);
        let leg = b.command(leg_goal, "moveArm", &[]);
        b.succeed(leg_goal);
        b.start(leg);
        // The controller raises an exception: central suspends, reports the failure...
        b.tree.suspend(leg, b.now).expect("suspend");
        b.fail(leg, "leg struck terrain");
        // ...finds the handler on `step` (two levels up), which ignores the failed move
        // by killing it and patches in a recovery move before the body move.
        let ancestors: Vec<_> = b.tree.ancestors(leg).collect();
        assert_eq!(ancestors, vec![leg_goal, step, walk]);
        b.tree.kill(leg, b.now).expect("kill");
        let (recover, _) = b
            .tree
            .add_node(
                NodeSpec::command("planArm", "controller").under(step).with(
                    NewConstraint::Before {
                        point: crate::Point::AchievementEnd,
                        after: body.achievement_start(),
                    },
                ),
                b.now,
            )
            .expect("patch");
        b.tree
            .resume(leg, b.now)
            .expect_err("the killed node was retired");
        assert!(b.tree.is_ready(recover));
        assert!(!b.tree.is_ready(body));
        b.run(recover);
        assert!(b.tree.is_ready(body));
        b.run(body);
        b.succeed(walk);
        assert!(b.tree.is_empty(), "{}", b.tree.render_text());
    }

    #[test]
    fn killing_a_subtree_reports_running_handlers_and_frees_the_parent() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let step = b.goal(Some(root), "step");
        b.start(step);
        let leg = b.command(step, "moveArm", &[]);
        let waiting = b.command(
            step,
            "moveBase",
            &[NewConstraint::sequential_achievement_after(leg)],
        );
        let later = b.command(
            root,
            "later",
            &[NewConstraint::sequential_achievement_after(step)],
        );
        b.succeed(root);
        b.start(leg);
        let events = b.tree.kill(step, b.now).expect("kill");
        assert_eq!(
            events,
            vec![
                TreeEvent::Killed {
                    node: step,
                    was: NodeState::Handling
                },
                TreeEvent::Killed {
                    node: leg,
                    was: NodeState::Handling
                },
                TreeEvent::Killed {
                    node: waiting,
                    was: NodeState::Waiting
                },
                TreeEvent::Retired(step),
                TreeEvent::Ready(later),
            ]
        );
        b.run(later);
        assert!(b.tree.is_empty());
    }

    #[test]
    fn suspension_stops_dispatch_in_the_subtree_until_resumed() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let a = b.command(root, "a", &[]);
        let c = b.command(root, "c", &[NewConstraint::sequential_achievement_after(a)]);
        b.tree.suspend(root, b.now).expect("suspend");
        b.tree.suspend(root, b.now).expect("suspend twice");
        assert!(!b.tree.is_ready(a));
        let events = b.succeed(root);
        assert!(
            events.iter().all(|e| !matches!(e, TreeEvent::Ready(_))),
            "{events:?}"
        );
        assert!(b.tree.resume(root, b.now).expect("resume").is_empty());
        let events = b.tree.resume(root, b.now).expect("resume");
        assert_eq!(events, vec![TreeEvent::Ready(a)]);
        assert!(!b.tree.is_ready(c));
        let err = b.tree.resume(root, b.now).expect_err("not suspended");
        assert_eq!(err, TreeError::NotSuspended { node: root });
    }

    #[test]
    fn retry_replans_a_handled_goal_after_killing_its_children() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.run(root);
        assert!(b.tree.is_empty(), "a childless goal is achieved at once");
        let root = b.goal(None, "walk");
        b.start(root);
        let step = b.goal(Some(root), "step");
        b.start(step);
        let cmd = b.command(step, "move", &[]);
        b.succeed(step);
        let events = b.tree.retry(step, b.now).expect("retry");
        assert_eq!(
            events,
            vec![
                TreeEvent::Killed {
                    node: cmd,
                    was: NodeState::Waiting
                },
                TreeEvent::Retired(cmd),
                TreeEvent::Ready(step),
            ]
        );
        let view = b.tree.get(step).expect("live");
        assert_eq!(view.state(), NodeState::Waiting);
        assert_eq!(view.children().count(), 0);
        let err = b.tree.retry(step, b.now).expect_err("waiting");
        assert!(
            matches!(err, TreeError::WrongState { op: "retry", .. }),
            "{err}"
        );
    }

    #[test]
    fn a_dead_node_satisfies_the_constraints_that_waited_for_it() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let a = b.command(root, "a", &[]);
        let c = b.command(root, "c", &[]);
        b.tree
            .add_constraint(Constraint::delay_planning(a, c), b.now)
            .expect("accepted");
        let events = b.tree.kill(a, b.now).expect("kill");
        assert!(events.contains(&TreeEvent::Ready(c)), "{events:?}");
    }
}
