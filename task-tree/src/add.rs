//! Adding nodes and constraints, plan-first included.

use tracing::debug;

use crate::constraint::{Constraint, NewConstraint};
use crate::error::{Result, TreeError};
use crate::event::TreeEvent;
use crate::id::{Nanos, NodeId};
use crate::node::{Edge, Node};
use crate::point::{Endpoint, Point};
use crate::propagate::Work;
use crate::spec::NodeSpec;
use crate::state::{NodeKind, NodeState};
use crate::tree::TaskTree;

impl TaskTree {
    /// Adds a node (a goal, command or query message) with its constraints, and returns
    /// its id with the events caused (typically `Ready` for the new node).
    ///
    /// The parent must be live, not a query, and not failed. Either the node and all its
    /// constraints are added, or nothing is (the id is not consumed).
    pub fn add_node(&mut self, spec: NodeSpec, now: Nanos) -> Result<(NodeId, Vec<TreeEvent>)> {
        self.check_time(now)?;
        if let Some(p) = spec.parent {
            self.check_parent(p, &spec.name)?;
        }
        if spec.kind == NodeKind::Query && !spec.constraints.is_empty() {
            return Err(TreeError::BadSpec {
                name: spec.name,
                reason: "a query cannot carry constraints: the tree never schedules queries"
                    .to_string(),
            });
        }
        let id = NodeId(self.next_id);
        self.next_id = self.next_id.checked_add(1).ok_or(TreeError::IdsExhausted)?;
        let NodeSpec {
            parent,
            kind,
            name,
            handler,
            constraints,
        } = spec;
        self.nodes
            .insert(id, Node::new(kind, name, handler, parent, now));
        match parent.and_then(|p| self.nodes.get_mut(&p)) {
            Some(pn) => {
                pn.children.push(id);
                pn.unfinished_children += 1;
            }
            None => {
                self.roots.insert(id);
            }
        }

        let mut linked = Vec::new();
        if let Err(e) = self.link_new_node(id, kind, &constraints, &mut linked) {
            debug!(node = %id, error = %e, "node refused");
            self.undo_links(&linked);
            self.nodes.remove(&id);
            match parent.and_then(|p| self.nodes.get_mut(&p)) {
                Some(pn) => {
                    pn.children.pop();
                    pn.unfinished_children = pn.unfinished_children.saturating_sub(1);
                }
                None => {
                    self.roots.remove(&id);
                }
            }
            self.next_id = id.0;
            return Err(e);
        }
        for c in &linked {
            self.after_blocked(c.after);
        }
        self.peak_len = self.peak_len.max(self.nodes.len());
        self.work.push_back(Work::Advance(id));
        self.run(now);
        Ok((id, self.take_events()))
    }

    /// Adds a point constraint between any two endpoints of any two nodes.
    ///
    /// Satisfied at once (and not stored) when its `before` point has already occurred, or
    /// belongs to a finished or retired node. Refused when its `after` point has already
    /// occurred or its node has finished, when it names a query, or when it would close a
    /// cycle.
    pub fn add_constraint(&mut self, constraint: Constraint, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        let mut linked = Vec::new();
        self.link(constraint, &mut linked)?;
        for c in &linked {
            self.after_blocked(c.after);
        }
        self.run(now);
        Ok(self.take_events())
    }

    /// Plan first: every goal of `node`'s subtree, `node` included, finishes planning
    /// (its handling ends) before any achievement in the subtree starts.
    ///
    /// Expressed with point constraints: `end(handle g) <= start(achieve node)` for every
    /// goal `g` of the subtree, now and for each goal added below `node` later, as long as
    /// `node`'s achievement has not started. Since a command's start is the start of its
    /// achievement, and starting any achievement below `node` starts `node`'s, this holds
    /// back every command of the subtree until all its planning is done. Goals patched in
    /// after the achievement has started are not held back.
    pub fn plan_first(&mut self, node: NodeId, now: Nanos) -> Result<Vec<TreeEvent>> {
        self.check_time(now)?;
        let n = self.live_node(node)?;
        if n.kind == NodeKind::Query {
            return Err(TreeError::WrongState {
                node,
                op: "set plan-first on",
                state: n.state,
                hint: "queries are never scheduled",
            });
        }
        if n.occurred(Point::AchievementStart) || n.state == NodeState::Failed {
            return Err(TreeError::WrongState {
                node,
                op: "set plan-first on",
                state: n.state,
                hint: "plan-first needs a node whose achievement has not started yet",
            });
        }
        if n.plan_first {
            return Ok(Vec::new());
        }
        let goals: Vec<NodeId> = self
            .subtree_ids(node)
            .into_iter()
            .filter(|g| {
                self.nodes.get(g).is_some_and(|gn| {
                    gn.kind == NodeKind::Goal
                        && !gn.is_finished()
                        && !gn.occurred(Point::HandlingEnd)
                })
            })
            .collect();
        let mut linked = Vec::new();
        for g in goals {
            let c = Constraint::new(g.handling_end(), node.achievement_start());
            if let Err(e) = self.link(c, &mut linked) {
                self.undo_links(&linked);
                return Err(e);
            }
        }
        if let Some(n) = self.nodes.get_mut(&node) {
            n.plan_first = true;
        }
        for c in &linked {
            self.after_blocked(c.after);
        }
        self.run(now);
        Ok(self.take_events())
    }

