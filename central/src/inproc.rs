//! The in-process transport: a module in the same process as central talks to it over tokio
//! channels. Frames are still encoded, so the in-process path exercises the same codec as zenoh.
//! A frame sent while the link's inbox in central is full is refused at once
//! ([`CentralError::Refused`](crate::CentralError::Refused) with an over-limit error).

use std::sync::Arc;

use bytes::Bytes;
use tokio::sync::mpsc;

use crate::core::{Event, LinkId};
use crate::inbox::Inbox;
use crate::outbox::FrameReceiver;
use crate::runtime::Input;

/// A module's end of an in-process link. Dropping it closes the link, as a crash would.
#[derive(Debug)]
pub struct InProcLink {
    link: LinkId,
    to_central: mpsc::UnboundedSender<Input>,
    inbox: Arc<Inbox>,
    from_central: Option<FrameReceiver>,
}

impl InProcLink {
    pub(crate) fn new(
        link: LinkId,
        to_central: mpsc::UnboundedSender<Input>,
        inbox: Arc<Inbox>,
        from_central: FrameReceiver,
    ) -> Self {
        InProcLink {
            link,
            to_central,
            inbox,
            from_central: Some(from_central),
        }
    }

    /// The link number.
    pub fn link(&self) -> LinkId {
        self.link
    }

    /// A sender of frames to central (cheap to clone).
    pub fn sender(&self) -> InProcSender {
        InProcSender {
            link: self.link,
            inbox: self.inbox.clone(),
        }
    }

    /// Takes the receiver of frames from central (once). Keep reading it: frames not taken
    /// count against the link's outbox limits (`max_outbox_frames`, `max_outbox_bytes`).
    pub fn take_receiver(&mut self) -> Option<FrameReceiver> {
        self.from_central.take()
    }
}

impl Drop for InProcLink {
    fn drop(&mut self) {
        let _ = self.to_central.send(Input::Event(Event::Closed(self.link)));
    }
}

/// Sends frames to central on one in-process link.
#[derive(Clone, Debug)]
pub struct InProcSender {
    link: LinkId,
    inbox: Arc<Inbox>,
}

impl InProcSender {
    /// Sends a frame. Fails when central has stopped, or when the link already has
    /// `max_inbox_frames` frames (or `max_inbox_bytes` bytes) waiting in central:
    /// [`CentralError::Refused`](crate::CentralError::Refused) with
    /// [`RouteError::OverLimit`](tca_messages::RouteError::OverLimit); the frame is not sent.
    pub fn send(&self, frame: Bytes) -> Result<(), crate::CentralError> {
        self.inbox.push(frame)
    }

    /// The link number.
    pub fn link(&self) -> LinkId {
        self.link
    }
}
