//! Sending: queries, goals, commands, informs and exceptions, typed and raw; the envelope
//! every send builds and the frame it becomes.

use std::time::Duration;

use bytes::Bytes;
use tca_messages::control::{MonitorAction, TaskOutcome};
use tca_messages::{
    Class, ConstraintSpec, Envelope, Failure, Message, MessageId, MessageName, RouteError,
    SendOptions, class_of, decode_data, encode, encode_data, kind,
};
use tokio::sync::oneshot;

use super::{Module, Task, WatchedTask, lock, route_error};
use crate::error::{ModuleError, Result};

impl Module {
    /// Sends a query and waits for the reply (at most the module's query timeout).
    pub async fn query<Q: Message<Kind = kind::Query>>(&self, query: &Q) -> Result<Q::Reply> {
        self.query_with_timeout(query, self.shared.query_timeout)
            .await
    }

    /// Like [`Module::query`], but a query lost with central (it went away before answering) is
    /// asked again once the module has rejoined a central, as long as that takes at most
    /// `patience` each time: for queries that only read the world, which may be asked twice.
    pub async fn query_through_restarts<Q: Message<Kind = kind::Query>>(
        &self,
        query: &Q,
        patience: Duration,
    ) -> Result<Q::Reply> {
        loop {
            match self.query(query).await {
                Err(ModuleError::CentralLost) => {
                    if !self.wait_online(patience).await {
                        return Err(ModuleError::CentralLost);
                    }
                }
                other => return other,
            }
        }
    }

    /// Sends a query and waits at most `timeout` for the reply.
    pub async fn query_with_timeout<Q: Message<Kind = kind::Query>>(
        &self,
        query: &Q,
        timeout: Duration,
    ) -> Result<Q::Reply> {
        let data = self.ask(Q::NAME, encode_data(query)?, timeout).await?;
        Ok(decode_data(&data)?)
    }

    /// Sends a query given by name and postcard data, and waits at most `timeout` (the
    /// module's query timeout if `None`) for the reply's postcard data. For tools that do not
    /// know the message's Rust type (`tca log replay`); modules use [`Module::query`].
    pub async fn query_raw(
        &self,
        name: &str,
        data: Vec<u8>,
        timeout: Option<Duration>,
    ) -> Result<Vec<u8>> {
        self.ask(name, data, timeout.unwrap_or(self.shared.query_timeout))
            .await
    }

    /// Asks a query and returns the reply's data; asks again (up to the module's
    /// `requery_after_crash`) when the module answering dies first.
    async fn ask(&self, name: &str, data: Vec<u8>, timeout: Duration) -> Result<Vec<u8>> {
        let mut data = Some(data);
        let mut crashes = 0;
        let answer = loop {
            // Keep a copy only while the query may have to be sent again.
            let payload = if crashes < self.shared.requery_after_crash {
                data.clone()
            } else {
                data.take()
            }
            .unwrap_or_default();
            let envelope = self.envelope(Class::Query, name, payload, None)?;
            let answer = self.request(envelope, timeout).await?;
            if answer.class == Class::Error
                && crashes < self.shared.requery_after_crash
                && let ModuleError::Route(RouteError::HandlerDied { .. }) = route_error(&answer)
            {
                crashes += 1;
                tracing::info!(
                    name,
                    attempt = crashes,
                    "the module answering died; asking again"
                );
                continue;
            }
            break answer;
        };
        match answer.class {
            Class::Reply => Ok(answer.data),
            Class::Failure => Err(ModuleError::HandlerFailed {
                name: name.into(),
                reason: decode_data::<Failure>(&answer.data)
                    .map(|f| f.reason)
                    .unwrap_or_else(|e| e.to_string()),
            }),
            _ => Err(route_error(&answer)),
        }
    }

    /// Sends a goal (non-blocking): it becomes a task-tree node under this handle's context.
    pub fn goal<G: Message<Kind = kind::Goal>>(&self, goal: &G) -> Result<Task> {
        self.send_task(goal, [])
    }

    /// Sends a command (non-blocking).
    pub fn command<C: Message<Kind = kind::Command>>(&self, command: &C) -> Result<Task> {
        self.send_task(command, [])
    }

