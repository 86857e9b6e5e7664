//! Exceptions (§3.2): a handler raises a named exception in the context of its task node;
//! central suspends dispatch in that node's subtree and routes the exception to the nearest
//! exception handler attached for that name on the node or an ancestor.
//!
//! Protocol, as modules see it:
//! - a module that can handle exception `E` registers `E` (class exception) and attaches itself
//!   to task nodes with `tca.onException { node, name }` (typically the node its own goal
//!   handler runs for);
//! - the exception is delivered with `node` = the node it was attached at and `context` = the
//!   node that raised it; the handler may kill or retry nodes, add nodes (send goals in the
//!   context of the attachment node: patching the plan; add new nodes *before* killing the
//!   failed ones, or a parent left with no unfinished child is achieved at once), then ends the
//!   exception with
//!   **success** (handled: dispatch resumes; a failure of the raising node that was held during
//!   the exception now propagates unless the handler killed or retried it) or **failure** (pass
//!   it up: the search goes on above the attachment node);
//! - nobody handles it up to the root: the whole tree is killed and its originator is told that
//!   it failed, with the exception's name and reason.

use rustc_hash::FxHashMap as HashMap;

use tca_messages::control::{OnException, Retry};
use tca_messages::{Class, Envelope, MessageId, MessageName, ModuleName, RouteError};

use super::waiting::Waiting;
use super::{Action, Central, LinkId};

/// Exception handlers attached to nodes: node -> (exception name, module).
pub(super) type Attachments = HashMap<u64, Vec<(MessageName, ModuleName)>>;

/// An exception being handled.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct OpenException {
    /// The exception as raised.
    envelope: Envelope,
    /// The node that raised it (suspended while it is handled).
    raised_at: u64,
    /// The node whose attached handler has it now.
    at: u64,
    /// The module handling it now.
    handler: ModuleName,
    /// Why the handlers that passed it up did so.
    passed: Vec<(ModuleName, String)>,
}

impl Central {
    /// A handler raised an exception.
    pub(super) fn raise(
        &mut self,
        link: LinkId,
        module: ModuleName,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        let Some(node) = envelope
            .context
            .map(|n| n.0)
            .filter(|n| self.tree.contains(*n))
        else {
            let reason = format!(
                "exception {} was raised outside a live task node; raise exceptions from the \
                 handler of a goal or command (its context)",
                envelope.name
            );
            return self.send_error(link, &envelope, RouteError::Refused { reason }, out);
        };
        let _ = module;
        self.raise_internal(envelope, node, out);
    }

    /// Suspends the raising node and routes the exception (also used by monitors).
    pub(super) fn raise_internal(&mut self, envelope: Envelope, node: u64, out: &mut Vec<Action>) {
        if let Err(reason) = self
            .tree
            .suspend(node, self.tree_now(), Some(envelope.id.0), out)
        {
            self.problem(None, Some(envelope.sender.clone()), reason, &[], out);
        }
        tracing::info!(exception = %envelope.name, node, "exception raised");
        self.route_exception(envelope, node, Some(node), Vec::new(), out);
    }

    /// Looks for a handler from `from` upwards; delivers, or fails the tree.
    fn route_exception(
        &mut self,
        envelope: Envelope,
        raised_at: u64,
        from: Option<u64>,
        passed: Vec<(ModuleName, String)>,
        out: &mut Vec<Action>,
    ) {
        let mut chain: Vec<u64> = Vec::new();
        if let Some(start) = from {
            chain.push(start);
            chain.extend(self.tree.ancestors(start));
        }
        let found = chain.into_iter().find_map(|n| {
            self.attachments.get(&n).and_then(|list| {
                list.iter()
                    .find(|(name, _)| name == &envelope.name)
                    .map(|(_, m)| (n, m.clone()))
            })
        });
        let Some((at, handler)) = found else {
            return self.unhandled(envelope, raised_at, &passed, out);
        };
        let mut delivery = envelope.clone();
        delivery.node = Some(tca_messages::NodeId(at));
        delivery.context = Some(tca_messages::NodeId(raised_at));
        self.exceptions.insert(
            envelope.id,
            OpenException {
                envelope,
                raised_at,
                at,
                handler: handler.clone(),
                passed,
            },
        );
        match self.modules.get(&handler).and_then(|m| m.link) {
            Some(link) => self.send(link, &delivery, out),
            None => {
                if let Err(err) = self.hold(&handler, Waiting::new(delivery.clone(), self.now)) {
                    let reason = format!("its handler module {handler} is down: {err}");
                    self.exceptions.remove(&delivery.id);
                    self.fail_tree_of(raised_at, &delivery, reason, out);
                }
            }
        }
    }

    /// The exception's handler ended it.
    pub(super) fn exception_done(
        &mut self,
        module: ModuleName,
        id: MessageId,
        outcome: Result<(), String>,
        out: &mut Vec<Action>,
    ) {
        let Some(open) = self.exceptions.remove(&id) else {
            return;
        };
        if open.handler != module {
            self.exceptions.insert(id, open);
            return;
        }
        match outcome {
            Ok(()) => {
                tracing::info!(exception = %open.envelope.name, node = open.at, "exception handled");
                self.resume_after_exception(open.raised_at, id, out);
            }
            Err(reason) => {
                // Passed up: go on above the node it was attached at.
                let mut passed = open.passed;
                passed.push((open.handler.clone(), reason));
                let above = self.tree.ancestors(open.at).next();
                match above {
                    Some(parent) => self.route_exception(
                        open.envelope,
                        open.raised_at,
                        Some(parent),
                        passed,
                        out,
                    ),
                    None => self.unhandled(open.envelope, open.raised_at, &passed, out),
                }
            }
        }
    }

