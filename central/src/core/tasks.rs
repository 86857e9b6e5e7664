//! Goals and commands: task-tree nodes, dispatched when their constraints hold and their
//! handler module has capacity (TCA's resource management).

use serde::{Deserialize, Serialize};
use tca_messages::control::{Cancel, ControlNotice, TaskEnded, TaskOutcome};
use tca_messages::{
    Class, ConstraintSpec, Envelope, Failure, MessageId, ModuleName, NodeId, RouteError, TaskRef,
    decode_data,
};

use super::tree::{RelConstraint, TreeEvent, Who, point};
use super::{Action, Central, LinkId};

/// A goal or command known to central.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Task {
    /// The message as sent; `node` is filled in when it is delivered.
    pub(super) envelope: Envelope,
    /// Its task-tree node.
    pub(super) node: u64,
    /// Who sent it.
    pub(super) sender: ModuleName,
    /// Who handles it.
    pub(super) handler: ModuleName,
    /// Tell the sender how it ends.
    pub(super) notify: bool,
    /// Its handler is running it.
    pub(super) running: bool,
    /// When it last became ready.
    pub(super) ready_since: u64,
    /// Whether it is a root (no parent).
    pub(super) root: bool,
    /// Why it was killed, when that is a failure (an unhandled exception).
    pub(super) failure: Option<String>,
    /// It counts against its sender's queue limits (until first dispatched).
    pub(super) charged: bool,
}

impl Central {
    pub(super) fn new_task(
        &mut self,
        link: LinkId,
        sender: ModuleName,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        let handler = match self.lookup(&envelope) {
            Ok(entry) => entry.handler.clone(),
            Err(err) => return self.send_error(link, &envelope, err, out),
        };
        if let Err(err) = self.check_room(&handler) {
            return self.send_error(link, &envelope, err, out);
        }
        if let Err(err) = self.check_quota(&sender, envelope.data.len()) {
            return self.send_error(link, &envelope, err, out);
        }
        if self.tasks.contains_key(&envelope.id) {
            let reason = format!("message id {} was already used for a task", envelope.id);
            return self.send_error(link, &envelope, RouteError::BadFrame { reason }, out);
        }
        let parent = match envelope.context {
            Some(n) if self.tree.contains(n.0) => Some(n.0),
            Some(n) => {
                // Its handler's task was killed (or has finished) meanwhile: what the handler
                // still sent is not carried out. A root task in its place would act for a plan
                // that no longer exists (a leg move planned from where the leg no longer is).
                let reason = format!(
                    "{} {} was sent in the context of task node {n}, which is no longer live \
                     (killed or finished); it was not started",
                    envelope.class, envelope.id
                );
                tracing::debug!(%reason, sender = %sender, "task refused");
                return self.send_error(link, &envelope, RouteError::Tree { reason }, out);
            }
            None => None,
        };
        let constraints = match self.relative_constraints(&envelope.options.constraints) {
            Ok(c) => c,
            Err(reason) => {
                return self.send_error(link, &envelope, RouteError::Tree { reason }, out);
            }
        };
        let is_goal = envelope.class == Class::Goal;
        let added = self.tree.add(
            parent,
            is_goal,
            envelope.name.as_str(),
            handler.as_str(),
            constraints,
            self.tree_now(),
            Some(envelope.id.0),
            out,
        );
        let (node, events) = match added {
            Ok(x) => x,
            Err(reason) => {
                return self.send_error(link, &envelope, RouteError::Tree { reason }, out);
            }
        };
        let id = envelope.id;
        self.charge(&sender, envelope.data.len());
        self.tasks.insert(
            id,
            Box::new(Task {
                notify: envelope.options.notify,
                envelope,
                node,
                sender,
                handler,
                running: false,
                ready_since: self.now,
                root: parent.is_none(),
                failure: None,
                charged: true,
            }),
        );
        self.node_task.insert(node, id);
        self.tree_events(events, out);
    }

