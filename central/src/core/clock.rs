//! The simulated clock: central as a discrete-event scheduler (on when
//! `CentralConfig::simulated_time` is set).
//!
//! Every message that acts on the system (queries, informs, exceptions, goals, commands, their
//! answers, and the control requests that act on task trees) is an **event** at its simulated
//! stamp. Events wait in one queue, ordered by (stamp, arrival), and are released **one at a
//! time**, only while the system is *quiescent*: every handler of a simulated module that
//! central has delivered a message to has either finished or waits for an answer. A handler
//! that runs can still send something stamped earlier than any queued event; one that waits
//! cannot, and resumes no earlier than the stamp of the answer it waits for. So nothing is
//! ever released before something that happened earlier in simulated time, and since only one
//! handler runs at a time, the order of everything is the same on every run: ties are broken
//! by arrival, and arrivals come from one handler at a time.
//!
//! Central follows each handler by the messages it sends (each names, in `cause`, the
//! delivered message it handles): a query or an answered control request makes it wait until
//! the answer is delivered; an `await` control (sent when a handler awaits a task's end) until
//! the task's end reaches it; an answer to the delivered message (a reply, success or failure;
//! for an inform, an acknowledgement) ends it. A handler whose node is killed, or whose module
//! goes away, ends too: a module that dies does not stall the clock.
//!
//! Goals and commands are delivered when their constraints hold and their module has capacity,
//! judged as events are released: a task is delivered stamped with the simulated time that
//! made it ready. Messages from modules that do not keep simulated time (tools, a wall-clock
//! module) are released at the clock's time.

use std::collections::BTreeMap;

use rustc_hash::FxHashMap as HashMap;
use serde::{Deserialize, Serialize};
use tca_messages::control::ControlKind;
use tca_messages::{Class, Envelope, MessageId, ModuleName, is_simulated_stamp};

use super::LinkId;

/// Something waiting in the queue for its simulated time.
#[derive(Debug, Serialize, Deserialize)]
pub(super) enum Deferred {
    /// A frame to route, as it arrived.
    Frame {
        /// The link it came on.
        link: LinkId,
        /// Its sender.
        module: ModuleName,
        /// The envelope.
        envelope: Envelope,
    },
    /// A message to deliver to a simulated module's handler.
    Deliver {
        /// The module.
        module: ModuleName,
        /// The envelope as it will be sent.
        envelope: Envelope,
    },
    /// A polling monitor's next check.
    Poll {
        /// The monitored node.
        node: u64,
    },
}

/// A handler central follows.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Handler {
    module: ModuleName,
    class: Class,
    /// Answers it waits for (queries, control requests, task ends).
    waiting: u32,
}

/// The simulated clock and the event queue.
#[derive(Debug, Default, Serialize, Deserialize)]
pub(super) struct SimClock {
    /// The clock is on (central keeps simulated time).
    pub(super) on: bool,
    /// Simulated now: the stamp of the latest event released, nanoseconds.
    pub(super) now: u64,
    arrivals: u64,
    queue: BTreeMap<(u64, u64), Deferred>,
    /// Handlers running, by the id of the message they handle.
    handlers: HashMap<MessageId, Handler>,
    /// What waiting handlers wait for: request or task id -> the handler.
    awaited: HashMap<MessageId, MessageId>,
    /// A release is under way: sends go out at once.
    pub(super) releasing: bool,
    /// Events released so far.
    pub(super) released: u64,
}

impl SimClock {
    /// A clock, on or off.
    pub(super) fn new(on: bool) -> Self {
        SimClock {
            on,
            ..SimClock::default()
        }
    }

    /// The stamp an arriving envelope is released at: its own, but never before now (a tool on
    /// the wall clock, or a late sender, acts now).
    pub(super) fn release_stamp(&self, stamp: u64) -> u64 {
        if is_simulated_stamp(stamp) {
            stamp.max(self.now)
        } else {
            self.now
        }
    }

    /// Queues an event at `stamp` (arrival order breaks ties).
    pub(super) fn push(&mut self, stamp: u64, event: Deferred) {
        self.arrivals += 1;
        self.queue.insert((stamp, self.arrivals), event);
    }

    /// Whether every followed handler has finished or waits for an answer.
    pub(super) fn quiescent(&self) -> bool {
        self.handlers.values().all(|h| h.waiting > 0)
    }

    /// Takes the earliest event if the system is quiescent, moving the clock to it.
    pub(super) fn next(&mut self) -> Option<(u64, Deferred)> {
        if !self.quiescent() {
            return None;
        }
        let ((stamp, _), event) = self.queue.pop_first()?;
        self.now = self.now.max(stamp);
        self.released += 1;
        Some((self.now, event))
    }

