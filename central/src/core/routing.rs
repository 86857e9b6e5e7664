//! Queries, informs and exceptions: routed by name; and the replies that answer queries.

use serde::Serialize;
use tca_messages::control::{ControlError, ControlRequest, TreeView};
use tca_messages::{Class, Envelope, MessageId, MessageName, ModuleName, RouteError, encode_data};

use super::waiting::Waiting;
use super::{Action, Central, LinkId};

/// A query on its way to its handler or waiting for the reply.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct OpenQuery {
    pub(super) asker: ModuleName,
    pub(super) handler: ModuleName,
    pub(super) name: MessageName,
}

impl Central {
    /// Queries, informs and exceptions go to the module registered for their name.
    pub(super) fn route_by_name(
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
        if envelope.class == Class::Query {
            self.queries.insert(
                envelope.id,
                OpenQuery {
                    asker: sender,
                    handler: handler.clone(),
                    name: envelope.name.clone(),
                },
            );
        }
        self.deliver_or_wait(link, &handler, envelope, out);
    }

    /// Sends to the handler if it is connected and keeping up, else holds the message (within
    /// bounds).
    fn deliver_or_wait(
        &mut self,
        sender_link: LinkId,
        handler: &ModuleName,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        match self.work_link(handler) {
            Some(hlink) => self.send(hlink, &envelope, out),
            None => {
                if let Err(err) = self.hold(handler, Waiting::new(envelope.clone(), self.now)) {
                    self.queries.remove(&envelope.id);
                    self.send_error(sender_link, &envelope, err, out);
                }
            }
        }
    }

    /// A handler's reply to a query goes back to the module that asked.
    pub(super) fn answer_query(
        &mut self,
        link: LinkId,
        module: ModuleName,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        let Some(query_id) = envelope.correlation else {
            let reason = "a reply must name the query it answers (correlation)".to_owned();
            return self.send_error(link, &envelope, RouteError::BadFrame { reason }, out);
        };
        self.forward_answer(link, module, query_id, envelope, out);
    }

    /// Forwards a reply or a query failure to the asker.
    pub(super) fn forward_answer(
        &mut self,
        link: LinkId,
        module: ModuleName,
        query_id: MessageId,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        match self.queries.get(&query_id) {
            Some(q) if q.handler == module => {}
            Some(_) | None if self.late.take(query_id, &module) => {
                tracing::debug!(%module, %query_id, "answer to a query whose asker went down; dropped");
                return;
            }
            Some(_) | None => {
                // Other late answers (the asker gave up) are reported and dropped.
                let reason = format!(
                    "{} answers query {query_id}, which is not open for module {module}",
                    envelope.class
                );
                self.problem(Some(link), Some(module), reason, &[], out);
                return;
            }
        }
        let Some(q) = self.queries.remove(&query_id) else {
            return;
        };
        if self.is_central(&q.asker) {
            return self.monitor_answer(query_id, envelope, out);
        }
        if let Some(asker_link) = self.modules.get(&q.asker).and_then(|m| m.link) {
            self.send(asker_link, &envelope, out);
        }
    }

    /// Every query a module was handling, or held for it, fails at once when it goes down.
    pub(super) fn fail_queries_of(&mut self, module: &ModuleName, out: &mut Vec<Action>) {
        // Queries the dead module asked: nobody waits for their answers any more.
        let orphaned: Vec<(MessageId, ModuleName)> = self
            .queries
            .iter()
            .filter(|(_, q)| &q.asker == module)
            .map(|(id, q)| (*id, q.handler.clone()))
            .collect();
        let mut orphaned = orphaned;
        orphaned.sort_unstable_by_key(|(id, _)| *id);
        for (id, handler) in orphaned {
            self.queries.remove(&id);
            self.late.expect(id, handler);
        }
        // Queries sent to the dead module: tell each asker now.
        let held: std::collections::HashSet<MessageId> = self
            .modules
            .get(module)
            .map(|m| m.waiting.iter().map(|w| w.envelope.id).collect())
            .unwrap_or_default();
        let lost: Vec<(MessageId, ModuleName, MessageName)> = self
            .queries
            .iter()
            .filter(|(id, q)| &q.handler == module && !held.contains(id))
            .map(|(id, q)| (*id, q.asker.clone(), q.name.clone()))
            .collect();
        let mut lost = lost;
        lost.sort_unstable_by_key(|(id, _, _)| *id);
        for (id, asker, name) in lost {
            self.queries.remove(&id);
            let Some(link) = self.modules.get(&asker).and_then(|m| m.link) else {
                continue;
            };
            let error = RouteError::HandlerDied {
                module: module.to_string(),
            };
            let data = encode_data(&error).unwrap_or_default();
            let env = self.central_envelope(Class::Error, name, Some(id), data);
            self.counters.errors_sent += 1;
            self.send(link, &env, out);
        }
    }

