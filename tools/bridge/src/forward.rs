//! Forwarding, message class by class.
//!
//! On the side a message leaves, the bridge's handler for its name takes it:
//!
//! - an **inform** crosses and the handler ends;
//! - a **query** crosses and the handler waits for the reply (or failure) to come back, at
//!   most the delay up and down plus the query's own timeout on the far side
//!   ([`BridgeConfig::answer_within`](crate::BridgeConfig::answer_within));
//! - a **goal** or **command** crosses and the handler waits for its outcome: the task on
//!   this side ends as the far copy ended (achieved, or failed with the far side's reason).
//!   If this side's task is killed while it waits, a kill crosses after it and kills the far
//!   copy. A goal or command delivered again (the bridge restarted while it was under way)
//!   fails at once: whether the far side carried it out is not known, and it is not carried
//!   out twice;
//! - an **exception** raised on this side inside a task the bridge carries out here crosses
//!   and is raised again in the context of that task's origin on the other side; here it
//!   counts as handled.
//!
//! On the far side, once its delay has passed:
//!
//! - a goal or command is carried out under a goal `NAME.carry` that the bridge sends itself:
//!   the carry's handler attaches the bridge to the exceptions that cross from this side,
//!   sends the message as its child and ends as the child ends, and its outcome crosses
//!   back;
//! - a query is asked with its own timeout and the answer crosses back;
//! - an inform is sent; an exception is raised in its task's context; an answer is handed to
//!   the handler waiting for it; a kill kills the carry (and so the task under it).

use std::sync::{Arc, Weak};

use tca_logs::Direction as Way;
use tca_messages::control::TaskOutcome;
use tca_messages::{Class, MessageId, MessageName, ModuleName, decode_data, encode_data, now_ns};
use tca_module::{Context, HandlerError, Module, ModuleError};
use tokio::sync::oneshot;

use crate::bridge::{Carried, Carry, Core, Waiting, lock};
use crate::crossing::{Answer, Crossing, Payload};
use crate::log::side_module;
use crate::side::{Direction, Side};

type Handled = Result<Vec<u8>, HandlerError>;

fn stopping() -> HandlerError {
    HandlerError::new("the bridge is stopping; nothing more crosses")
}

impl Core {
    /// A message left `direction.from()`: logged as come in, and into the delay line.
    pub(crate) fn cross(
        &self,
        id: u32,
        direction: Direction,
        sender: ModuleName,
        cause: Option<MessageId>,
        payload: Payload,
    ) {
        let crossing = Crossing {
            id,
            direction,
            sender,
            received: std::time::Instant::now(),
            received_ns: now_ns(),
            payload,
        };
        if let Some(log) = &self.log {
            let envelope = crossing.log_envelope(cause, crossing.received_ns);
            log.frame(Way::In, direction.from(), &envelope, crossing.received_ns);
        }
        self.enqueue(crossing);
    }

    /// A crossing was handed to the far side (`cause`: its id there): measured and logged.
    pub(crate) fn released(&self, crossing: &Crossing, cause: Option<MessageId>) {
        let delay = crossing.received.elapsed().as_secs_f64();
        self.measured(crossing.direction, delay);
        if let Some(log) = &self.log {
            let at = now_ns();
            let envelope = crossing.log_envelope(cause, at);
            log.frame(Way::Out, crossing.direction.to(), &envelope, at);
        }
    }

    /// Waits for the answer to crossing `id`, which `ctx`'s handler sends.
    fn wait_answer(&self, id: u32, ctx: &Context) -> oneshot::Receiver<Answer> {
        let (tx, rx) = oneshot::channel();
        lock(&self.waiting).insert(
            id,
            Waiting {
                tx,
                handler: ctx.module().clone(),
                request: ctx.message_id(),
            },
        );
        rx
    }

    /// Sends request `request`'s answer back the way it came.
    fn answer(&self, request: &Crossing, answer: Answer) {
        let carried = lock(&self.carried).remove(&request.id);
        // An exception raised in the task can still come until now (see `carry`).
        if let Some(key) = carried.as_ref().and_then(|k| k.node) {
            lock(&self.carry_nodes).remove(&key);
        }
        let child = carried.and_then(|k| k.child);
        let name = request.payload.name().clone();
        let sender = self
            .handlers
            .get(&name)
            .cloned()
            .unwrap_or_else(|| side_module(request.direction.to()));
        self.cross(
            self.next_id(),
            request.direction.reverse(),
            sender,
            child,
            Payload::Answer {
                request: request.id,
                name,
                answer,
            },
        );
    }

