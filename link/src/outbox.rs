//! Per-link outboxes: the frames central has sent to a link that the link's transport has not
//! taken yet (an in-process module's receive loop, or central's zenoh publisher for that
//! module), bounded by `max_outbox_frames` and `max_outbox_bytes`.
//!
//! The frames travel over a tokio channel; a gauge shared by both ends counts them. Central's
//! driver counts each frame in as it sends it and never waits: the bound acts through central's
//! routing instead of by blocking.
//!
//! - At half the bound the link is **congested**: the core gives its module no new work, and
//!   the driver *watches* the gauge.
//! - When the receiver has taken a watched outbox down to a quarter of the bound, the gauge
//!   wakes the hub ([`LinkSignal::Drained`]), and central delivers what it held.
//! - Past the bound (only a module that does not read the answers to its own requests gets
//!   there), the module is disconnected as too slow.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::SeqCst};

use bytes::Bytes;
use tokio::sync::mpsc;

use crate::LinkId;
use crate::hub::{Hub, LinkSignal};

/// How full a link's outbox is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OutboxUse {
    /// Frames not yet taken by the link.
    pub frames: u64,
    /// Their bytes.
    pub bytes: u64,
}

/// The bound of every outbox, and the marks derived from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutboxLimits {
    /// Most frames (one frame always fits an empty outbox).
    pub frames: u64,
    /// Most bytes.
    pub bytes: u64,
}

impl OutboxLimits {
    /// The limits `max_outbox_frames` and `max_outbox_bytes`.
    pub fn new(frames: u32, bytes: u64) -> Self {
        OutboxLimits {
            frames: u64::from(frames.max(1)),
            bytes: bytes.max(1),
        }
    }

    /// At or past this level (frames or bytes) the link is congested.
    pub fn congested(&self, frames: u64, bytes: u64) -> bool {
        frames >= (self.frames / 2).max(1) || bytes >= (self.bytes / 2).max(1)
    }

    /// At or under this level (frames and bytes) a congested link is drained.
    fn drained(&self, frames: u64, bytes: u64) -> bool {
        frames <= self.frames / 4 && bytes <= self.bytes / 4
    }

    /// Past the bound: the module is disconnected.
    pub fn over(&self, frames: u64, bytes: u64) -> bool {
        frames > 1 && (frames > self.frames || bytes > self.bytes)
    }
}

/// The level of one outbox, shared by the driver (which counts frames in) and the receiver
/// (which counts them out).
#[derive(Debug)]
pub struct Gauge {
    link: LinkId,
    limits: OutboxLimits,
    frames: AtomicU64,
    bytes: AtomicU64,
    /// The driver waits for the level to fall to the drained mark.
    watch: AtomicBool,
    wake: Arc<dyn Hub>,
}

impl Gauge {
    /// The gauge of link `link`'s outbox, bounded by `limits`, waking `wake` when a watched
    /// level drains.
    pub fn new(link: LinkId, limits: OutboxLimits, wake: Arc<dyn Hub>) -> Self {
        Gauge {
            link,
            limits,
            frames: AtomicU64::new(0),
            bytes: AtomicU64::new(0),
            watch: AtomicBool::new(false),
            wake,
        }
    }

    /// Counts a frame of `len` bytes in; the level after it (frames, bytes).
    pub fn added(&self, len: usize) -> (u64, u64) {
        let len = len as u64;
        let frames = self.frames.fetch_add(1, SeqCst) + 1;
        let bytes = self.bytes.fetch_add(len, SeqCst) + len;
        (frames, bytes)
    }

    /// Counts a frame of `len` bytes out, waking the driver if it watches and the outbox is
    /// now drained.
    fn taken(&self, len: usize) {
        let len = len as u64;
        let frames = self.frames.fetch_sub(1, SeqCst).saturating_sub(1);
        let bytes = self.bytes.fetch_sub(len, SeqCst).saturating_sub(len);
        if self.limits.drained(frames, bytes)
            && self.watch.load(SeqCst)
            && self.watch.swap(false, SeqCst)
        {
            let _ = self.wake.signal(LinkSignal::Drained(self.link));
        }
    }

    /// The level now (frames, bytes).
    pub fn level(&self) -> (u64, u64) {
        (self.frames.load(SeqCst), self.bytes.load(SeqCst))
    }

    /// Asks for a [`LinkSignal::Drained`] once the outbox is drained. Returns false when it already
    /// is (no wake will come then): the watch and the receiver's check are ordered so that
    /// exactly one of them sees the drained level.
    fn watch(&self) -> bool {
        self.watch.store(true, SeqCst);
        let (frames, bytes) = self.level();
        !(self.limits.drained(frames, bytes) && self.watch.swap(false, SeqCst))
    }

    /// The level now, for central. A level at the congestion mark or above is watched: the
    /// hub hears ([`LinkSignal::Drained`]) when the receiver has taken it down to a quarter.
    pub fn measure(&self) -> OutboxUse {
        let (frames, bytes) = self.level();
        if self.limits.congested(frames, bytes) && self.watch() {
            return OutboxUse { frames, bytes };
        }
        // Not congested, or drained meanwhile (only the receiver lowers the level).
        let (frames, bytes) = self.level();
        OutboxUse { frames, bytes }
    }
}

