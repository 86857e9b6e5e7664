//! The in-process transport: a module in the same process as central talks to it over tokio
//! channels. Frames are still encoded, so the in-process path exercises the same codec as zenoh.

use bytes::Bytes;
use tokio::sync::mpsc;

use crate::core::{Event, LinkId};
use crate::runtime::Input;

/// A module's end of an in-process link. Dropping it closes the link, as a crash would.
#[derive(Debug)]
pub struct InProcLink {
    link: LinkId,
    to_central: mpsc::UnboundedSender<Input>,
    from_central: Option<mpsc::UnboundedReceiver<Bytes>>,
}

impl InProcLink {
    pub(crate) fn new(
        link: LinkId,
        to_central: mpsc::UnboundedSender<Input>,
        from_central: mpsc::UnboundedReceiver<Bytes>,
    ) -> Self {
        InProcLink {
            link,
            to_central,
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
            to_central: self.to_central.clone(),
        }
    }

    /// Takes the receiver of frames from central (once).
    pub fn take_receiver(&mut self) -> Option<mpsc::UnboundedReceiver<Bytes>> {
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
    to_central: mpsc::UnboundedSender<Input>,
}

impl InProcSender {
    /// Sends a frame; fails only when central has stopped.
    pub fn send(&self, frame: Bytes) -> Result<(), crate::CentralError> {
        self.to_central
            .send(Input::Event(Event::Frame(self.link, frame)))
            .map_err(|_| crate::CentralError::Stopped)
    }
}
