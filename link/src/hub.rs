//! How a link's queues wake whoever drives them.
//!
//! Central's driver owns every link's [`Inbox`](crate::Inbox) and outbox
//! [`Gauge`](crate::Gauge) but never polls them: an inbox that gets its first frame, an outbox
//! read down after congestion, and an in-process link whose module end is dropped each send one
//! [`LinkSignal`] to the [`Hub`].

use std::fmt;

use crate::LinkId;

/// Something a link tells its hub.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkSignal {
    /// The link's inbox was idle and now has something to handle.
    Ready(LinkId),
    /// The link's watched outbox was read down to a quarter of its bound.
    Drained(LinkId),
    /// The module's end of an in-process link was dropped (the module left or crashed).
    Closed(LinkId),
}

/// Where link signals go: central's driver.
pub trait Hub: Send + Sync + fmt::Debug + 'static {
    /// Delivers a signal; false when the hub has stopped.
    fn signal(&self, signal: LinkSignal) -> bool;

    /// Whether the hub has stopped (frames pushed now would never be handled).
    fn stopped(&self) -> bool;
}

#[cfg(test)]
pub(crate) mod testing {
    use std::sync::Mutex;

    use super::*;

    /// A hub that records what it is told.
    #[derive(Debug, Default)]
    pub(crate) struct Recorder {
        pub(crate) signals: Mutex<Vec<LinkSignal>>,
        pub(crate) stopped: std::sync::atomic::AtomicBool,
    }

    impl Recorder {
        /// Takes the signals recorded so far.
        pub(crate) fn take(&self) -> Vec<LinkSignal> {
            std::mem::take(&mut *self.signals.lock().unwrap())
        }
    }

    impl Hub for Recorder {
        fn signal(&self, signal: LinkSignal) -> bool {
            if self.stopped() {
                return false;
            }
            self.signals.lock().unwrap().push(signal);
            true
        }

        fn stopped(&self) -> bool {
            self.stopped.load(std::sync::atomic::Ordering::SeqCst)
        }
    }
}