    fn check_parent(&self, p: NodeId, name: &str) -> Result<()> {
        let bad = |reason: String| TreeError::BadSpec {
            name: name.to_string(),
            reason,
        };
        self.check_known(p)
            .map_err(|_| bad(format!("its parent {p} was never assigned by this tree")))?;
        let Some(pn) = self.nodes.get(&p) else {
            return Err(bad(format!(
                "its parent {p} has finished and was retired; add it under a live node"
            )));
        };
        if pn.kind == NodeKind::Query {
            return Err(bad(format!(
                "its parent {p} is a query, and queries are leaves"
            )));
        }
        if pn.state == NodeState::Failed || pn.is_finished() {
            return Err(bad(format!(
                "its parent {p} is {}; retry the parent first or add the node elsewhere",
                pn.state
            )));
        }
        Ok(())
    }

    fn link_new_node(
        &mut self,
        id: NodeId,
        kind: NodeKind,
        constraints: &[NewConstraint],
        linked: &mut Vec<Constraint>,
    ) -> Result<()> {
        for c in constraints {
            match c.resolve(id) {
                Some(point_constraint) => self.link(point_constraint, linked)?,
                None => {
                    if let Some(n) = self.nodes.get_mut(&id) {
                        n.plan_first = true;
                    }
                    if kind == NodeKind::Goal {
                        self.link(
                            Constraint::new(id.handling_end(), id.achievement_start()),
                            linked,
                        )?;
                    }
                }
            }
        }
        if kind == NodeKind::Goal {
            self.link_plan_first_ancestors(id, linked)?;
        }
        Ok(())
    }

    /// `end(handle id) <= start(achieve a)` for each plan-first ancestor `a` whose
    /// achievement has not started.
    pub(crate) fn link_plan_first_ancestors(
        &mut self,
        id: NodeId,
        linked: &mut Vec<Constraint>,
    ) -> Result<()> {
        let holders: Vec<NodeId> = self
            .ancestors(id)
            .filter(|a| {
                self.nodes
                    .get(a)
                    .is_some_and(|an| an.plan_first && !an.occurred(Point::AchievementStart))
            })
            .collect();
        for a in holders {
            self.link(
                Constraint::new(id.handling_end(), a.achievement_start()),
                linked,
            )?;
        }
        Ok(())
    }

    /// Validates and stores one constraint; pushes it on `linked` if it was stored.
    pub(crate) fn link(&mut self, c: Constraint, linked: &mut Vec<Constraint>) -> Result<()> {
        self.check_known(c.before.node)?;
        self.check_known(c.after.node)?;
        for ep in [c.before, c.after] {
            if self
                .nodes
                .get(&ep.node)
                .is_some_and(|n| n.kind == NodeKind::Query)
            {
                return Err(TreeError::QueryConstrained {
                    constraint: c,
                    node: ep.node,
                });
            }
        }
        let before_done = self
            .nodes
            .get(&c.before.node)
            .is_none_or(|n| n.is_finished() || n.occurred(c.before.point));
        if before_done {
            return Ok(());
        }
        let unsatisfiable = |reason: String| TreeError::Unsatisfiable {
            constraint: c,
            reason,
        };
        match self.nodes.get(&c.after.node) {
            None => {
                return Err(unsatisfiable(format!(
                    "{} has finished and was retired, while {} has not occurred",
                    c.after.node, c.before
                )));
            }
            Some(n) if n.is_finished() => {
                return Err(unsatisfiable(format!(
                    "{} is {} already, while {} has not occurred",
                    c.after.node, n.state, c.before
                )));
            }
            Some(n) => {
                if let Some(t) = n.time(c.after.point) {
                    return Err(unsatisfiable(format!(
                        "{} already occurred (at {t} ns), while {} has not",
                        c.after, c.before
                    )));
                }
            }
        }
        let (from, to) = (self.canonical(c.after), self.canonical(c.before));
        if from == to {
            return Ok(()); // `x <= x` always holds
        }
        let pending = self.nodes.get(&c.after.node).is_some_and(|n| {
            n.waits_on
                .iter()
                .any(|e| e.own == c.after.point && e.other == c.before)
        });
        if pending {
            return Ok(());
        }
        if let Some(path) = self.find_path(from, to) {
            let cycle = std::iter::once(to)
                .chain(path)
                .map(|e| e.to_string())
                .collect::<Vec<_>>()
                .join(" -> ");
            debug!(constraint = %c, %cycle, "cyclic constraint refused");
            return Err(TreeError::Cycle {
                constraint: c,
                cycle,
            });
        }
        if let Some(n) = self.nodes.get_mut(&c.after.node) {
            if n.waits_on.capacity() == 0 {
                n.waits_on.reserve_exact(1); // most points wait on one constraint
            }
            n.waits_on.push(Edge {
                own: c.after.point,
                other: c.before,
            });
            n.blockers[c.after.point.index()] += 1;
        }
        if let Some(n) = self.nodes.get_mut(&c.before.node) {
            if n.gates.capacity() == 0 {
                n.gates.reserve_exact(1);
            }
            n.gates.push(Edge {
                own: c.before.point,
                other: c.after,
            });
        }
        linked.push(c);
        Ok(())
    }