    /// A crossing's time has come: hands it to the far side.
    pub(crate) fn release(self: &Arc<Self>, crossing: Crossing) {
        let to = crossing.direction.to();
        let Some(half) = self.half(to).cloned() else {
            let text = format!(
                "{} could not be handed to the {to} side: the bridge is not joined to it",
                crossing.payload.name()
            );
            if matches!(
                crossing.payload,
                Payload::Task { .. } | Payload::Query { .. }
            ) {
                self.answer(&crossing, Answer::Failed(text));
            } else {
                self.problem(Some(to), text);
            }
            return;
        };
        match &crossing.payload {
            Payload::Task { .. } => self.release_task(half, crossing),
            Payload::Query { .. } => {
                self.released(&crossing, None);
                tokio::spawn(self.clone().release_query(half, crossing));
            }
            Payload::Inform { name, data } => {
                match half.send_raw(Class::Inform, name.as_str(), data.clone(), []) {
                    Ok(id) => self.released(&crossing, Some(id)),
                    Err(e) => self.problem(
                        Some(to),
                        format!("inform {name} could not be handed to the {to} side: {e}"),
                    ),
                }
            }
            Payload::Exception { task, name, data } => {
                let handler = lock(&self.waiting).get(task).map(|w| w.handler.clone());
                let Some(handler) = handler else {
                    return self.problem(
                        Some(to),
                        format!(
                            "exception {name} came across for a task that has ended on the {to} \
                             side; dropped"
                        ),
                    );
                };
                match handler.send_raw(Class::Exception, name.as_str(), data.clone(), []) {
                    Ok(id) => self.released(&crossing, Some(id)),
                    Err(e) => self.problem(
                        Some(to),
                        format!("exception {name} could not be raised on the {to} side: {e}"),
                    ),
                }
            }
            Payload::Answer { request, .. } => {
                let waiting = lock(&self.waiting).remove(request);
                match waiting {
                    Some(w) => {
                        self.released(&crossing, Some(w.request));
                        if let Payload::Answer { answer, .. } = crossing.payload {
                            let _ = w.tx.send(answer);
                        }
                    }
                    None => tracing::debug!(
                        name = %crossing.payload.name(),
                        "an answer came back for a request nobody waits for any more (killed or timed out)"
                    ),
                }
            }
            Payload::Kill { task, name } => {
                let carry = lock(&self.carried).get(task).and_then(|k| k.carry);
                match carry {
                    Some(id) => {
                        self.released(&crossing, Some(id));
                        let name = name.clone();
                        tokio::spawn(async move {
                            if let Err(e) = half.kill_task(id).await {
                                tracing::debug!(%name, error = %e, "the far copy had ended before the kill came");
                            }
                        });
                    }
                    None => tracing::debug!(%name, "a kill came for a task that has ended"),
                }
            }
        }
    }

    /// Sends the carry of a goal or command; its outcome crosses back.
    fn release_task(self: &Arc<Self>, half: Module, crossing: Crossing) {
        let to = crossing.direction.to();
        let name = crossing.payload.name().to_string();
        let data = match encode_data(&Carry {
            crossing: crossing.id,
            name: name.clone(),
        }) {
            Ok(d) => d,
            Err(e) => return self.answer(&crossing, Answer::Failed(e.to_string())),
        };
        lock(&self.carried).insert(
            crossing.id,
            Carried {
                crossing: crossing.clone(),
                carry: None,
                child: None,
                node: None,
            },
        );
        match half.send_watched_raw(Class::Goal, self.carry.as_str(), data, []) {
            Ok(watched) => {
                if let Some(k) = lock(&self.carried).get_mut(&crossing.id) {
                    k.carry = Some(watched.id());
                }
                let core = self.clone();
                tokio::spawn(async move {
                    let answer = match watched.outcome().await {
                        Ok(TaskOutcome::Achieved) => Answer::Done,
                        Ok(TaskOutcome::Failed(reason)) => Answer::Failed(reason),
                        Ok(TaskOutcome::Killed) => {
                            Answer::Failed(format!("{name} was killed on the {to} side"))
                        }
                        Err(e) => Answer::Failed(format!(
                            "{name} was not carried out on the {to} side: {e}"
                        )),
                    };
                    core.answer(&crossing, answer);
                });
            }
            Err(e) => self.answer(
                &crossing,
                Answer::Failed(format!("the {to} side's central did not take {name}: {e}")),
            ),
        }
    }

