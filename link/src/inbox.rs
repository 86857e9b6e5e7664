//! Per-link inboxes: the frames a link has sent that central has not handled yet, bounded by
//! `max_inbox_frames` and `max_inbox_bytes`. The driver serves the inboxes in turn (one frame
//! per link per turn), so a module that floods central delays only itself.
//!
//! A transport pushes a frame with [`Inbox::push`] (in-process: the sender gets the refusal at
//! once) or [`Inbox::push_or_refuse`] (zenoh: a refused frame's header is kept aside, up to
//! [`MAX_REFUSALS`], so central can answer it with an error; past that it is only counted and
//! the module told once). The first push into an
//! idle inbox wakes the hub with [`LinkSignal::Ready`].

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use bytes::Bytes;
use tca_messages::RouteError;

use crate::hub::{Hub, LinkSignal};
use crate::{LinkError, LinkId};

/// How full a link's inbox was when a frame was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InboxUse {
    /// Frames waiting.
    pub frames: u64,
    /// Their bytes.
    pub bytes: u64,
}

/// Most refused frames of one link kept to be answered (as headers of ~100 bytes each); more
/// are dropped and counted.
pub const MAX_REFUSALS: usize = 65_536;

/// The frame with its data removed: enough for central to answer it. Undecodable frames are
/// kept as their first 64 bytes, for the problem record.
fn header_only(frame: &Bytes) -> Bytes {
    match tca_messages::decode(frame, usize::MAX) {
        Ok(mut envelope) => {
            envelope.data = Vec::new();
            envelope.options = Default::default();
            match tca_messages::encode(&envelope) {
                Ok(head) => Bytes::from(head),
                Err(_) => frame.slice(..frame.len().min(64)),
            }
        }
        Err(_) => frame.slice(..frame.len().min(64)),
    }
}

/// Something the driver takes out of an inbox.
#[derive(Debug)]
pub enum Taken {
    /// A frame to handle.
    Frame(Bytes),
    /// A frame refused because the inbox was full, to answer with an error.
    Refused(Bytes, InboxUse),
    /// Frames refused and dropped without an answer (the refusal queue was full too).
    Dropped(u64),
}

#[derive(Debug, Default)]
struct State {
    frames: VecDeque<Bytes>,
    bytes: u64,
    refused: VecDeque<(Bytes, InboxUse)>,
    dropped: u64,
    /// The driver knows this inbox has something (a `Ready` was sent and not yet served dry).
    scheduled: bool,
    closed: bool,
    /// The most frames and bytes waiting at once.
    high: (u64, u64),
}

impl State {
    fn queue(&mut self, frame: Bytes) {
        self.bytes += frame.len() as u64;
        self.frames.push_back(frame);
        self.high.0 = self.high.0.max(self.frames.len() as u64);
        self.high.1 = self.high.1.max(self.bytes);
    }
}

/// One link's inbox: frames the module sent that central has not handled yet.
#[derive(Debug)]
pub struct Inbox {
    link: LinkId,
    max_frames: u64,
    max_bytes: u64,
    wake: Arc<dyn Hub>,
    state: Mutex<State>,
}

