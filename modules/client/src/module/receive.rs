//! Receiving: the loop that reads frames from central, and the dispatch of what it sends to
//! handlers, waiting requests and task watchers.

use std::sync::Weak;
use std::sync::atomic::Ordering;

use tca_link::{FrameReceiver, Presence};
use tca_messages::control::ControlNotice;
use tca_messages::{Class, Envelope, Failure, decode, encode_data};
use tokio::sync::mpsc;

use super::{Module, Shared, lock, route_error};
use crate::context::{Context, Incoming};
use crate::error::ModuleError;
use crate::rejoin::{Rejoiner, Verdict};

impl Module {
    /// Reads frames from central until the link closes. Holds the module weakly, so the link
    /// closes when the last [`Module`] handle is dropped (as when a module process dies). Over
    /// zenoh it also follows central's presence and rejoins a restarted central
    /// ([`crate::rejoin`]).
    pub(crate) async fn receive_loop(
        shared: Weak<Shared>,
        mut rx: FrameReceiver,
        mut presence: Option<mpsc::UnboundedReceiver<Presence>>,
        mut rejoiner: Option<Rejoiner>,
        early: Vec<Envelope>,
    ) {
        let upgrade = |shared: &Weak<Shared>| {
            shared.upgrade().map(|shared| Module {
                shared,
                context: None,
                clock: None,
                handling: None,
            })
        };
        // What central delivered while the module was still registering comes first.
        if let Some(module) = upgrade(&shared) {
            for envelope in early {
                module.on_envelope(envelope);
            }
        }
        loop {
            let deadline = rejoiner.as_ref().and_then(Rejoiner::deadline);
            tokio::select! {
                frame = rx.recv() => {
                    let Some(frame) = frame else { break };
                    let Some(module) = upgrade(&shared) else { return };
                    let envelope = match decode(&frame, usize::MAX) {
                        Ok(envelope) => envelope,
                        Err(e) => {
                            tracing::warn!(module = %module.shared.name, error = %e, "bad frame from central");
                            continue;
                        }
                    };
                    match rejoiner.as_mut().map(|r| r.on_envelope(&module, &envelope)) {
                        None | Some(Verdict::Handle) => module.on_envelope(envelope),
                        Some(Verdict::Consumed) => {}
                        Some(Verdict::Online(held)) => {
                            for envelope in held {
                                module.on_envelope(envelope);
                            }
                        }
                        Some(Verdict::Refused(reason)) => {
                            tracing::error!(module = %module.shared.name, %reason, "central refused this module when it rejoined; it stops");
                            break;
                        }
                    }
                }
                p = next_presence(&mut presence) => {
                    let Some(module) = upgrade(&shared) else { return };
                    match (p, rejoiner.as_mut()) {
                        (Some(p), Some(r)) => r.on_presence(&module, p),
                        (Some(_), None) => {}
                        (None, _) => presence = None,
                    }
                }
                _ = sleep_until(deadline) => {
                    let Some(module) = upgrade(&shared) else { return };
                    if let Some(r) = rejoiner.as_mut() {
                        r.on_timer(&module);
                    }
                }
            }
        }
        let Some(shared) = shared.upgrade() else {
            return;
        };
        shared.closed.store(true, Ordering::Relaxed);
        shared.closed_signal.send_replace(true);
        // Fail everything still waiting: dropping the senders wakes the waiters.
        fail_in_flight(&shared, || ModuleError::Disconnected);
        tracing::info!(module = %shared.name, "link to central closed");
    }

    fn on_envelope(&self, envelope: Envelope) {
        match envelope.class {
            class if class.is_handled() => self.run_handler(envelope),
            Class::Reply | Class::Failure | Class::Error => {
                let Some(id) = envelope.correlation else {
                    tracing::warn!(?envelope, "answer without correlation");
                    return;
                };
                if let Some(tx) = lock(&self.shared.pending).remove(&id) {
                    let _ = tx.send(envelope);
                } else if let Some(tx) = lock(&self.shared.watchers).remove(&id) {
                    let _ = tx.send(Err(route_error(&envelope)));
                } else if envelope.class == Class::Error {
                    tracing::warn!(module = %self.shared.name, error = %route_error(&envelope), about = %id, "central reported an error");
                }
            }
            Class::Control => self.on_control(envelope),
            other => tracing::warn!(class = %other, "unexpected class from central"),
        }
    }

    fn on_control(&self, envelope: Envelope) {
        match ControlNotice::decode(envelope.name.as_str(), &envelope.data) {
            Some(ControlNotice::Cancel(cancel)) => {
                if let Some(h) = lock(&self.shared.running).remove(&cancel.node) {
                    tracing::info!(node = %cancel.node, "handler cancelled by central");
                    h.abort();
                }
            }
            Some(ControlNotice::TaskEnded(ended)) => {
                if let Some(id) = envelope.correlation {
                    self.observe(envelope.timestamp_ns);
                    if let Some(tx) = lock(&self.shared.watchers).remove(&id) {
                        let _ = tx.send(Ok(ended.outcome));
                    }
                }
            }
            Some(ControlNotice::Tapped(tapped)) => {
                let mut tap = lock(&self.shared.tap);
                if let Some(tx) = tap.as_ref()
                    && tx.send(tapped.envelope).is_err()
                {
                    // Nobody reads the copies any more.
                    *tap = None;
                }
            }
            _ => tracing::debug!(name = %envelope.name, "control message ignored"),
        }
    }

