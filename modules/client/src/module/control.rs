//! Central's control requests (registry, tree, kill, constraints, exception handlers, retry,
//! monitors) and the link's life cycle (goodbye, abort, offline and online).

use std::sync::atomic::Ordering;
use std::time::Duration;

use serde::de::DeserializeOwned;
use tca_messages::control::{
    Constrain, ControlRequest, Kill, KillTask, Monitor, MonitorAction, OnException, Registry,
    Retry, Tap, TaskState, TaskStatus, TaskStatusRequest, TreeView,
};
use tca_messages::{
    Class, ConstraintSpec, Envelope, Message, MessageId, MessageName, NodeId, decode_data,
    encode_data, kind,
};
use tokio::sync::mpsc;

use super::{Module, lock, route_error};
use crate::error::{ModuleError, Result};

impl Module {
    /// The registry of every registered message.
    pub async fn registry(&self) -> Result<Registry> {
        self.control(ControlRequest::Registry).await
    }

    /// The live task trees, as text.
    pub async fn tree(&self) -> Result<TreeView> {
        self.control(ControlRequest::Tree).await
    }

    /// Kills a node and its subtree.
    pub async fn kill(&self, node: NodeId) -> Result<()> {
        self.control(ControlRequest::Kill(Kill { node })).await
    }

    /// Kills the task a goal or command created (by the id of its message), and its subtree.
    pub async fn kill_task(&self, task: MessageId) -> Result<()> {
        self.control(ControlRequest::KillTask(KillTask { task }))
            .await
    }

    /// Kills every task tree (an emergency stop); returns how many trees there were. Central
    /// kills them all before it starts anything their end frees.
    pub async fn kill_all(&self) -> Result<u64> {
        self.control(ControlRequest::KillAll).await
    }

    /// Asks central for a copy of every message of these names (every name when empty) that
    /// modules send it or it sends on its own (not control traffic), from now until the
    /// module leaves or taps again (a new tap replaces this one). The copies arrive in the
    /// returned [`Tapping`], in the order central saw them.
    pub async fn tap(&self, names: &[&str]) -> Result<Tapping> {
        let names = names
            .iter()
            .map(|n| MessageName::new(*n).map_err(|e| ModuleError::Usage(e.to_string())))
            .collect::<Result<Vec<_>>>()?;
        let (tx, rx) = mpsc::unbounded_channel();
        *lock(&self.shared.tap) = Some(tx);
        if let Err(e) = self.control::<()>(ControlRequest::Tap(Tap { names })).await {
            *lock(&self.shared.tap) = None;
            return Err(e);
        }
        Ok(Tapping { rx })
    }

    /// Attaches this module as the handler of exception `E` raised at `node` or below (it must
    /// have registered a handler for `E`). The handler gets the exception with its context's
    /// node = `node` and [`Context::origin`](crate::Context::origin) = the raising node.
    pub async fn on_exception<E: Message<Kind = kind::Exception>>(
        &self,
        node: NodeId,
    ) -> Result<()> {
        self.on_exception_raw(node, E::NAME).await
    }

    /// [`Module::on_exception`] for an exception given by name (tools that do not know its
    /// Rust type).
    pub async fn on_exception_raw(&self, node: NodeId, name: &str) -> Result<()> {
        let name = MessageName::new(name).map_err(|e| ModuleError::Usage(e.to_string()))?;
        self.control(ControlRequest::OnException(OnException { node, name }))
            .await
    }

    /// Puts a node back to waiting so it is delivered again (in an exception handler: after
    /// the raising node failed).
    pub async fn retry(&self, node: NodeId) -> Result<()> {
        self.control(ControlRequest::Retry(Retry { node })).await
    }

    /// Installs a point monitor on `node`: when its handler starts, central asks `condition`
    /// (a query answering `bool`) once; `true` triggers `action`.
    pub async fn point_monitor<Q: Message<Kind = kind::Query, Reply = bool>>(
        &self,
        node: NodeId,
        condition: &Q,
        action: MonitorAction,
    ) -> Result<()> {
        self.monitor(node, condition, None, action).await
    }