    /// Events waiting.
    pub(super) fn queued(&self) -> usize {
        self.queue.len()
    }

    /// Handlers running or waiting.
    pub(super) fn handlers(&self) -> usize {
        self.handlers.len()
    }

    /// A handled message was delivered to a simulated module: its handler runs.
    pub(super) fn started(&mut self, envelope: &Envelope, module: &ModuleName) {
        self.handlers.insert(
            envelope.id,
            Handler {
                module: module.clone(),
                class: envelope.class,
                waiting: 0,
            },
        );
    }

    /// Follows what a simulated module's handler sent; true when central should consume the
    /// envelope here (an acknowledged inform, an await), not route it.
    pub(super) fn sent(&mut self, envelope: &Envelope) -> bool {
        let Some(cause) = envelope.cause else {
            return false;
        };
        let Some(handler) = self.handlers.get_mut(&cause) else {
            return false;
        };
        match envelope.class {
            Class::Query => {
                handler.waiting += 1;
                self.awaited.insert(envelope.id, cause);
                false
            }
            Class::Control => match ControlKind::from_name(envelope.name.as_str()) {
                Some(ControlKind::Await) => {
                    if let Ok(tca_messages::control::ControlRequest::Await(a)) =
                        tca_messages::control::ControlRequest::decode(
                            envelope.name.as_str(),
                            &envelope.data,
                        )
                    {
                        handler.waiting += 1;
                        self.awaited.insert(a.task, cause);
                    }
                    true
                }
                Some(kind) if kind.is_answered() => {
                    handler.waiting += 1;
                    self.awaited.insert(envelope.id, cause);
                    false
                }
                _ => false,
            },
            Class::Reply | Class::Success | Class::Failure
                if envelope.correlation == Some(cause) =>
            {
                let inform = handler.class == Class::Inform;
                self.end(cause);
                // An inform's acknowledgement only ends its handler.
                inform
            }
            _ => false,
        }
    }

    /// Something is delivered to `to` that a waiting handler of that module may wait for (an
    /// answer, a task's end, an error about its request): the handler runs again once nothing
    /// else is awaited.
    pub(super) fn delivered(&mut self, envelope: &Envelope, to: &ModuleName) {
        let answers = match envelope.class {
            Class::Reply | Class::Failure | Class::Error => true,
            Class::Control => envelope.name.as_str() == tca_messages::control::names::TASK_ENDED,
            _ => false,
        };
        if !answers {
            return;
        }
        let Some(c) = envelope.correlation else {
            return;
        };
        let Some(&handler) = self.awaited.get(&c) else {
            return;
        };
        match self.handlers.get_mut(&handler) {
            Some(h) if &h.module == to => {
                h.waiting = h.waiting.saturating_sub(1);
                self.awaited.remove(&c);
            }
            Some(_) => {}
            None => {
                self.awaited.remove(&c);
            }
        }
    }

    /// A handler ended (answered, was cancelled, or its module went away).
    pub(super) fn end(&mut self, handled: MessageId) {
        self.handlers.remove(&handled);
        self.awaited.retain(|_, h| *h != handled);
    }

    /// A module went away: its handlers end, and what was queued for it is handed back.
    pub(super) fn module_gone(&mut self, module: &ModuleName) -> Vec<Envelope> {
        let gone: Vec<MessageId> = self
            .handlers
            .iter()
            .filter(|(_, h)| &h.module == module)
            .map(|(id, _)| *id)
            .collect();
        for id in gone {
            self.end(id);
        }
        let keys: Vec<(u64, u64)> = self
            .queue
            .iter()
            .filter(|(_, e)| matches!(e, Deferred::Deliver { module: m, .. } if m == module))
            .map(|(k, _)| *k)
            .collect();
        keys.into_iter()
            .filter_map(|k| match self.queue.remove(&k) {
                Some(Deferred::Deliver { envelope, .. }) => Some(envelope),
                _ => None,
            })
            .collect()
    }

    /// Takes the goals and commands queued as they arrived that would become roots of new
    /// task trees (sent outside any task), in queue order: an emergency stop drops them.
    pub(super) fn take_root_tasks(&mut self) -> Vec<(LinkId, Envelope)> {
        let keys: Vec<(u64, u64)> = self
            .queue
            .iter()
            .filter(|(_, e)| {
                matches!(e, Deferred::Frame { envelope, .. }
                    if envelope.class.is_task() && envelope.context.is_none())
            })
            .map(|(k, _)| *k)
            .collect();
        keys.into_iter()
            .filter_map(|k| match self.queue.remove(&k) {
                Some(Deferred::Frame { link, envelope, .. }) => Some((link, envelope)),
                _ => None,
            })
            .collect()
    }