/// A module's receiver of the frames central sends it.
///
/// For an in-process link it is the receiving end of the link's outbox, and taking frames from
/// it is what frees room there: a module must keep reading it, or central stops giving it work
/// and finally disconnects it as too slow. A transport that feeds a module from elsewhere (the
/// zenoh client side) wraps its own channel with [`FrameReceiver::from`].
#[derive(Debug)]
pub struct FrameReceiver {
    rx: mpsc::UnboundedReceiver<Bytes>,
    gauge: Option<Arc<Gauge>>,
}

impl FrameReceiver {
    /// The receiving end of an outbox whose level `gauge` counts.
    pub fn metered(rx: mpsc::UnboundedReceiver<Bytes>, gauge: Arc<Gauge>) -> Self {
        FrameReceiver {
            rx,
            gauge: Some(gauge),
        }
    }

    /// The next frame; `None` once the link is closed and every frame sent before was taken.
    pub async fn recv(&mut self) -> Option<Bytes> {
        let frame = self.rx.recv().await?;
        self.count_out(&frame);
        Some(frame)
    }

    /// The next frame if one is there now.
    pub fn try_recv(&mut self) -> Option<Bytes> {
        let frame = self.rx.try_recv().ok()?;
        self.count_out(&frame);
        Some(frame)
    }

    fn count_out(&self, frame: &Bytes) {
        if let Some(g) = &self.gauge {
            g.taken(frame.len());
        }
    }
}

impl From<mpsc::UnboundedReceiver<Bytes>> for FrameReceiver {
    /// A receiver of frames that no outbox of central counts.
    fn from(rx: mpsc::UnboundedReceiver<Bytes>) -> Self {
        FrameReceiver { rx, gauge: None }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::hub::testing::Recorder;

    fn gauge(frames: u32) -> (Arc<Gauge>, Arc<Recorder>) {
        let hub = Arc::new(Recorder::default());
        (
            Arc::new(Gauge::new(
                3,
                OutboxLimits::new(frames, 1 << 30),
                hub.clone(),
            )),
            hub,
        )
    }

    #[test]
    fn marks_sit_at_half_and_a_quarter_of_the_bound() {
        let l = OutboxLimits::new(8, 800);
        assert!(!l.congested(3, 0) && l.congested(4, 0) && l.congested(0, 400));
        assert!(l.drained(2, 200) && !l.drained(3, 0) && !l.drained(0, 201));
        assert!(!l.over(8, 800) && l.over(9, 0) && l.over(2, 801));
        // One frame always fits, whatever its size.
        assert!(!l.over(1, 10_000));
    }

    #[test]
    fn a_watched_gauge_wakes_the_driver_once_when_drained() {
        let (g, wake) = gauge(8);
        let (tx, rx) = mpsc::unbounded_channel();
        let mut receiver = FrameReceiver::metered(rx, g.clone());
        for _ in 0..5 {
            g.added(10);
            tx.send(Bytes::from_static(b"0123456789")).unwrap();
        }
        assert_eq!(g.level(), (5, 50));
        assert!(g.watch(), "5 of 8 frames is not drained");
        for left in [4, 3] {
            receiver.try_recv().unwrap();
            assert_eq!(g.level().0, left);
            assert!(wake.take().is_empty(), "not drained at {left} frames");
        }
        receiver.try_recv().unwrap();
        assert_eq!(wake.take(), [LinkSignal::Drained(3)]);
        receiver.try_recv().unwrap();
        assert!(wake.take().is_empty(), "one wake per watch");
        assert_eq!(g.level(), (1, 10));
    }

    #[test]
    fn measuring_watches_a_congested_gauge_only() {
        let (g, wake) = gauge(8);
        let (tx, rx) = mpsc::unbounded_channel();
        let mut receiver = FrameReceiver::metered(rx, g.clone());
        for _ in 0..3 {
            g.added(1);
            tx.send(Bytes::from_static(b"x")).unwrap();
        }
        assert_eq!(
            g.measure(),
            OutboxUse {
                frames: 3,
                bytes: 3
            }
        );
        for _ in 0..3 {
            receiver.try_recv().unwrap();
        }
        assert!(wake.take().is_empty(), "3 of 8 frames was not watched");
        for _ in 0..4 {
            g.added(1);
            tx.send(Bytes::from_static(b"x")).unwrap();
        }
        assert_eq!(g.measure().frames, 4);
        for _ in 0..2 {
            receiver.try_recv().unwrap();
        }
        assert_eq!(wake.take(), [LinkSignal::Drained(3)]);
    }

    #[test]
    fn watching_a_drained_gauge_says_so_instead_of_waking() {
        let (g, wake) = gauge(8);
        g.added(1);
        assert!(!g.watch());
        assert!(wake.take().is_empty());
    }
}