    fn resume_after_exception(&mut self, node: u64, cause: MessageId, out: &mut Vec<Action>) {
        if !self.tree.contains(node) {
            return; // killed or retired by the handler
        }
        match self.tree.resume(node, self.tree_now(), Some(cause.0), out) {
            Ok(events) => self.tree_events(events, out),
            Err(reason) => tracing::debug!(%reason, "resume after exception"),
        }
    }

    /// Nobody handles it: the whole tree fails and its originator is told.
    fn unhandled(
        &mut self,
        envelope: Envelope,
        raised_at: u64,
        passed: &[(ModuleName, String)],
        out: &mut Vec<Action>,
    ) {
        let data = self
            .registry
            .get(&envelope.name)
            .and_then(|e| e.format.decode_value(&envelope.data).ok())
            .map(|v| format!(": {v}"))
            .unwrap_or_default();
        // The last handler's reason says most (it saw the exception in context); the
        // exception itself and who passed it up follow.
        let origin = format!(
            "unhandled exception {} raised by {} at node n{raised_at}",
            envelope.name, envelope.sender
        );
        let reason = match passed.split_last() {
            None => format!("{origin}{data}"),
            Some((last, earlier)) => {
                let mut handlers: Vec<&str> = earlier.iter().map(|(m, _)| m.as_str()).collect();
                handlers.push(last.0.as_str());
                format!(
                    "{} ({origin}, passed up by {})",
                    last.1,
                    handlers.join(", ")
                )
            }
        };
        tracing::info!(%reason, "task tree failed");
        self.fail_tree_of(raised_at, &envelope, reason, out);
    }

    fn fail_tree_of(&mut self, node: u64, cause: &Envelope, reason: String, out: &mut Vec<Action>) {
        let root = self.tree.ancestors(node).last().unwrap_or(node);
        if let Some(id) = self.node_task.get(&root).copied()
            && let Some(task) = self.tasks.get_mut(&id)
        {
            task.failure = Some(reason.clone());
        }
        self.record_problem(None, Some(cause.sender.clone()), reason, &[], out);
        match self.tree.kill(root, self.tree_now(), Some(cause.id.0), out) {
            Ok(events) => self.tree_events(events, out),
            Err(reason) => tracing::debug!(%reason, "kill after unhandled exception"),
        }
    }

    /// `tca.onException`: attach the sender as handler of an exception on a node.
    pub(super) fn attach_exception_handler(
        &mut self,
        module: &ModuleName,
        on: OnException,
    ) -> Result<(), String> {
        match self.registry.get(&on.name) {
            Some(e) if e.class == Class::Exception && &e.handler == module => {}
            _ => {
                return Err(format!(
                    "module {module} must register exception {} (class exception) before \
                     attaching to nodes",
                    on.name
                ));
            }
        }
        if !self.tree.contains(on.node.0) {
            return Err(format!("node {} is not live", on.node));
        }
        let list = self.attachments.entry(on.node.0).or_default();
        if !list.iter().any(|(n, m)| n == &on.name && m == module) {
            list.push((on.name, module.clone()));
        }
        Ok(())
    }

    /// `tca.retry`: put a node back to waiting (after a failure held by an exception).
    pub(super) fn retry_node(
        &mut self,
        request: &Envelope,
        retry: Retry,
        out: &mut Vec<Action>,
    ) -> Result<(), String> {
        let events = self
            .tree
            .retry(retry.node.0, self.tree_now(), Some(request.id.0), out)?;
        if let Some(id) = self.node_task.get(&retry.node.0).copied()
            && let Some(t) = self.tasks.get_mut(&id)
        {
            t.running = false;
            t.envelope.redelivery += 1;
        }
        self.tree_events(events, out);
        Ok(())
    }

    /// The module handling some exceptions went down: they are delivered again when it returns.
    pub(super) fn requeue_exceptions_of(&mut self, module: &ModuleName) {
        let now = self.now;
        let mut open: Vec<&OpenException> = self
            .exceptions
            .values()
            .filter(|e| &e.handler == module)
            .collect();
        open.sort_unstable_by_key(|e| e.envelope.id);
        let mine: Vec<Envelope> = open
            .into_iter()
            .map(|e| {
                let mut d = e.envelope.clone();
                d.node = Some(tca_messages::NodeId(e.at));
                d.context = Some(tca_messages::NodeId(e.raised_at));
                d.redelivery += 1;
                d
            })
            .collect();
        if let Some(state) = self.modules.get_mut(module) {
            for d in mine {
                state.waiting.push_back(Waiting::new(d, now));
            }
        }
    }

    /// Forgets attachments of a node that left the tree.
    pub(super) fn forget_node(&mut self, node: u64) {
        self.attachments.remove(&node);
    }
}