    /// Translates wire constraints into tree constraints relative to a new node.
    fn relative_constraints(
        &mut self,
        specs: &[ConstraintSpec],
    ) -> Result<Vec<RelConstraint>, String> {
        let mut result = Vec::with_capacity(specs.len());
        for spec in specs {
            let before = self.who(spec.before.task)?;
            let after = self.who(spec.after.task)?;
            match (before, after) {
                (Some(b), Some(a)) => result.push(RelConstraint {
                    before: (b, point(spec.before.point)),
                    after: (a, point(spec.after.point)),
                }),
                _ => {
                    // A task that has finished (and been forgotten) passed every point it
                    // had, at its end: the constraint holds already.
                    tracing::debug!(constraint = ?spec, "constraint on a finished task holds already");
                }
            }
        }
        Ok(result)
    }

    /// Resolves a task reference: `Ok(None)` for a finished, forgotten task.
    fn who(&self, task: TaskRef) -> Result<Option<Who>, String> {
        match task {
            TaskRef::This => Ok(Some(Who::This)),
            TaskRef::Node(n) if self.tree.contains(n.0) => Ok(Some(Who::Node(n.0))),
            TaskRef::Node(n) if self.tree.was_retired(n.0) => Ok(None),
            TaskRef::Node(n) => Err(format!("node {n} does not exist")),
            TaskRef::Message(id) => match self.tasks.get(&id) {
                Some(t) => Ok(Some(Who::Node(t.node))),
                None => Ok(None),
            },
        }
    }

    /// Adds a constraint between existing nodes (`tca.constrain`).
    pub(super) fn add_constraint(
        &mut self,
        spec: ConstraintSpec,
        _this: Option<u64>,
        cause: Option<MessageId>,
        out: &mut Vec<Action>,
    ) -> Result<(), String> {
        let before = self.who(spec.before.task)?;
        let after = self.who(spec.after.task)?;
        let (Some(Who::Node(b)), Some(Who::Node(a))) = (before, after) else {
            return Err(
                "a constraint added later must name two existing nodes (This is only for sends)"
                    .into(),
            );
        };
        let events = self.tree.constrain(
            (b, point(spec.before.point)),
            (a, point(spec.after.point)),
            self.tree_now(),
            cause.map(|m| m.0),
            out,
        )?;
        self.tree_events(events, out);
        Ok(())
    }

    /// Kills a node and its subtree (`tca.kill`).
    pub(super) fn kill_node(
        &mut self,
        node: NodeId,
        cause: Option<MessageId>,
        out: &mut Vec<Action>,
    ) -> Result<(), String> {
        let events = self
            .tree
            .kill(node.0, self.tree_now(), cause.map(|m| m.0), out)?;
        self.tree_events(events, out);
        Ok(())
    }

    /// A handler ended a goal, command or query.
    pub(super) fn handler_done(
        &mut self,
        link: LinkId,
        module: ModuleName,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        let Some(id) = envelope.correlation else {
            let reason = format!("{} must name what it ends (correlation)", envelope.class);
            return self.send_error(link, &envelope, RouteError::BadFrame { reason }, out);
        };
        if self.queries.contains_key(&id) && envelope.class == Class::Failure {
            return self.forward_answer(link, module, id, envelope, out);
        }
        if self.exceptions.contains_key(&id) {
            let outcome = if envelope.class == Class::Success {
                Ok(())
            } else {
                Err(decode_data::<Failure>(&envelope.data)
                    .map(|f| f.reason)
                    .unwrap_or_else(|e| format!("failure with unreadable reason: {e}")))
            };
            return self.exception_done(module, id, outcome, out);
        }
        if self.late.take(id, &module) {
            tracing::debug!(%module, %id, "end of a task that was stopped while its handler ran; dropped");
            return;
        }
        if envelope.class == Class::Success
            && self
                .registry
                .get(&envelope.name)
                .is_some_and(|e| e.class == Class::Inform)
        {
            // The end of an inform's handler, told on the simulated clock: nothing to route.
            tracing::debug!(%module, %id, "inform handled");
            return;
        }
        let Some(task) = self.tasks.get(&id) else {
            let reason = format!("{} ends {id}, which is not a live task", envelope.class);
            return self.problem(Some(link), Some(module), reason, &[], out);
        };
        if task.handler != module || !task.running {
            // A task killed (or moved to a replacement) while its handler ran: the late end is
            // recorded and ignored.
            let reason = format!(
                "{} ends {id}, which module {module} is not running (killed or reassigned)",
                envelope.class
            );
            return self.problem(Some(link), Some(module), reason, &[], out);
        }
        let node = task.node;
        let outcome = if envelope.class == Class::Success {
            Ok(())
        } else {
            Err(decode_data::<Failure>(&envelope.data)
                .map(|f| f.reason)
                .unwrap_or_else(|e| format!("failure with unreadable reason: {e}")))
        };
        if let Some(t) = self.tasks.get_mut(&id) {
            t.running = false;
        }
        if let Some(m) = self.modules.get_mut(&module) {
            m.running = m.running.saturating_sub(1);
        }
        match self
            .tree
            .finish(node, outcome, self.tree_now(), Some(id.0), out)
        {
            Ok(events) => self.tree_events(events, out),
            Err(reason) => self.problem(Some(link), Some(module.clone()), reason, &[], out),
        }
        self.dispatch(&module, out);
    }

