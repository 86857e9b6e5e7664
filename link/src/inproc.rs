//! The in-process transport: a module in the same process as central talks to it over tokio
//! channels. Frames are still encoded, so the in-process path exercises the same codec as any
//! other transport. A frame sent while the link's inbox in central is full is refused at once
//! ([`LinkError::Refused`] with an over-limit error).
//!
//! Central hands out an [`InProcTransport`] (`CentralHandle::in_process` in `tca-central`);
//! each [`Transport::open`] asks central for a new link.

use std::fmt;
use std::sync::Arc;

use bytes::Bytes;
use futures::future::BoxFuture;

use crate::hub::{Hub, LinkSignal};
use crate::inbox::Inbox;
use crate::outbox::FrameReceiver;
use crate::transport::{FrameSender, Link, SendFrame, Transport};
use crate::{LinkError, LinkId, Result};

/// A module's end of an in-process link. Dropping it closes the link, as a crash would.
#[derive(Debug)]
pub struct InProcLink {
    link: LinkId,
    hub: Arc<dyn Hub>,
    inbox: Arc<Inbox>,
    from_central: Option<FrameReceiver>,
}

impl InProcLink {
    /// The module's end of link `link`: frames go into `inbox`, frames come from
    /// `from_central`, and dropping it tells `hub` that the link closed.
    pub fn new(
        link: LinkId,
        hub: Arc<dyn Hub>,
        inbox: Arc<Inbox>,
        from_central: FrameReceiver,
    ) -> Self {
        InProcLink {
            link,
            hub,
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
        let _ = self.hub.signal(LinkSignal::Closed(self.link));
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
    /// [`LinkError::Refused`] with
    /// [`RouteError::OverLimit`](tca_messages::RouteError::OverLimit); the frame is not sent.
    pub fn send(&self, frame: Bytes) -> Result<()> {
        self.inbox.push(frame)
    }

    /// The link number.
    pub fn link(&self) -> LinkId {
        self.link
    }
}

impl SendFrame for InProcSender {
    fn send(&self, frame: Bytes) -> Result<()> {
        InProcSender::send(self, frame)
    }
}

/// Opens in-process links to a central running in this process.
#[derive(Clone)]
pub struct InProcTransport {
    dial: Arc<dyn Fn() -> Result<InProcLink> + Send + Sync>,
}

impl InProcTransport {
    /// A transport whose every link is opened by `dial` (central provides it).
    pub fn new(dial: impl Fn() -> Result<InProcLink> + Send + Sync + 'static) -> Self {
        InProcTransport {
            dial: Arc::new(dial),
        }
    }

    /// Opens a link at once (in-process links need no waiting).
    pub fn dial(&self) -> Result<InProcLink> {
        (self.dial)()
    }
}

impl fmt::Debug for InProcTransport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("InProcTransport")
    }
}

impl Transport for InProcTransport {
    fn open(&self) -> BoxFuture<'_, Result<Link>> {
        Box::pin(async move {
            let mut link = self.dial()?;
            let receiver = link
                .take_receiver()
                .ok_or_else(|| LinkError::Open("link receiver already taken".into()))?;
            Ok(Link {
                sender: FrameSender::new(link.sender()),
                receiver,
                presence: None,
                keep: Box::new(link),
            })
        })
    }

    fn describe(&self) -> String {
        "in-process central".into()
    }
}