    /// Central's own control requests.
    pub(super) fn control(
        &mut self,
        link: LinkId,
        module: ModuleName,
        envelope: Envelope,
        out: &mut Vec<Action>,
    ) {
        let request = match ControlRequest::decode(envelope.name.as_str(), &envelope.data) {
            Ok(request) => request,
            Err(err @ ControlError::Unknown { .. }) => {
                let reason = err.to_string();
                return self.send_error(link, &envelope, RouteError::Refused { reason }, out);
            }
            Err(err) => {
                let reason = err.to_string();
                return self.send_error(link, &envelope, RouteError::BadFrame { reason }, out);
            }
        };
        let done: Result<(), RouteError> = match request {
            ControlRequest::Hello(_) | ControlRequest::HelloAuth(_) => Err(RouteError::BadFrame {
                reason: format!(
                    "module {module} is already connected; a hello is the first frame on a \
                     link only"
                ),
            }),
            ControlRequest::Register(register) => {
                return self.register(link, module, &envelope, register, out);
            }
            ControlRequest::Registry => {
                let view = self.registry_view();
                self.reply_control(link, &envelope, &view, out);
                return;
            }
            ControlRequest::Bye => {
                self.reply_control(link, &envelope, &(), out);
                return self.bye(link, out);
            }
            ControlRequest::TaskStatus(request) => {
                let status = self.task_status(&module, request);
                self.reply_control(link, &envelope, &status, out);
                return;
            }
            ControlRequest::Tree => {
                let view = TreeView {
                    text: self.tree.render(),
                    nodes: self.tree.len() as u64,
                };
                self.reply_control(link, &envelope, &view, out);
                return;
            }
            ControlRequest::Kill(kill) => self
                .kill_node(kill.node, Some(envelope.id), out)
                .map_err(|reason| RouteError::Tree { reason }),
            ControlRequest::KillTask(kill) => self
                .kill_task(kill.task, Some(envelope.id), out)
                .map_err(|reason| RouteError::Tree { reason }),
            ControlRequest::KillAll => {
                let killed = self.kill_all(Some(envelope.id), out);
                self.reply_control(link, &envelope, &killed, out);
                return;
            }
            ControlRequest::Tap(tap) => self
                .set_tap(&module, tap)
                .map_err(|reason| RouteError::Refused { reason }),
            ControlRequest::OnException(on) => self
                .attach_exception_handler(&module, on)
                .map_err(|reason| RouteError::Refused { reason }),
            ControlRequest::Monitor(monitor) => self
                .add_monitor(&module, monitor, out)
                .map_err(|reason| RouteError::Refused { reason }),
            ControlRequest::Retry(retry) => self
                .retry_node(&envelope, retry, out)
                .map_err(|reason| RouteError::Tree { reason }),
            ControlRequest::Constrain(c) => self
                .add_constraint(c.constraint, None, Some(envelope.id), out)
                .map_err(|reason| RouteError::Tree { reason }),
            other => Err(RouteError::Refused {
                reason: format!("{} is not handled by this central", other.kind()),
            }),
        };
        match done {
            Ok(()) => self.reply_control(link, &envelope, &(), out),
            Err(error) => self.send_error(link, &envelope, error, out),
        }
    }

    /// Answers a control request with a `Reply` carrying `value`.
    pub(super) fn reply_control<T: Serialize>(
        &mut self,
        link: LinkId,
        request: &Envelope,
        value: &T,
        out: &mut Vec<Action>,
    ) {
        let data = encode_data(value).unwrap_or_default();
        let env = self.central_envelope(Class::Reply, request.name.clone(), Some(request.id), data);
        self.send(link, &env, out);
    }
}