    /// Removes constraints stored by [`TaskTree::link`], newest first, without events.
    pub(crate) fn undo_links(&mut self, linked: &[Constraint]) {
        for c in linked.iter().rev() {
            self.drop_wait(c.after, c.before, false);
            self.drop_gate(c.before, c.after);
        }
    }

    /// A new constraint now holds back `after`: readiness announced before no longer
    /// stands for the nodes it gates.
    pub(crate) fn after_blocked(&mut self, after: Endpoint) {
        let Some(node) = self.nodes.get(&after.node) else {
            return;
        };
        let gated: Vec<NodeId> = match (after.point, node.kind) {
            (Point::HandlingStart, _) | (Point::AchievementStart, NodeKind::Command) => {
                vec![after.node]
            }
            (Point::AchievementStart, _) => self
                .subtree_ids(after.node)
                .into_iter()
                .filter(|d| {
                    self.nodes
                        .get(d)
                        .is_some_and(|dn| dn.kind == NodeKind::Command)
                })
                .collect(),
            _ => Vec::new(),
        };
        for d in gated {
            if let Some(dn) = self.nodes.get_mut(&d)
                && dn.state == NodeState::Waiting
            {
                dn.announced = false;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::Bench;
    use crate::{Constraint, NewConstraint, NodeId, NodeSpec, TreeError, TreeEvent};

    #[test]
    fn a_cycle_through_the_implicit_orderings_is_refused_and_named() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        let n2 = b.goal(Some(root), "planGait");
        let n3 = b.goal(Some(n2), "moveArm");
        let err = b
            .tree
            .add_constraint(
                Constraint::new(n3.achievement_end(), n2.handling_start()),
                9,
            )
            .expect_err("cycle");
        assert_eq!(
            err.to_string(),
            "constraint end(achieve n3) <= start(handle n2) would close the cycle \
             end(achieve n3) -> start(handle n2) -> start(handle n3) -> end(handle n3) -> \
             end(achieve n3); drop or reverse a constraint on that cycle"
        );
    }

    #[test]
    fn a_cycle_through_explicit_constraints_is_refused() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        let a = b.command(root, "a", &[]);
        let c = b.command(root, "c", &[NewConstraint::sequential_achievement_after(a)]);
        let err = b
            .tree
            .add_constraint(Constraint::sequential_achievement(c, a), 9)
            .expect_err("cycle");
        assert!(matches!(err, TreeError::Cycle { .. }), "{err}");
        // The reverse direction repeats what is there and is accepted.
        assert!(
            b.tree
                .add_constraint(Constraint::invocation_order(a, c), 9)
                .is_ok()
        );
    }

    #[test]
    fn a_refused_node_leaves_the_tree_unchanged_and_its_id_unused() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        let child = b.goal(Some(root), "step");
        let before = b.tree.render_text();
        let spec = NodeSpec::goal("bad", "planner")
            .under(child)
            .with(NewConstraint::invocation_after(root))
            .with(NewConstraint::Before {
                point: crate::Point::AchievementEnd,
                after: child.handling_start(),
            });
        let err = b.tree.add_node(spec, 9).expect_err("cycle");
        assert!(matches!(err, TreeError::Cycle { .. }), "{err}");
        assert_eq!(b.tree.render_text(), before);
        assert_eq!(b.tree.next_id(), NodeId(3));
        assert_eq!(b.tree.get(root).map(|v| v.gating().count()), Some(0));
    }