    /// Installs a polling monitor on `node`: while it is active, central asks `condition` every
    /// `period`; the first `true` triggers `action`. It ends with the node.
    pub async fn polling_monitor<Q: Message<Kind = kind::Query, Reply = bool>>(
        &self,
        node: NodeId,
        condition: &Q,
        period: Duration,
        action: MonitorAction,
    ) -> Result<()> {
        let period_ms = u64::try_from(period.as_millis()).unwrap_or(u64::MAX).max(1);
        self.monitor(node, condition, Some(period_ms), action).await
    }

    async fn monitor<Q: Message<Kind = kind::Query, Reply = bool>>(
        &self,
        node: NodeId,
        condition: &Q,
        period_ms: Option<u64>,
        action: MonitorAction,
    ) -> Result<()> {
        let monitor = Monitor {
            node,
            query: MessageName::new(Q::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?,
            query_data: encode_data(condition)?,
            period_ms,
            action,
        };
        self.control(ControlRequest::Monitor(monitor)).await
    }

    /// Adds a temporal constraint between existing tasks.
    pub async fn constrain(&self, constraint: ConstraintSpec) -> Result<()> {
        self.control(ControlRequest::Constrain(Constrain { constraint }))
            .await
    }

    /// Sends a control request and waits for central's answer.
    async fn control<R: DeserializeOwned>(&self, request: ControlRequest) -> Result<R> {
        let envelope =
            self.envelope(Class::Control, request.name(), request.encode_data()?, None)?;
        let answer = self.request(envelope, self.shared.query_timeout).await?;
        match answer.class {
            Class::Reply => Ok(decode_data(&answer.data)?),
            _ => Err(route_error(&answer)),
        }
    }

    /// Says goodbye to central and waits (at most 2 s) for it to acknowledge, so nothing sent
    /// before is lost; later sends fail with [`ModuleError::Disconnected`].
    pub async fn close(&self) {
        let bye = ControlRequest::Bye;
        if let Ok(env) = self.envelope(
            Class::Control,
            bye.name(),
            bye.encode_data().unwrap_or_default(),
            None,
        ) {
            let _ = self.request(env, Duration::from_secs(2)).await;
        }
        self.shared.closed.store(true, Ordering::Relaxed);
        self.shared.closed_signal.send_replace(true);
    }

    /// Waits for `work`, unless the user presses Ctrl-C first: then the task that message
    /// `task` created (with its subtree) is killed, the module says goodbye, and `None` is
    /// returned. Meant for tools that start a task and wait for its end, such as a walker, so
    /// that nothing they asked for goes on without them. Once this has run, Ctrl-C no longer
    /// ends the process by itself.
    pub async fn unless_interrupted<F: std::future::Future>(
        &self,
        task: MessageId,
        work: F,
    ) -> Option<F::Output> {
        let interrupted = async {
            if let Err(err) = tokio::signal::ctrl_c().await {
                tracing::warn!(%err, "cannot watch for Ctrl-C; it will end the process as usual");
                std::future::pending::<()>().await;
            }
        };
        tokio::select! {
            done = work => Some(done),
            () = interrupted => {
                if let Err(err) = self.kill_task(task).await {
                    tracing::warn!(%err, %task, "cannot kill the interrupted task");
                }
                self.close().await;
                None
            }
        }
    }

    /// Drops the link to central at once, without a goodbye, and stops every running handler:
    /// what central sees when a module crashes. For testing recovery.
    pub fn abort_link(&self) {
        self.shared.closed.store(true, Ordering::Relaxed);
        for (_, h) in lock(&self.shared.running).drain() {
            h.abort();
        }
        drop(lock(&self.shared.keep).take());
        self.shared.closed_signal.send_replace(true);
    }

    /// Resolves when the link to central closes (central stopped, or it closed the link).
    pub async fn closed(&self) {
        let mut closed = self.shared.closed_signal.subscribe();
        let _ = closed.wait_for(|c| *c).await;
    }

    /// Whether the link to central is closed.
    pub fn is_closed(&self) -> bool {
        self.shared.closed.load(Ordering::Relaxed)
    }

    /// Central is gone: what was in flight went with it. Waiting queries fail with
    /// [`ModuleError::CentralLost`], running handlers stop, new sends are refused until the
    /// module has rejoined. Task watchers fail too, unless central keeps a journal: then they
    /// wait for the central that comes back on it (see [`Module::rejoined`]).
    pub(crate) fn go_offline(&self) {
        self.shared.online.store(false, Ordering::Relaxed);
        if lock(&self.shared.journal).is_none() {
            super::receive::fail_watchers(&self.shared, &|| ModuleError::CentralLost);
        }
        super::receive::fail_all_but_watchers(&self.shared);
    }

    /// A central welcomed the module back, keeping `journal`. If it is the journal of the
    /// central the module's task watchers were waiting on, they wait on (see
    /// [`Module::resume_watchers`]); otherwise what they waited for was lost with the old
    /// central, and they fail with [`ModuleError::CentralLost`].
    pub(crate) fn rejoined(&self, journal: Option<u64>) -> bool {
        let before = std::mem::replace(&mut *lock(&self.shared.journal), journal);
        let same = before.is_some() && before == journal;
        if !same {
            super::receive::fail_watchers(&self.shared, &|| ModuleError::CentralLost);
        }
        same
    }

    /// Asks the central rejoined on the same journal what became of the tasks this module
    /// waits for: ends told while it was away are delivered now, tasks central never received
    /// fail with [`ModuleError::CentralLost`], live ones wait on for their end.
    pub(crate) async fn resume_watchers(&self) {
        let tasks: Vec<MessageId> = lock(&self.shared.watchers).keys().copied().collect();
        if tasks.is_empty() {
            return;
        }
        let request = ControlRequest::TaskStatus(TaskStatusRequest {
            tasks: tasks.clone(),
        });
        let statuses: Vec<TaskStatus> = match self.control(request).await {
            Ok(s) => s,
            Err(ModuleError::CentralLost) => return, // asked again when it is back
            Err(e) => {
                tracing::warn!(module = %self.name(), error = %e, "central cannot say what became of the tasks this module waits for; they are given up");
                let mut watchers = lock(&self.shared.watchers);
                for id in tasks {
                    if let Some(w) = watchers.remove(&id) {
                        let _ = w.send(Err(ModuleError::CentralLost));
                    }
                }
                return;
            }
        };
        let mut watchers = lock(&self.shared.watchers);
        for status in statuses {
            let outcome = match status.state {
                TaskState::Live => continue,
                TaskState::Ended(outcome) => Ok(outcome),
                TaskState::Unknown => Err(ModuleError::CentralLost),
            };
            tracing::info!(module = %self.name(), task = %status.task, ?outcome, "a task this module waits for ended while central was away, or never reached it");
            if let Some(w) = watchers.remove(&status.task) {
                let _ = w.send(outcome);
            }
        }
    }

    /// Registered again with a new central.
    pub(crate) fn go_online(&self) {
        self.shared.online.store(true, Ordering::Relaxed);
        self.shared.online_signal.send_replace(true);
    }

    /// The link number of a new central's welcome.
    pub(crate) fn set_link(&self, link: u32) {
        self.shared.link_no.store(link, Ordering::Relaxed);
    }

    /// Whether the module is registered with a live central. False while central is gone and
    /// until the module has rejoined it (zenoh only; see [`crate::rejoin`]).
    pub fn is_online(&self) -> bool {
        self.shared.online.load(Ordering::Relaxed)
    }

    /// Waits until the module is registered with a live central (at once when it is), or for
    /// at most `timeout`; returns whether it is.
    pub async fn wait_online(&self, timeout: Duration) -> bool {
        let mut online = self.shared.online_signal.subscribe();
        let wait = online.wait_for(|_| self.is_online());
        matches!(tokio::time::timeout(timeout, wait).await, Ok(Ok(_)))
    }
}

/// Copies of tapped messages ([`Module::tap`]).
#[derive(Debug)]
pub struct Tapping {
    rx: mpsc::UnboundedReceiver<Envelope>,
}

impl Tapping {
    /// The next tapped message as central saw it; `None` once the link has closed or
    /// another tap replaced this one.
    pub async fn next(&mut self) -> Option<Envelope> {
        self.rx.recv().await
    }
}
