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
            return Err(bad(format!("its parent {p} is a query, and queries are leaves")));
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
            self.link(Constraint::new(id.handling_end(), a.achievement_start()), linked)?;
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
            n.waits_on.push(Edge {
                own: c.after.point,
                other: c.before,
            });
            n.blockers[c.after.point.index()] += 1;
        }
        if let Some(n) = self.nodes.get_mut(&c.before.node) {
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