    /// Takes the goal or command of message `id` from the queue, if it waits there as it
    /// arrived (not yet a task).
    pub(super) fn take_task_frame(&mut self, id: MessageId) -> Option<(LinkId, Envelope)> {
        let key = self.queue.iter().find_map(|(k, e)| {
            matches!(e, Deferred::Frame { envelope, .. }
                if envelope.id == id && envelope.class.is_task())
            .then_some(*k)
        })?;
        match self.queue.remove(&key) {
            Some(Deferred::Frame { link, envelope, .. }) => Some((link, envelope)),
            _ => None,
        }
    }

    /// Whether the goal or command of message `id` from `sender` waits in the queue as it
    /// arrived (not yet a task).
    pub(super) fn holds_task_frame(&self, id: MessageId, sender: &ModuleName) -> bool {
        self.on
            && self.queue.values().any(|e| {
                matches!(e, Deferred::Frame { module, envelope, .. }
                    if envelope.id == id && module == sender && envelope.class.is_task())
            })
    }

    /// Forgets the queued checks of a monitor on `node`.
    pub(super) fn drop_polls(&mut self, node: u64) {
        self.queue
            .retain(|_, e| !matches!(e, Deferred::Poll { node: n } if *n == node));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_messages::{MessageName, SendOptions};

    fn env(id: (u32, u32), class: Class, name: &str, cause: Option<MessageId>) -> Envelope {
        Envelope {
            id: MessageId::new(id.0, id.1),
            class,
            name: MessageName::new(name).unwrap(),
            sender: ModuleName::new("m").unwrap(),
            context: None,
            node: None,
            correlation: None,
            cause,
            timestamp_ns: 0,
            options: SendOptions::default(),
            redelivery: 0,
            data: Vec::new(),
        }
    }

    #[test]
    fn events_wait_while_a_handler_runs_and_go_in_stamp_order() {
        let mut c = SimClock::new(true);
        let m = ModuleName::new("m").unwrap();
        let goal = env((1, 1), Class::Goal, "g", None);
        c.started(&goal, &m);
        c.push(20, Deferred::Poll { node: 2 });
        c.push(10, Deferred::Poll { node: 1 });
        assert!(c.next().is_none(), "the goal's handler runs");
        // It asks a query: it waits, and the earliest event goes.
        let q = env((1, 2), Class::Query, "q", Some(goal.id));
        assert!(!c.sent(&q));
        assert!(matches!(c.next(), Some((10, Deferred::Poll { node: 1 }))));
        // The reply comes: it runs again.
        let mut reply = env((2, 1), Class::Reply, "q", None);
        reply.correlation = Some(q.id);
        c.delivered(&reply, &ModuleName::new("other").unwrap());
        assert!(c.quiescent(), "a reply to another module does not wake it");
        c.delivered(&reply, &m);
        assert!(!c.quiescent());
        assert!(c.next().is_none());
        // It ends: the rest goes, the clock never goes back.
        let mut done = env((1, 3), Class::Success, "g", Some(goal.id));
        done.correlation = Some(goal.id);
        assert!(!c.sent(&done));
        assert!(matches!(c.next(), Some((20, Deferred::Poll { node: 2 }))));
        assert_eq!(c.release_stamp(5), 20);
        assert_eq!(
            c.release_stamp(1_764_000_000_000_000_000),
            20,
            "wall stamps act now"
        );
    }

    #[test]
    fn an_inform_acknowledgement_ends_its_handler_and_is_consumed() {
        let mut c = SimClock::new(true);
        let m = ModuleName::new("m").unwrap();
        let inform = env((1, 1), Class::Inform, "i", None);
        c.started(&inform, &m);
        assert!(!c.quiescent());
        let mut ack = env((2, 5), Class::Success, "i", Some(inform.id));
        ack.correlation = Some(inform.id);
        assert!(c.sent(&ack));
        assert!(c.quiescent());
    }

    #[test]
    fn a_module_that_goes_away_does_not_stall_the_clock() {
        let mut c = SimClock::new(true);
        let m = ModuleName::new("m").unwrap();
        let goal = env((1, 1), Class::Goal, "g", None);
        c.started(&goal, &m);
        c.push(
            3,
            Deferred::Deliver {
                module: m.clone(),
                envelope: env((1, 9), Class::Inform, "i", None),
            },
        );
        assert!(!c.quiescent());
        let handed_back = c.module_gone(&m);
        assert_eq!(handed_back.len(), 1);
        assert!(c.quiescent());
        assert_eq!(c.queued(), 0);
    }
}
