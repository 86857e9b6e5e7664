//! Simulated time: the rule by which a module's handlers start.
//!
//! A module on simulated time stamps what it sends with the time its handler has reached
//! instead of the wall clock. A handler starts at the stamp of the message it handles; a goal,
//! command or exception ([`Class::runs_in_turn`]) no earlier than the end of the module's
//! previous one, since a module handles those in turn. [`HandlingClock`] holds that rule; the
//! module library runs handlers by it, and the traffic log's replay scripts derive recorded
//! handlers' own time by it.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::class::Class;

/// Envelope stamps below this (about 1973 as wall-clock nanoseconds since the epoch) are
/// simulated time.
pub const SIMULATED_TIME_BELOW_NS: u64 = 100_000_000_000_000_000;

/// Whether a stamp is simulated time rather than the wall clock.
pub fn is_simulated_stamp(stamp_ns: u64) -> bool {
    stamp_ns < SIMULATED_TIME_BELOW_NS
}

/// When one module's handlers start in simulated time. Shared by the module's handlers
/// (it takes `&self`).
#[derive(Debug, Default)]
pub struct HandlingClock {
    /// When the module's latest goal, command or exception handler ended, nanoseconds.
    busy_until: AtomicU64,
}

impl HandlingClock {
    /// A clock of a module that has handled nothing yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// When the handler of a `class` message stamped `sent_ns` starts: at `sent_ns`, and for
    /// a goal, command or exception no earlier than the end of the module's previous one.
    pub fn start(&self, class: Class, sent_ns: u64) -> u64 {
        if class.runs_in_turn() {
            self.busy_until.load(Ordering::Relaxed).max(sent_ns)
        } else {
            sent_ns
        }
    }

    /// A handler of a `class` message ended at `end_ns`.
    pub fn ended(&self, class: Class, end_ns: u64) {
        if class.runs_in_turn() {
            self.busy_until.fetch_max(end_ns, Ordering::Relaxed);
        }
    }

    /// When the module's latest goal, command or exception handler ended.
    pub fn busy_until(&self) -> u64 {
        self.busy_until.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tasks_wait_their_turn_and_queries_do_not() {
        let clock = HandlingClock::new();
        assert_eq!(clock.start(Class::Command, 10), 10);
        clock.ended(Class::Command, 30);
        // A command sent at 20 starts when the previous one ended.
        assert_eq!(clock.start(Class::Command, 20), 30);
        assert_eq!(clock.start(Class::Exception, 25), 30);
        // A query or inform is answered as of when it was sent.
        assert_eq!(clock.start(Class::Query, 20), 20);
        assert_eq!(clock.start(Class::Inform, 5), 5);
        // Their ends do not move the turn; an earlier end does not move it back.
        clock.ended(Class::Query, 100);
        clock.ended(Class::Goal, 25);
        assert_eq!(clock.busy_until(), 30);
        assert_eq!(clock.start(Class::Goal, 40), 40);
    }

    #[test]
    fn wall_clock_stamps_are_told_apart() {
        assert!(is_simulated_stamp(503_000_000_000));
        assert!(!is_simulated_stamp(1_764_000_000_000_000_000));
    }
}