    fn run_handler(&self, envelope: Envelope) {
        let Some(entry) = self.shared.handlers.get(&envelope.name).cloned() else {
            // Central only routes what we registered; answer so nobody waits forever.
            let reason = format!(
                "module {} has no handler for {}",
                self.shared.name, envelope.name
            );
            self.answer(&envelope, Err(reason));
            return;
        };
        let node = envelope.node;
        let class = envelope.class;
        let handler_module = Module {
            shared: self.shared.clone(),
            context: node,
            clock: self.handler_clock(class, envelope.timestamp_ns),
            handling: Some(envelope.id),
        };
        let ctx = Context::new(
            handler_module.clone(),
            envelope.redelivery,
            envelope.context,
            Incoming {
                sender: envelope.sender.clone(),
                id: envelope.id,
                class,
            },
        );
        // The handler is called here, in the order messages arrive: what it does before its
        // future first waits (a monitor writing a record, a bridge taking a crossing into its
        // delay line) happens in that order. Its future then runs beside the others.
        let running_handler = (entry.call)(ctx, envelope.data.clone());
        // Hold the table while spawning so the handler cannot finish (and remove itself)
        // before it is entered.
        let mut running = lock(&self.shared.running);
        let task = tokio::spawn(async move {
            let result = running_handler.await;
            if let Some(n) = node {
                lock(&handler_module.shared.running).remove(&n);
            }
            handler_module.handler_ended(class);
            handler_module.answer(&envelope, result.map_err(|e| e.to_string()));
        });
        if let Some(n) = node {
            running.insert(n, task.abort_handle());
        }
    }

    /// Sends the end of a handler: reply, success or failure.
    fn answer(&self, request: &Envelope, result: std::result::Result<Vec<u8>, String>) {
        let (class, data) = match (request.class, result) {
            (Class::Query, Ok(data)) => (Class::Reply, data),
            (class, Ok(_)) if class.runs_in_turn() => {
                (Class::Success, encode_data(&()).unwrap_or_default())
            }
            (Class::Inform, result) => {
                if let Err(reason) = result {
                    tracing::warn!(name = %request.name, %reason, "inform handler failed");
                }
                if !self.on_central_clock() {
                    return;
                }
                // On central's simulated clock, the end of an inform's handler is told too.
                (Class::Success, encode_data(&()).unwrap_or_default())
            }
            (_, Ok(_)) => return,
            (_, Err(reason)) => {
                tracing::debug!(name = %request.name, %reason, "handler failed");
                (
                    Class::Failure,
                    encode_data(&Failure { reason }).unwrap_or_default(),
                )
            }
        };
        let mut envelope =
            match self
                .in_context(request.node)
                .envelope(class, request.name.as_str(), data, None)
            {
                Ok(e) => e,
                Err(e) => {
                    tracing::error!(error = %e, "cannot build answer");
                    return;
                }
            };
        envelope.correlation = Some(request.id);
        envelope.node = request.node;
        if let Err(e) = self.transmit(&envelope) {
            tracing::warn!(error = %e, name = %request.name, "answer not sent");
        }
    }
}

/// Fails every waiting query (dropping its sender), task watcher and running handler.
pub(super) fn fail_in_flight(shared: &Shared, error: impl Fn() -> ModuleError) {
    fail_watchers(shared, &error);
    fail_all_but_watchers(shared);
}

/// Fails every task watcher.
pub(super) fn fail_watchers(shared: &Shared, error: &impl Fn() -> ModuleError) {
    for (_, w) in lock(&shared.watchers).drain() {
        let _ = w.send(Err(error()));
    }
}

/// Fails every waiting query and stops every running handler; ends the tap.
pub(super) fn fail_all_but_watchers(shared: &Shared) {
    lock(&shared.pending).clear();
    for (_, h) in lock(&shared.running).drain() {
        h.abort();
    }
    // The tap ends with the link (a central that comes back knows nothing of it).
    lock(&shared.tap).take();
}

/// The next change of central's presence; never, without a presence feed.
async fn next_presence(
    presence: &mut Option<mpsc::UnboundedReceiver<Presence>>,
) -> Option<Presence> {
    match presence {
        Some(rx) => rx.recv().await,
        None => std::future::pending().await,
    }
}

/// Sleeps until the deadline; forever without one.
async fn sleep_until(deadline: Option<tokio::time::Instant>) {
    match deadline {
        Some(d) => tokio::time::sleep_until(d).await,
        None => std::future::pending().await,
    }
}
