//! What goes into and comes out of the core.

use bytes::Bytes;
use tca_logs::LogRecord;

pub use tca_link::{InboxUse, LinkId, OutboxUse};

/// Something that happened to central.
#[derive(Clone, Debug)]
pub enum Event {
    /// A link opened (the module will say hello next).
    Opened(LinkId),
    /// The transport authenticated the link's peer as this identity of the policy (its zenoh
    /// user or certificate common name, which the router's access control confines to its own
    /// keys). Comes right after `Opened`, before any frame; the module's hello is then held to
    /// that identity.
    Identified(LinkId, String),
    /// A frame arrived on a link.
    Frame(LinkId, Bytes),
    /// A link closed: the module left or crashed.
    Closed(LinkId),
    /// Time passed: check deadlines (waiting messages that are too old).
    Tick,
    /// A frame the link sent while its inbox in central was full: it is answered with
    /// an over-limit error and not routed.
    InboxFull(LinkId, Bytes, InboxUse),
    /// Frames the link sent while its inbox and its refusal queue were full: dropped unanswered.
    InboxDropped(LinkId, u64),
    /// How many frames sent to the link it has not taken yet (its outbox), as measured after
    /// an [`Action::Measure`] or when a watched outbox drained. At half of `max_outbox_frames`
    /// or `max_outbox_bytes` or more the link is congested and the driver watches it: another
    /// report follows once the link has taken it down to a quarter.
    OutboxLevel(LinkId, OutboxUse),
    /// The link's outbox went past its bound: the module is disconnected as too slow.
    OutboxFull(LinkId, OutboxUse),
}

/// Something central wants done.
#[derive(Clone, Debug)]
pub enum Action {
    /// Send a frame on a link.
    Send(LinkId, Bytes),
    /// Append a record to the traffic log.
    Log(LogRecord),
    /// Close a link (after a refused hello or a protocol violation).
    Close(LinkId),
    /// Measure the link's outbox and report it as [`Event::OutboxLevel`]: the frames central
    /// counted out to it since the last report reached half its bound.
    Measure(LinkId),
}
