//! The adapter between central and `tca-task-tree`: every mutation goes through a logged
//! [`TreeOp`], applied with `TaskTree::apply`, so the log replays into the same tree.

use tca_logs::{LogRecord, RecordKind, TreeRecord};
use tca_messages::TimePoint;
use tca_task_tree::{
    Constraint, Endpoint, NewConstraint, NodeId, NodeKind, NodeSpec, Outcome, TaskTree,
    TreeEvent as Raw, TreeOp,
};

pub(super) use tca_task_tree::Point;

use super::Action;

/// A constraint's task: the node being added, or an existing node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Who {
    This,
    Node(u64),
}

/// A constraint given with a new node.
#[derive(Clone, Copy, Debug)]
pub(super) struct RelConstraint {
    pub(super) before: (Who, Point),
    pub(super) after: (Who, Point),
}

/// What central acts on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum TreeEvent {
    /// Dispatch it when its handler has capacity.
    Ready(u64),
    /// Achieved.
    Achieved(u64),
    /// Failed (tell whoever asked).
    Failed(u64, String),
    /// Its handler is running and must be told to stop.
    Cancel(u64),
    /// Killed.
    Killed(u64),
    /// Gone from the tree: forget it.
    Retired(u64),
}

/// Converts a wire time point.
pub(super) fn point(p: TimePoint) -> Point {
    match p {
        TimePoint::HandlingStart => Point::HandlingStart,
        TimePoint::HandlingEnd => Point::HandlingEnd,
        TimePoint::AchievementStart => Point::AchievementStart,
        TimePoint::AchievementEnd => Point::AchievementEnd,
    }
}

/// The task tree with logging.
#[derive(Default, serde::Serialize, serde::Deserialize)]
pub(super) struct Tree {
    tree: TaskTree,
}

impl Tree {
    pub(super) fn len(&self) -> usize {
        self.tree.len()
    }

    pub(super) fn contains(&self, node: u64) -> bool {
        self.tree.contains(NodeId(node))
    }

    pub(super) fn was_retired(&self, node: u64) -> bool {
        self.tree.was_retired(NodeId(node))
    }

    pub(super) fn is_ready(&self, node: u64) -> bool {
        self.tree.is_ready(NodeId(node))
    }

    pub(super) fn render(&self) -> String {
        self.tree.render_text()
    }