    /// Sends a goal or command with temporal constraints.
    pub fn send_task<M: Message>(
        &self,
        message: &M,
        constraints: impl IntoIterator<Item = ConstraintSpec>,
    ) -> Result<Task>
    where
        M::Kind: kind::TaskClass,
    {
        self.send_task_raw(
            class_of::<M>(),
            M::NAME,
            encode_data(message)?,
            constraints,
            None,
        )
    }

    /// Sends a goal or command with temporal constraints and asks central to say how it ends:
    /// await [`WatchedTask::outcome`].
    pub fn send_watched<M: Message>(
        &self,
        message: &M,
        constraints: impl IntoIterator<Item = ConstraintSpec>,
    ) -> Result<WatchedTask>
    where
        M::Kind: kind::TaskClass,
    {
        self.send_watched_raw(class_of::<M>(), M::NAME, encode_data(message)?, constraints)
    }

    /// Sends an inform (one-way).
    pub fn inform<I: Message<Kind = kind::Inform>>(&self, inform: &I) -> Result<()> {
        let envelope = self.envelope(Class::Inform, I::NAME, encode_data(inform)?, None)?;
        self.transmit(&envelope)
    }

    /// Raises an exception in the context of this handle's task node: central routes it to the
    /// nearest handler registered for its name up the task tree (§3.2).
    pub fn raise<E: Message<Kind = kind::Exception>>(&self, exception: &E) -> Result<()> {
        let envelope = self.envelope(Class::Exception, E::NAME, encode_data(exception)?, None)?;
        self.transmit(&envelope)
    }

    /// Sends a goal, command, inform or exception given by class, name and postcard data, in
    /// this handle's context (an exception is raised there). `constraints` apply to goals and
    /// commands only; for informs and exceptions they must be empty. Returns the id of the
    /// message sent. For tools that do not know the message's Rust type (`tca log replay`);
    /// modules use [`Module::goal`], [`Module::raise`] and the like.
    pub fn send_raw(
        &self,
        class: Class,
        name: &str,
        data: Vec<u8>,
        constraints: impl IntoIterator<Item = ConstraintSpec>,
    ) -> Result<MessageId> {
        let constraints: Vec<ConstraintSpec> = constraints.into_iter().collect();
        match class {
            Class::Goal | Class::Command => self
                .send_task_raw(class, name, data, constraints, None)
                .map(|t| t.id),
            Class::Inform | Class::Exception if constraints.is_empty() => {
                let envelope = self.envelope(class, name, data, None)?;
                self.transmit(&envelope)?;
                Ok(envelope.id)
            }
            Class::Inform | Class::Exception => Err(ModuleError::Usage(format!(
                "{name} is a {class}: constraints apply to goals and commands only"
            ))),
            other => Err(ModuleError::Usage(format!(
                "send_raw sends goals, commands, informs and exceptions; {name} is a {other} \
                 (use query_raw for queries)"
            ))),
        }
    }

    /// [`Module::send_watched`] for a goal or command given by class, name and postcard data.
    pub fn send_watched_raw(
        &self,
        class: Class,
        name: &str,
        data: Vec<u8>,
        constraints: impl IntoIterator<Item = ConstraintSpec>,
    ) -> Result<WatchedTask> {
        if !class.is_task() {
            return Err(ModuleError::Usage(format!(
                "{name} is a {class}, not a goal or command: notification and constraints \
                 apply to goals and commands only"
            )));
        }
        let (watch, outcome) = oneshot::channel();
        let task = self.send_task_raw(class, name, data, constraints, Some(watch))?;
        let waiter = self.handling.is_some().then(|| self.clone());
        Ok(WatchedTask {
            task,
            outcome,
            waiter,
        })
    }