    /// Starts ready tasks of `module` while it has capacity (and reads what it is sent).
    pub(super) fn dispatch(&mut self, module: &ModuleName, out: &mut Vec<Action>) {
        loop {
            let Some(link) = self.work_link(module) else {
                return;
            };
            let Some(state) = self.modules.get_mut(module) else {
                return;
            };
            if state.running >= state.capacity {
                return;
            }
            let Some(id) = state.ready.pop_front() else {
                return;
            };
            let Some(task) = self.tasks.get(&id) else {
                continue;
            };
            if task.running || &task.handler != module || !self.tree.is_ready(task.node) {
                continue;
            }
            let node = task.node;
            let events = match self.tree.start(node, self.tree_now(), Some(id.0), out) {
                Ok(ev) => ev,
                Err(reason) => {
                    self.problem(None, Some(module.clone()), reason, &[], out);
                    continue;
                }
            };
            if let Some(m) = self.modules.get_mut(module) {
                m.running += 1;
            }
            // Send the stored envelope with its node filled in, without copying it.
            let Some(mut task) = self.tasks.remove(&id) else {
                continue;
            };
            task.running = true;
            if task.charged {
                task.charged = false;
                self.refund(&task.sender, task.envelope.data.len());
            }
            task.envelope.node = Some(NodeId(node));
            task.envelope.timestamp_ns = task.envelope.timestamp_ns.max(self.cause_stamp);
            // Delivered (again): its end is expected, not late.
            self.late.take(id, &task.handler);
            self.send(link, &task.envelope, out);
            self.tasks.insert(id, task);
            self.tree_events(events, out);
            self.monitors_node_started(node, out);
        }
    }

    /// A module went down: the tasks it was running go back to wait for it (or a replacement),
    /// with their descendants killed, and are delivered again marked as redeliveries.
    pub(super) fn requeue_tasks_of(&mut self, module: &ModuleName, out: &mut Vec<Action>) {
        let mut running: Vec<(MessageId, u64)> = self
            .tasks
            .iter()
            .filter(|(_, t)| &t.handler == module && t.running)
            .map(|(id, t)| (*id, t.node))
            .collect();
        running.sort();
        for (id, node) in running {
            if let Some(t) = self.tasks.get_mut(&id) {
                t.running = false;
                t.envelope.redelivery += 1;
            }
            match self.tree.restart(node, self.tree_now(), out) {
                Ok(events) => self.tree_events(events, out),
                Err(reason) => self.problem(None, Some(module.clone()), reason, &[], out),
            }
        }
    }

    /// A ready task waited too long for its module: it is killed and its sender told.
    pub(super) fn expire_task(
        &mut self,
        id: MessageId,
        module: &ModuleName,
        limit_ns: u64,
        out: &mut Vec<Action>,
    ) {
        let Some(task) = self.tasks.get(&id) else {
            return;
        };
        let waited = self.now.saturating_sub(task.ready_since);
        let (sender, envelope, node) = (task.sender.clone(), task.envelope.clone(), task.node);
        let error = RouteError::Expired {
            module: module.to_string(),
            waited_ms: waited / 1_000_000,
            limit_ms: limit_ns / 1_000_000,
        };
        self.send_error_to_module(&sender, &envelope, error, out);
        if let Ok(events) = self.tree.kill(node, self.tree_now(), Some(id.0), out) {
            self.tree_events(events, out);
        }
    }