    #[test]
    fn a_constraint_whose_before_point_has_occurred_is_satisfied_at_once() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let cmd = b.command(root, "move", &[NewConstraint::invocation_after(root)]);
        assert!(b.tree.is_ready(cmd));
        assert_eq!(b.tree.get(cmd).map(|v| v.waiting_on().count()), Some(0));
    }

    #[test]
    fn constraints_on_retired_nodes_are_satisfied_as_before_and_refused_as_after() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let done = b.command(root, "done", &[]);
        b.run(done);
        assert!(b.tree.was_retired(done));
        let next = b.command(
            root,
            "next",
            &[NewConstraint::sequential_achievement_after(done)],
        );
        assert!(b.tree.is_ready(next));
        let err = b
            .tree
            .add_constraint(Constraint::sequential_achievement(next, done), 20)
            .expect_err("unsatisfiable");
        assert!(matches!(err, TreeError::Unsatisfiable { .. }), "{err}");
    }

    #[test]
    fn a_constraint_on_a_point_that_has_passed_is_refused() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        let other = b.goal(None, "other");
        b.start(root);
        let err = b
            .tree
            .add_constraint(Constraint::invocation_order(other, root), 9)
            .expect_err("unsatisfiable");
        assert_eq!(
            err.to_string(),
            "constraint start(handle n2) <= start(handle n1) can never hold: \
             start(handle n1) already occurred (at 3 ns), while start(handle n2) has not"
        );
    }

    #[test]
    fn unknown_nodes_and_queries_are_refused() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        let err = b
            .tree
            .add_constraint(Constraint::invocation_order(root, NodeId(99)), 5)
            .expect_err("unknown");
        assert_eq!(
            err,
            TreeError::UnknownNode {
                node: NodeId(99),
                last: 1
            }
        );
        b.start(root);
        let q = b.add(NodeSpec::query("bodyPosition", "controller").under(root));
        let err = b
            .tree
            .add_constraint(Constraint::invocation_order(root, q), 9)
            .expect_err("query");
        assert!(matches!(err, TreeError::QueryConstrained { .. }), "{err}");
        let err = b
            .tree
            .add_node(
                NodeSpec::goal("x", "planner")
                    .under(q)
                    .with(NewConstraint::invocation_after(root)),
                9,
            )
            .expect_err("under a query");
        assert!(matches!(err, TreeError::BadSpec { .. }), "{err}");
    }

    #[test]
    fn the_same_constraint_twice_is_stored_once() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        let a = b.goal(Some(root), "a");
        let c = b.goal(Some(root), "c");
        for t in 10..13 {
            b.tree
                .add_constraint(Constraint::delay_planning(a, c), t)
                .expect("accepted");
        }
        assert_eq!(b.tree.get(c).map(|v| v.waiting_on().count()), Some(1));
    }

    #[test]
    fn a_constraint_added_to_a_ready_node_withdraws_readiness_until_it_holds() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let a = b.command(root, "a", &[]);
        let c = b.command(root, "c", &[]);
        assert!(b.tree.is_ready(c));
        b.tree
            .add_constraint(Constraint::sequential_achievement(a, c), 10)
            .expect("accepted");
        assert!(!b.tree.is_ready(c));
        assert_eq!(
            b.tree.why_not_ready(c).as_deref(),
            Some("constraint end(achieve n2) <= start(achieve n3) does not hold yet")
        );
        b.now = 10;
        let events = b.run(a);
        assert!(events.contains(&TreeEvent::Ready(c)), "{events:?}");
    }

    #[test]
    fn plan_first_holds_every_command_until_all_planning_is_done() {
        let mut b = Bench::new();
        let root = b.add(NodeSpec::goal("walk", "planner").with(NewConstraint::PlanFirst));
        b.start(root);
        let g1 = b.goal(Some(root), "planA");
        let g2 = b.goal(Some(root), "planB");
        b.start(g1);
        let c1 = b.command(g1, "moveA", &[]);
        b.succeed(g1);
        assert!(!b.tree.is_ready(c1), "planB and walk are still planning");
        b.succeed(root);
        assert!(!b.tree.is_ready(c1), "planB is still planning");
        b.start(g2);
        let c2 = b.command(g2, "moveB", &[]);
        let events = b.succeed(g2);
        assert!(events.contains(&TreeEvent::Ready(c1)), "{events:?}");
        assert!(events.contains(&TreeEvent::Ready(c2)), "{events:?}");
    }

    #[test]
    fn plan_first_added_later_covers_existing_goals() {
        let mut b = Bench::new();
        let root = b.goal(None, "walk");
        b.start(root);
        let g1 = b.goal(Some(root), "plan");
        let c = b.command(root, "move", &[]);
        assert!(b.tree.is_ready(c));
        b.tree.plan_first(root, 10).expect("plan first");
        assert!(!b.tree.is_ready(c));
        b.now = 10;
        b.succeed(root);
        let events = b.run(g1);
        assert!(events.contains(&TreeEvent::Ready(c)), "{events:?}");
    }
}