    /// Asks a query with its own timeout (it was handed over just before); the answer
    /// crosses back.
    async fn release_query(self: Arc<Self>, half: Module, crossing: Crossing) {
        let Payload::Query {
            name,
            data,
            timeout,
        } = &crossing.payload
        else {
            return;
        };
        let to = crossing.direction.to();
        let answer = match half
            .query_raw(name.as_str(), data.clone(), Some(*timeout))
            .await
        {
            Ok(reply) => Answer::Reply(reply),
            Err(ModuleError::HandlerFailed { reason, .. }) => Answer::Failed(reason),
            Err(ModuleError::Timeout { timeout, .. }) => Answer::Failed(format!(
                "{name} was not answered within its own timeout of {:.3} s on the {to} side",
                timeout.as_secs_f64()
            )),
            Err(e) => Answer::Failed(format!("{name} on the {to} side: {e}")),
        };
        self.answer(&crossing, answer);
    }
}

/// What a bridge handler returns: the wait for what comes back, if anything does.
pub(crate) type Pending = std::pin::Pin<Box<dyn std::future::Future<Output = Handled> + Send>>;

fn done(result: Handled) -> Pending {
    Box::pin(std::future::ready(result))
}

/// The bridge's handler of a message crossing `direction`, on the side it leaves.
///
/// The message takes its place in the delay line here, when the handler is called: the
/// module calls handlers in the order messages arrive, so what leaves a side crosses in the
/// order it left (an exception raised in a carried task ahead of that task's outcome, one
/// telemetry sample ahead of the next). The returned future only waits for what comes back.
pub(crate) fn forward(
    core: Weak<Core>,
    direction: Direction,
    class: Class,
    name: MessageName,
    ctx: Context,
    data: Vec<u8>,
) -> Pending {
    let Some(c) = core.upgrade() else {
        return done(Err(stopping()));
    };
    let sender = ctx.sender().clone();
    let cause = Some(ctx.message_id());
    match class {
        Class::Inform => {
            c.cross(
                c.next_id(),
                direction,
                sender,
                cause,
                Payload::Inform { name, data },
            );
            done(Ok(Vec::new()))
        }
        Class::Exception => {
            let side = direction.from();
            let task = ctx
                .node()
                .and_then(|n| lock(&c.carry_nodes).get(&(side, n)).copied());
            let Some(task) = task else {
                return done(Err(HandlerError::new(format!(
                    "{name} was not raised inside a task the bridge carries out; passed up"
                ))));
            };
            c.cross(
                c.next_id(),
                direction,
                sender,
                cause,
                Payload::Exception { task, name, data },
            );
            done(Ok(Vec::new()))
        }
        Class::Query => {
            let id = c.next_id();
            let rx = c.wait_answer(id, &ctx);
            let within = c.config.answer_within(direction, &name);
            let timeout = c.config.query_timeout(direction, &name);
            let (up, down) = (
                c.config.delay(direction),
                c.config.delay(direction.reverse()),
            );
            c.cross(
                id,
                direction,
                sender,
                cause,
                Payload::Query {
                    name: name.clone(),
                    data,
                    timeout,
                },
            );
            drop(c);
            Box::pin(async move {
                match tokio::time::timeout(within, rx).await {
                    Ok(Ok(Answer::Reply(reply))) => Ok(reply),
                    Ok(Ok(Answer::Failed(reason))) => Err(HandlerError::new(reason)),
                    Ok(Ok(Answer::Done)) => Err(HandlerError::new(format!(
                        "{name}: a task's outcome came back for a query"
                    ))),
                    Ok(Err(_)) => Err(stopping()),
                    Err(_) => {
                        if let Some(c) = core.upgrade() {
                            lock(&c.waiting).remove(&id);
                        }
                        Err(HandlerError::new(format!(
                            "no answer to {name} came back across the bridge within {:.3} s \
                             (its own {:.3} s on the {} side, {:.3} s there and {:.3} s back, \
                             and a second for the centrals)",
                            within.as_secs_f64(),
                            timeout.as_secs_f64(),
                            direction.to(),
                            up.as_secs_f64(),
                            down.as_secs_f64()
                        )))
                    }
                }
            })
        }
        Class::Goal | Class::Command => {
            if ctx.redelivery() > 0 {
                return done(Err(HandlerError::new(format!(
                    "{name} was crossing to the {} side when the bridge stopped; whether it \
                     was carried out there is not known, so it is not sent again: look at the \
                     telemetry, then send it again if it is still wanted",
                    direction.to()
                ))));
            }
            let id = c.next_id();
            let rx = c.wait_answer(id, &ctx);
            let guard = KillOnDrop {
                core: core.clone(),
                id,
                direction,
                name: name.clone(),
                armed: true,
            };
            c.cross(
                id,
                direction,
                sender,
                cause,
                Payload::Task {
                    class,
                    name: name.clone(),
                    data,
                },
            );
            drop(c);
            Box::pin(async move {
                let answer = rx.await;
                guard.disarm();
                match answer {
                    Ok(Answer::Done) => Ok(Vec::new()),
                    Ok(Answer::Failed(reason)) => Err(HandlerError::new(reason)),
                    Ok(Answer::Reply(_)) => Err(HandlerError::new(format!(
                        "{name}: a reply came back for a {class}"
                    ))),
                    Err(_) => Err(stopping()),
                }
            })
        }
        other => done(Err(HandlerError::new(format!(
            "{name} is a {other}: the bridge forwards queries, goals, commands, informs and \
             exceptions"
        )))),
    }
}