    fn apply(
        &mut self,
        op: TreeOp,
        cause: Option<u64>,
        at_ns: u64,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        let raw = self.tree.apply(&op).map_err(|e| e.to_string())?;
        out.push(Action::Log(LogRecord {
            at_ns,
            kind: RecordKind::Tree(TreeRecord { op, message: cause }),
        }));
        Ok(raw.into_iter().filter_map(convert).collect())
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn add(
        &mut self,
        parent: Option<u64>,
        goal: bool,
        name: &str,
        handler: &str,
        constraints: Vec<RelConstraint>,
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<(u64, Vec<TreeEvent>), String> {
        let kind = if goal {
            NodeKind::Goal
        } else {
            NodeKind::Command
        };
        let mut spec = NodeSpec::new(kind, name, handler);
        spec.parent = parent.map(NodeId);
        let mut later = Vec::new();
        for c in constraints {
            match (c.before.0, c.after.0) {
                (Who::Node(b), Who::This) => spec.constraints.push(NewConstraint::After {
                    before: Endpoint::new(NodeId(b), c.before.1),
                    point: c.after.1,
                }),
                (Who::This, Who::Node(a)) => spec.constraints.push(NewConstraint::Before {
                    point: c.before.1,
                    after: Endpoint::new(NodeId(a), c.after.1),
                }),
                (Who::Node(b), Who::Node(a)) => later.push(((b, c.before.1), (a, c.after.1))),
                (Who::This, Who::This) => {
                    later.push(((u64::MAX, c.before.1), (u64::MAX, c.after.1)))
                }
            }
        }
        let id = self.tree.next_id();
        let mut events = self.apply(TreeOp::AddNode { id, spec, now }, cause, now, out)?;
        for ((b, pb), (a, pa)) in later {
            let b = if b == u64::MAX { id.0 } else { b };
            let a = if a == u64::MAX { id.0 } else { a };
            events.extend(self.constrain((b, pb), (a, pa), now, cause, out)?);
        }
        Ok((id.0, events))
    }

    pub(super) fn constrain(
        &mut self,
        before: (u64, Point),
        after: (u64, Point),
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        let constraint = Constraint::new(
            Endpoint::new(NodeId(before.0), before.1),
            Endpoint::new(NodeId(after.0), after.1),
        );
        self.apply(TreeOp::AddConstraint { constraint, now }, cause, now, out)
    }

    pub(super) fn start(
        &mut self,
        node: u64,
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        self.apply(
            TreeOp::Start {
                node: NodeId(node),
                now,
            },
            cause,
            now,
            out,
        )
    }

    pub(super) fn finish(
        &mut self,
        node: u64,
        outcome: Result<(), String>,
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        let outcome = match outcome {
            Ok(()) => Outcome::Success,
            Err(reason) => Outcome::Failure { reason },
        };
        self.apply(
            TreeOp::Finish {
                node: NodeId(node),
                outcome,
                now,
            },
            cause,
            now,
            out,
        )
    }

    pub(super) fn kill(
        &mut self,
        node: u64,
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        self.apply(
            TreeOp::Kill {
                node: NodeId(node),
                now,
            },
            cause,
            now,
            out,
        )
    }

    /// Whether the node's handler has started (it is past waiting).
    pub(super) fn has_started(&self, node: u64) -> bool {
        self.tree
            .get(NodeId(node))
            .is_some_and(|v| v.time(Point::HandlingStart).is_some())
    }

    pub(super) fn ancestors(&self, node: u64) -> impl Iterator<Item = u64> + '_ {
        self.tree.ancestors(NodeId(node)).map(|n| n.0)
    }

    pub(super) fn suspend(
        &mut self,
        node: u64,
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        let node = NodeId(node);
        self.apply(TreeOp::Suspend { node, now }, cause, now, out)
    }

    pub(super) fn resume(
        &mut self,
        node: u64,
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        let node = NodeId(node);
        self.apply(TreeOp::Resume { node, now }, cause, now, out)
    }

    pub(super) fn retry(
        &mut self,
        node: u64,
        now: u64,
        cause: Option<u64>,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        let node = NodeId(node);
        self.apply(TreeOp::Retry { node, now }, cause, now, out)
    }

    /// Puts a node whose handler was running back to waiting, killing what its handler had
    /// created: used when the handler's module goes down, so the node is delivered again.
    /// Expressed as logged ops: suspend (so the failure is held, not propagated), finish with
    /// failure, retry, resume.
    pub(super) fn restart(
        &mut self,
        node: u64,
        now: u64,
        out: &mut Vec<Action>,
    ) -> Result<Vec<TreeEvent>, String> {
        let id = NodeId(node);
        let mut events = Vec::new();
        events.extend(self.apply(TreeOp::Suspend { node: id, now }, None, now, out)?);
        let failure = Outcome::Failure {
            reason: "its handler's module went down; it will be delivered again".into(),
        };
        events.extend(self.apply(
            TreeOp::Finish {
                node: id,
                outcome: failure,
                now,
            },
            None,
            now,
            out,
        )?);
        events.extend(self.apply(TreeOp::Retry { node: id, now }, None, now, out)?);
        events.extend(self.apply(TreeOp::Resume { node: id, now }, None, now, out)?);
        // The node's own "failed" and "cancel" events are not real: it is waiting again.
        Ok(events
            .into_iter()
            .filter(|e| !matches!(e, TreeEvent::Failed(n, _) | TreeEvent::Cancel(n) if *n == node))
            .collect())
    }
}

fn convert(raw: Raw) -> Option<TreeEvent> {
    Some(match raw {
        Raw::Ready(n) => TreeEvent::Ready(n.0),
        Raw::Achieved(n) => TreeEvent::Achieved(n.0),
        Raw::Failed { node, reason } => TreeEvent::Failed(node.0, reason),
        Raw::CancelHandler(n) => TreeEvent::Cancel(n.0),
        Raw::Killed { node, .. } => TreeEvent::Killed(node.0),
        Raw::Retired(n) => TreeEvent::Retired(n.0),
        _ => return None,
    })
}