    /// Sends a task's envelope; with a `watch`, central is asked to say how the task ends and
    /// the watch hears it (the watch is dropped again if the send fails).
    fn send_task_raw(
        &self,
        class: Class,
        name: &str,
        data: Vec<u8>,
        constraints: impl IntoIterator<Item = ConstraintSpec>,
        watch: Option<oneshot::Sender<Result<TaskOutcome>>>,
    ) -> Result<Task> {
        let options = SendOptions {
            constraints: constraints.into_iter().collect(),
            notify: watch.is_some(),
        };
        let envelope = self.envelope(class, name, data, Some(options))?;
        let id = envelope.id;
        if let Some(watch) = watch {
            lock(&self.shared.watchers).insert(id, watch);
        }
        if let Err(e) = self.transmit(&envelope) {
            lock(&self.shared.watchers).remove(&id);
            return Err(e);
        }
        Ok(Task { id })
    }

    /// Sends and waits for the envelope that answers it.
    pub(crate) async fn request(&self, envelope: Envelope, timeout: Duration) -> Result<Envelope> {
        let (tx, rx) = oneshot::channel();
        let id = envelope.id;
        lock(&self.shared.pending).insert(id, tx);
        if let Err(e) = self.transmit(&envelope) {
            lock(&self.shared.pending).remove(&id);
            return Err(e);
        }
        match tokio::time::timeout(timeout, rx).await {
            Ok(Ok(answer)) => {
                self.observe(answer.timestamp_ns);
                Ok(answer)
            }
            Ok(Err(_)) if !self.is_online() => Err(ModuleError::CentralLost),
            Ok(Err(_)) => Err(ModuleError::Disconnected),
            Err(_) => {
                lock(&self.shared.pending).remove(&id);
                Err(ModuleError::Timeout {
                    name: envelope.name.to_string(),
                    timeout,
                })
            }
        }
    }

    pub(crate) fn next_id(&self) -> MessageId {
        use std::sync::atomic::Ordering;
        let seq = self.shared.seq.fetch_add(1, Ordering::Relaxed);
        MessageId::new(self.shared.link_no.load(Ordering::Relaxed), seq)
    }

    /// An envelope from this handle: the next id, its context, its time.
    pub(crate) fn envelope(
        &self,
        class: Class,
        name: &str,
        data: Vec<u8>,
        options: Option<SendOptions>,
    ) -> Result<Envelope> {
        Ok(Envelope {
            id: self.next_id(),
            class,
            name: MessageName::new(name).map_err(|e| ModuleError::Usage(e.to_string()))?,
            sender: self.shared.name.clone(),
            context: self.context,
            node: None,
            correlation: None,
            cause: self.handling,
            timestamp_ns: self.time_ns(),
            options: options.unwrap_or_default(),
            redelivery: 0,
            data,
        })
    }

    /// Sends an envelope while the module is connected and online.
    pub(crate) fn transmit(&self, envelope: &Envelope) -> Result<()> {
        if self.is_closed() {
            return Err(ModuleError::Disconnected);
        }
        if !self.is_online() {
            return Err(ModuleError::CentralLost);
        }
        self.send_frame(envelope)
    }

    /// Sends a hello or registration, online or not.
    pub(crate) fn send_bootstrap(&self, envelope: &Envelope) -> Result<()> {
        if self.is_closed() {
            return Err(ModuleError::Disconnected);
        }
        self.send_frame(envelope)
    }

    fn send_frame(&self, envelope: &Envelope) -> Result<()> {
        let frame = encode(envelope)?;
        if frame.len() > self.shared.max_frame_bytes {
            return Err(ModuleError::Codec(tca_messages::CodecError::TooLarge {
                size: frame.len(),
                limit: self.shared.max_frame_bytes,
            }));
        }
        self.shared
            .tx
            .send(Bytes::from(frame))
            .map_err(ModuleError::from)
    }
}

/// A monitor action raising exception `exception` in the monitored node's context.
pub fn raise_action<E: Message<Kind = kind::Exception>>(exception: &E) -> Result<MonitorAction> {
    Ok(MonitorAction::Raise {
        name: MessageName::new(E::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?,
        data: encode_data(exception)?,
    })
}

/// A monitor action sending `message` (a goal, command or inform; goals and commands become
/// children of the monitored node).
pub fn send_action<M: Message>(message: &M) -> Result<MonitorAction>
where
    M::Kind: kind::MonitorSend,
{
    Ok(MonitorAction::Send {
        class: class_of::<M>(),
        name: MessageName::new(M::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?,
        data: encode_data(message)?,
    })
}