impl Inbox {
    /// An empty inbox of link `link` holding at most `max_frames` frames and `max_bytes`
    /// bytes (one frame always fits an empty inbox), waking `wake` when it gets something.
    pub fn new(link: LinkId, max_frames: u32, max_bytes: u64, wake: Arc<dyn Hub>) -> Self {
        Inbox {
            link,
            max_frames: u64::from(max_frames.max(1)),
            max_bytes,
            wake,
            state: Mutex::new(State::default()),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Whether a frame of `len` bytes fits; one frame always fits an empty inbox.
    fn over(&self, s: &State, len: usize) -> Option<InboxUse> {
        let frames = s.frames.len() as u64;
        let full = frames >= self.max_frames || s.bytes.saturating_add(len as u64) > self.max_bytes;
        (frames > 0 && full).then_some(InboxUse {
            frames,
            bytes: s.bytes,
        })
    }

    fn schedule(&self, s: &mut State) -> Result<(), LinkError> {
        if !s.scheduled {
            s.scheduled = true;
            if !self.wake.signal(LinkSignal::Ready(self.link)) {
                return Err(LinkError::Stopped);
            }
        }
        Ok(())
    }

    /// The link's number.
    pub fn link(&self) -> LinkId {
        self.link
    }

    /// Queues a frame, or refuses it when the inbox is full ([`LinkError::Refused`] with an
    /// over-limit error naming the setting; the frame is not queued).
    pub fn push(&self, frame: Bytes) -> Result<(), LinkError> {
        if self.wake.stopped() {
            return Err(LinkError::Stopped);
        }
        let mut s = self.lock();
        if s.closed {
            return Err(LinkError::Stopped);
        }
        if let Some(used) = self.over(&s, frame.len()) {
            return Err(LinkError::Refused(self.refusal(used)));
        }
        s.queue(frame);
        self.schedule(&mut s)
    }

    /// Queues a frame; a refused one is kept aside (bounded) for central to answer.
    pub fn push_or_refuse(&self, frame: Bytes) {
        let mut s = self.lock();
        if s.closed {
            return;
        }
        match self.over(&s, frame.len()) {
            None => s.queue(frame),
            // A refused frame is kept as its header only (data dropped), so each costs about a
            // hundred bytes; past MAX_REFUSALS they are only counted.
            Some(used) if s.refused.len() < MAX_REFUSALS => {
                s.refused.push_back((header_only(&frame), used));
            }
            Some(_) => s.dropped += 1,
        }
        let _ = self.schedule(&mut s);
    }

    /// The error a refused in-process sender gets.
    fn refusal(&self, used: InboxUse) -> RouteError {
        let module = format!("on link {}", self.link);
        if used.frames >= self.max_frames {
            RouteError::OverLimit {
                module,
                what: "frames waiting in central's inbox".into(),
                used: used.frames,
                limit: self.max_frames,
                setting: "max_inbox_frames".into(),
            }
        } else {
            RouteError::OverLimit {
                module,
                what: "bytes waiting in central's inbox".into(),
                used: used.bytes,
                limit: self.max_bytes,
                setting: "max_inbox_bytes".into(),
            }
        }
    }

    /// Takes the next item, and whether more remain. When none remain the inbox is marked idle,
    /// so the next push wakes the driver again.
    pub fn take(&self) -> (Option<Taken>, bool) {
        let mut s = self.lock();
        let item = if let Some(f) = s.frames.pop_front() {
            s.bytes -= f.len() as u64;
            Some(Taken::Frame(f))
        } else if let Some((f, used)) = s.refused.pop_front() {
            Some(Taken::Refused(f, used))
        } else if s.dropped > 0 {
            Some(Taken::Dropped(std::mem::take(&mut s.dropped)))
        } else {
            None
        };
        let more = !s.frames.is_empty() || !s.refused.is_empty() || s.dropped > 0;
        if !more {
            s.scheduled = false;
        }
        (item, more)
    }

    /// The most frames and bytes that have waited in this inbox at once.
    pub fn high_water(&self) -> (u64, u64) {
        self.lock().high
    }

    /// Stops accepting frames (the link closed).
    pub fn close(&self) {
        let mut s = self.lock();
        s.closed = true;
        s.frames.clear();
        s.refused.clear();
        s.bytes = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::hub::testing::Recorder;

    fn inbox(frames: u32, bytes: u64) -> (Inbox, Arc<Recorder>) {
        let hub = Arc::new(Recorder::default());
        (Inbox::new(7, frames, bytes, hub.clone()), hub)
    }

    #[test]
    fn wakes_once_until_served_dry() {
        let (inbox, hub) = inbox(10, 1000);
        inbox.push(Bytes::from_static(b"a")).unwrap();
        inbox.push(Bytes::from_static(b"b")).unwrap();
        assert_eq!(hub.take(), [LinkSignal::Ready(7)]);
        assert!(matches!(inbox.take(), (Some(Taken::Frame(_)), true)));
        assert!(matches!(inbox.take(), (Some(Taken::Frame(_)), false)));
        inbox.push(Bytes::from_static(b"c")).unwrap();
        assert_eq!(hub.take(), [LinkSignal::Ready(7)]);
    }

    #[test]
    fn a_stopped_hub_refuses_pushes() {
        let (inbox, hub) = inbox(10, 1000);
        hub.stopped.store(true, std::sync::atomic::Ordering::SeqCst);
        assert!(matches!(
            inbox.push(Bytes::from_static(b"a")),
            Err(LinkError::Stopped)
        ));
    }

    #[test]
    fn full_inbox_refuses_with_the_limit_named() {
        let (inbox, _hub) = inbox(2, 1000);
        inbox.push(Bytes::from_static(b"a")).unwrap();
        inbox.push(Bytes::from_static(b"b")).unwrap();
        let err = inbox.push(Bytes::from_static(b"c")).unwrap_err();
        assert!(err.to_string().contains("max_inbox_frames"), "{err}");
        let (inbox, _hub) = super::tests::inbox(100, 10);
        // One frame always fits an empty inbox.
        inbox.push(Bytes::from(vec![0u8; 50])).unwrap();
        let err = inbox.push(Bytes::from_static(b"x")).unwrap_err();
        assert!(err.to_string().contains("max_inbox_bytes"), "{err}");
    }

    #[test]
    fn refused_frames_are_kept_then_counted() {
        let (inbox, _hub) = inbox(1, 1000);
        for _ in 0..MAX_REFUSALS + 3 {
            inbox.push_or_refuse(Bytes::from_static(b"a"));
        }
        assert!(matches!(inbox.take().0, Some(Taken::Frame(_))));
        for _ in 0..MAX_REFUSALS {
            assert!(matches!(inbox.take().0, Some(Taken::Refused(_, _))));
        }
        assert!(matches!(inbox.take().0, Some(Taken::Dropped(2))));
        assert!(matches!(inbox.take(), (None, false)));
    }
}