/// Kills the far copy of a task whose handler here stopped before its outcome came (its
/// task was killed, or its central went away).
struct KillOnDrop {
    core: Weak<Core>,
    id: u32,
    direction: Direction,
    name: MessageName,
    armed: bool,
}

impl KillOnDrop {
    fn disarm(mut self) {
        self.armed = false;
    }
}

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        if !self.armed {
            return;
        }
        let Some(core) = self.core.upgrade() else {
            return;
        };
        if lock(&core.waiting).remove(&self.id).is_none() {
            return;
        }
        let side = self.direction.from();
        core.cross(
            core.next_id(),
            self.direction,
            side_module(side),
            None,
            Payload::Kill {
                task: self.id,
                name: self.name.clone(),
            },
        );
    }
}

/// The handler of `NAME.carry` on `side`: carries out a forwarded goal or command as its
/// child and ends as the child ends.
pub(crate) async fn carry(core: Weak<Core>, side: Side, ctx: Context, data: Vec<u8>) -> Handled {
    let Some(c) = core.upgrade() else {
        return Err(stopping());
    };
    let carry: Carry = decode_data(&data)
        .map_err(|e| HandlerError::new(format!("a carry the bridge cannot read: {e}")))?;
    if ctx.redelivery() > 0 {
        return Err(HandlerError::new(format!(
            "{} came across before the bridge restarted; its origin on the {} side is gone, so \
             it is not carried out",
            carry.name,
            side.other()
        )));
    }
    let crossing = lock(&c.carried)
        .get(&carry.crossing)
        .map(|k| k.crossing.clone());
    let Some(crossing) = crossing else {
        return Err(HandlerError::new(format!(
            "{} came across before the bridge restarted (crossing {} is not known); not carried \
             out",
            carry.name, carry.crossing
        )));
    };
    let Payload::Task { class, name, data } = &crossing.payload else {
        return Err(HandlerError::new(format!(
            "crossing {} is not a goal or command",
            carry.crossing
        )));
    };
    let node = ctx.node();
    if let Some(node) = node {
        let exceptions = &c.exceptions[side.index()];
        // One round trip for all: the attachments go out in order, before the child.
        let attached = futures::future::join_all(
            exceptions
                .iter()
                .map(|e| ctx.on_exception_raw(node, e.as_str())),
        )
        .await;
        for (e, r) in exceptions.iter().zip(attached) {
            if let Err(err) = r {
                tracing::warn!(exception = %e, error = %err, "cannot attach the bridge to a carried task's exceptions");
            }
        }
        lock(&c.carry_nodes).insert((side, node), crossing.id);
        if let Some(k) = lock(&c.carried).get_mut(&crossing.id) {
            k.node = Some((side, node));
        }
    }
    let child = ctx
        .send_watched_raw(*class, name.as_str(), data.clone(), [])
        .map_err(|e| {
            HandlerError::new(format!("{name} could not be sent on the {side} side: {e}"))
        })?;
    if let Some(k) = lock(&c.carried).get_mut(&crossing.id) {
        k.child = Some(child.id());
    }
    c.released(&crossing, Some(child.id()));
    drop(c);
    // Central sends an exception raised in the node before the node's failure, and the
    // bridge's exception handler puts it in the delay line as it arrives (see `forward`),
    // before this wait can wake: the exception crosses ahead of the outcome.
    let outcome = child.outcome().await;
    match outcome {
        Ok(TaskOutcome::Achieved) => Ok(Vec::new()),
        Ok(TaskOutcome::Failed(reason)) => Err(HandlerError::new(reason)),
        Ok(TaskOutcome::Killed) => Err(HandlerError::new(format!(
            "{name} was killed on the {side} side"
        ))),
        Err(e) => Err(HandlerError::new(format!("{name} on the {side} side: {e}"))),
    }
}