    /// Acts on what the tree reports.
    pub(super) fn tree_events(&mut self, events: Vec<TreeEvent>, out: &mut Vec<Action>) {
        let mut touched: Vec<ModuleName> = Vec::new();
        for event in events {
            match event {
                TreeEvent::Ready(node) => {
                    let Some(id) = self.node_task.get(&node).copied() else {
                        continue;
                    };
                    let now = self.now;
                    let Some(task) = self.tasks.get_mut(&id) else {
                        continue;
                    };
                    task.ready_since = now;
                    let handler = task.handler.clone();
                    if let Some(m) = self.modules.get_mut(&handler) {
                        m.ready.push_back(id);
                    }
                    if !touched.contains(&handler) {
                        touched.push(handler);
                    }
                }
                TreeEvent::Achieved(node) => {
                    self.monitors_node_ended(node);
                    self.task_ended(node, TaskOutcome::Achieved, out)
                }
                TreeEvent::Failed(node, reason) => {
                    self.task_ended(node, TaskOutcome::Failed(reason), out);
                }
                TreeEvent::Cancel(node) => self.stop_running(node, &mut touched, out),
                TreeEvent::Killed(node) => {
                    self.monitors_node_ended(node);
                    self.stop_running(node, &mut touched, out);
                    self.task_ended(node, TaskOutcome::Killed, out);
                }
                TreeEvent::Retired(node) => {
                    if let Some(id) = self.node_task.remove(&node)
                        && let Some(task) = self.tasks.remove(&id)
                        && task.charged
                    {
                        self.refund(&task.sender, task.envelope.data.len());
                    }
                    self.forget_node(node);
                    self.monitors_node_ended(node);
                }
            }
        }
        for module in touched {
            self.dispatch(&module, out);
        }
    }

    /// A node stopped (killed or failed by propagation) while its handler may be running: the
    /// handler is told to stop and its capacity is freed.
    fn stop_running(&mut self, node: u64, touched: &mut Vec<ModuleName>, out: &mut Vec<Action>) {
        let Some(id) = self.node_task.get(&node).copied() else {
            return;
        };
        let Some(task) = self.tasks.get_mut(&id) else {
            return;
        };
        let handler = task.handler.clone();
        if let Some(m) = self.modules.get_mut(&handler) {
            m.ready.retain(|x| *x != id);
        }
        if !task.running {
            return;
        }
        task.running = false;
        // Its handler may end it before the cancel arrives.
        self.late.expect(id, handler.clone());
        self.clock.end(id);
        let Some(state) = self.modules.get_mut(&handler) else {
            return;
        };
        state.running = state.running.saturating_sub(1);
        if let Some(link) = state.link {
            let cancel = ControlNotice::Cancel(Cancel { node: NodeId(node) });
            let env = self.notice_envelope(&cancel, Some(id));
            self.send(link, &env, out);
        }
        if !touched.contains(&handler) {
            touched.push(handler);
        }
    }

    /// Tells the sender how a task ended, if it asked, and the originator of a root that failed.
    fn task_ended(&mut self, node: u64, outcome: TaskOutcome, out: &mut Vec<Action>) {
        let Some(id) = self.node_task.get(&node).copied() else {
            return;
        };
        let Some(task) = self.tasks.get(&id) else {
            return;
        };
        let outcome = match (&task.failure, outcome) {
            (Some(reason), TaskOutcome::Killed) => TaskOutcome::Failed(reason.clone()),
            (_, o) => o,
        };
        let tell = task.notify || (task.root && !matches!(outcome, TaskOutcome::Achieved));
        if !tell {
            return;
        }
        if task.notify {
            // Told now if its sender is here; asked for later if it was away.
            let sender = task.sender.clone();
            self.ends.ended(id, sender, outcome.clone());
        }
        let Some(task) = self.tasks.get(&id) else {
            return;
        };
        let Some(link) = self.modules.get(&task.sender).and_then(|m| m.link) else {
            return;
        };
        let ended = ControlNotice::TaskEnded(TaskEnded {
            node: NodeId(node),
            outcome,
        });
        let mut env = self.notice_envelope(&ended, Some(id));
        // On the clock of the message that ended it (simulated time for simulations).
        env.timestamp_ns = self.cause_stamp;
        self.send(link, &env, out);
    }
}
