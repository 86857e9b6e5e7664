//! The module's simulated clock.
//!
//! A module built with `simulated_time(true)` stamps what it sends with simulated time. Each
//! handler runs on a clock of its own, started by the module's [`HandlingClock`]
//! (`tca_messages::sim_time`): a query or inform as of the time it was sent; a goal, command or
//! exception when it was sent or when the module's previous one ended, whichever is later.
//! A handler's clock follows the stamps of the answers it receives and advances by what it
//! [`spend`](Module::spend)s. The module's own clock is the latest time any of them reached.
//!
//! On a central that keeps the system's simulated clock, central decides when each handler
//! starts (the stamp it delivers the message with), and the module tells it what central could
//! not see: when an inform's handler ended, and when a handler awaits a task's end.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use tca_messages::{Class, now_ns};

use super::Module;

impl Module {
    /// Whether this module stamps its messages with simulated time.
    pub fn simulated_time(&self) -> bool {
        self.shared.sim_time
    }

    /// The time this handle stamps on what it sends, in nanoseconds: simulated time (for a
    /// module built with `simulated_time(true)`: the time its handler has reached, following
    /// the time of every message it received), otherwise the wall clock (since the epoch).
    pub fn time_ns(&self) -> u64 {
        if !self.shared.sim_time {
            return now_ns();
        }
        match &self.clock {
            Some(c) => c.load(Ordering::Relaxed),
            None => self.shared.base_clock.load(Ordering::Relaxed),
        }
    }

    /// Charges `duration` of simulated time to the running handler (a move, a computation).
    /// Does nothing for modules on the wall clock.
    pub fn spend(&self, duration: Duration) {
        if !self.shared.sim_time {
            return;
        }
        let d = u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX);
        let t = match &self.clock {
            Some(c) => c.fetch_add(d, Ordering::Relaxed).saturating_add(d),
            None => self
                .shared
                .base_clock
                .fetch_add(d, Ordering::Relaxed)
                .saturating_add(d),
        };
        self.shared.base_clock.fetch_max(t, Ordering::Relaxed);
    }

    /// Moves simulated time forward to at least `t_ns` (a message from later arrived).
    pub(crate) fn observe(&self, t_ns: u64) {
        if !self.shared.sim_time {
            return;
        }
        if let Some(c) = &self.clock {
            c.fetch_max(t_ns, Ordering::Relaxed);
        }
        self.shared.base_clock.fetch_max(t_ns, Ordering::Relaxed);
    }

    /// The clock of a handler of a `class` message stamped `sent_ns` (simulated time only).
    /// On central's simulated clock a handler starts at the stamp central delivered it with
    /// (central judges capacity); otherwise by the module's own `HandlingClock`.
    pub(crate) fn handler_clock(&self, class: Class, sent_ns: u64) -> Option<Arc<AtomicU64>> {
        self.shared.sim_time.then(|| {
            let start = if self.on_central_clock() {
                sent_ns
            } else {
                self.shared.handling.start(class, sent_ns)
            };
            Arc::new(AtomicU64::new(start))
        })
    }

    /// Whether this module runs on central's simulated clock.
    pub fn on_central_clock(&self) -> bool {
        self.shared.sim_time && self.shared.central_clock.load(Ordering::Relaxed)
    }

    /// Whether central keeps the system's simulated clock (its welcome said so), whatever
    /// this module stamps its messages with. Tools that work in wall-clock time (a bridge
    /// that delays traffic by real seconds) refuse such a central.
    pub fn central_keeps_simulated_time(&self) -> bool {
        self.shared.central_clock.load(Ordering::Relaxed)
    }

    /// Central's welcome said whether it keeps the simulated clock.
    pub(crate) fn set_central_clock(&self, on: bool) {
        self.shared.central_clock.store(on, Ordering::Relaxed);
    }

    /// Tells central this handler waits for the end of `task` (on central's simulated clock).
    pub(crate) fn awaiting(&self, task: tca_messages::MessageId) -> crate::Result<()> {
        if !self.on_central_clock() || self.handling.is_none() {
            return Ok(());
        }
        let request =
            tca_messages::control::ControlRequest::Await(tca_messages::control::Await { task });
        let envelope =
            self.envelope(Class::Control, request.name(), request.encode_data()?, None)?;
        self.transmit(&envelope)
    }

    /// This handle's handler of a `class` message ended: the module's next goal, command or
    /// exception starts no earlier.
    pub(crate) fn handler_ended(&self, class: Class) {
        if self.shared.sim_time {
            self.shared.handling.ended(class, self.time_ns());
        }
    }
}
