//! The one interface every transport implements, and what a module gets from it.

use std::any::Any;
use std::fmt;
use std::sync::Arc;

use bytes::Bytes;
use futures::future::BoxFuture;
use tokio::sync::mpsc;

use crate::Result;
use crate::outbox::FrameReceiver;

/// A way for a module to reach central. [`InProcTransport`](crate::InProcTransport) and
/// [`ZenohTransport`](crate::ZenohTransport) implement it; another transport slots in by
/// implementing it too, and the module library uses it unchanged.
pub trait Transport: Send + Sync + fmt::Debug + 'static {
    /// Opens a new link to central.
    fn open(&self) -> BoxFuture<'_, Result<Link>>;

    /// Says where it connects, for messages ("central over zenoh at tcp/...").
    fn describe(&self) -> String;
}

/// Sends frames up a link, to central.
pub trait SendFrame: Send + Sync + fmt::Debug + 'static {
    /// Sends one encoded frame. Fails with
    /// [`LinkError::Refused`](crate::LinkError::Refused) when central refuses it (the link
    /// stays open) and [`LinkError::Stopped`](crate::LinkError::Stopped) when the link is
    /// closed.
    fn send(&self, frame: Bytes) -> Result<()>;
}

/// A cheap, cloneable sender of frames up one link.
#[derive(Clone, Debug)]
pub struct FrameSender(Arc<dyn SendFrame>);

impl FrameSender {
    /// Wraps a transport's sender.
    pub fn new(sender: impl SendFrame) -> Self {
        FrameSender(Arc::new(sender))
    }

    /// Sends one encoded frame (see [`SendFrame::send`]).
    pub fn send(&self, frame: Bytes) -> Result<()> {
        self.0.send(frame)
    }
}

/// Whether central is there, as a link that can outlive central sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presence {
    /// Central appeared: it is (back) up, and a module says hello and registers again.
    Up,
    /// Central went away: its process died or the network dropped.
    Down,
}

/// An open link, as the module sees it.
pub struct Link {
    /// Sends frames to central.
    pub sender: FrameSender,
    /// Receives the frames central sends.
    pub receiver: FrameReceiver,
    /// Central's comings and goings, for transports where central can die and come back while
    /// the link stays (zenoh). `None` where the module shares central's fate (in-process).
    pub presence: Option<mpsc::UnboundedReceiver<Presence>>,
    /// What keeps the link open: dropping it closes the link, as a crash of the module would.
    pub keep: Box<dyn Any + Send>,
}

impl fmt::Debug for Link {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Link")
            .field("sender", &self.sender)
            .field("presence", &self.presence.is_some())
            .finish_non_exhaustive()
    }
}
