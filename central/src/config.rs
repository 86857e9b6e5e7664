//! Central's configuration.

use std::sync::Arc;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::policy::Policy;

/// Limits and defaults of central. Every field has a sensible default.
///
/// # Resource limits
///
/// Three layers keep one module from hurting the others, and central's memory bounded:
///
/// - **Inbox** (`max_inbox_frames`, `max_inbox_bytes`): frames a link has sent that central has
///   not handled yet. Central serves links' inboxes in turn (round robin), so a flooding module
///   only delays itself; a frame arriving at a full inbox is refused with
///   [`RouteError::OverLimit`](tca_messages::RouteError::OverLimit): at once as the send's
///   error in-process, as an error envelope over zenoh. One frame is always accepted into an
///   empty inbox, whatever its size (up to `max_frame_bytes`).
/// - **Queued in central** (`max_queued_messages`, `max_queued_bytes`): messages a module sent
///   that central holds (goals and commands waiting for constraints or for their handler's
///   capacity, messages held for a handler that is down), counted against the *sender*. A send
///   past either limit is refused with `OverLimit`; the module may send again once central has
///   delivered some.
/// - **Outbox** (`max_outbox_frames`, `max_outbox_bytes`): frames central has sent to a link
///   that the link has not taken yet (a slow module). Central never waits for a link: at half
///   either limit it gives that module no new work (goals and commands stay queued in central,
///   queries and informs are held for it, all counted against their senders' queue limits, so
///   the senders meet over-limit refusals) until the module has read its outbox down to a
///   quarter. Past the limit, which only a module that does not read the answers to its own
///   requests reaches, the module is disconnected as too slow (logged, told in a last error
///   frame, and treated as any module that went down). One frame always fits an empty outbox.
/// - **Log** (`max_log_backlog`): records waiting for the traffic-log writer. When the writer
///   falls that far behind, central takes no frames from modules until it is back under half;
///   the frames wait in the inboxes above.
///
/// # Authentication and authorisation
///
/// `policy` (loaded from a TOML file with [`Policy::load`], `tca central --policy FILE`)
/// makes central check every hello against the policy's identities (identity + secret,
/// secrets stored as salted SHA3-256 hashes) and every registration and send against the
/// identity's `register` and `send` globs; its `[transport] zenoh_users_file` and
/// `[transport.tls]` also make the zenoh router authenticate clients (zenoh login, client
/// certificates) and confine each identity to its own keys. See [`crate::policy`] for the
/// file format. Without a policy, central admits every module, as before.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CentralConfig {
    /// Largest frame accepted, in bytes.
    pub max_frame_bytes: usize,
    /// Most messages that may wait in central for one module while it is down.
    pub max_waiting: u32,
    /// Longest a message waits for a module that is down before its sender gets an error.
    #[serde(with = "duration_ms")]
    pub max_wait: Duration,
    /// Goals/commands a module handles at once when its hello says 0.
    pub default_capacity: u32,
    /// Most frames of one link waiting to be handled by central (its inbox).
    pub max_inbox_frames: u32,
    /// Most bytes of one link's frames waiting to be handled by central (its inbox).
    pub max_inbox_bytes: u64,
    /// Most messages of one sending module that central may hold at once (not yet delivered:
    /// goals/commands waiting for their constraints or their handler, messages held for a
    /// handler that is down).
    pub max_queued_messages: u32,
    /// Most data bytes of those held messages, per sending module.
    pub max_queued_bytes: u64,
    /// Most frames sent to one link and not yet taken by it (its outbox); central stops
    /// giving the module new work at half of this and disconnects it past it.
    pub max_outbox_frames: u32,
    /// Most bytes of those frames, with the same two marks.
    pub max_outbox_bytes: u64,
    /// Most records handed to the traffic-log writer and not yet written. At this many,
    /// central stops taking frames from modules (they wait in the modules' inboxes, so modules
    /// meet over-limit refusals) until the writer is back under half: the log's pace is
    /// central's.
    pub max_log_backlog: u32,
    /// User ids besides central's own whose processes may connect to central's local sockets
    /// (`--listen local`). The kernel tells central each peer's user id; everyone else is
    /// refused at connection, before any hello. The socket's directory (0700) and file (0600)
    /// keep other users out as well: to admit one, also give it access to them.
    pub local_peer_uids: Vec<u32>,
    /// Who may connect, register and send (None: everyone may do everything).
    #[serde(skip)]
    pub policy: Option<Arc<Policy>>,
    /// Keep the system's simulated clock (a discrete-event clock): release messages in
    /// simulated-time order, one at a time, and move the clock on only when every handler of
    /// a simulated module has finished or waits for an answer. Off (the default), messages
    /// are routed as they arrive, on the wall clock, as a real robot's system needs. See
    /// `core::clock`.
    pub simulated_time: bool,
}

impl Default for CentralConfig {
    fn default() -> Self {
        CentralConfig {
            max_frame_bytes: tca_messages::DEFAULT_MAX_FRAME_BYTES,
            max_waiting: 1024,
            max_wait: Duration::from_secs(60),
            default_capacity: 1,
            // Generous: a legitimate burst (a benchmark sending 100,000 goals in a loop) fits;
            // a module that floods without end is stopped within ~100 MB of central's memory.
            max_inbox_frames: 1 << 18,
            max_inbox_bytes: 64 << 20,
            max_queued_messages: 1 << 18,
            max_queued_bytes: 256 << 20,
            // A module that keeps reading stays far below this; one that stops costs central
            // at most ~64 MB before it is disconnected.
            max_outbox_frames: 1 << 16,
            max_outbox_bytes: 64 << 20,
            // About 20 to 30 MB of records (each holds its frame).
            max_log_backlog: 1 << 17,
            local_peer_uids: Vec::new(),
            policy: None,
            simulated_time: false,
        }
    }
}

mod duration_ms {
    use serde::{Deserialize, Deserializer, Serializer};
    use std::time::Duration;

    pub(super) fn serialize<S: Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(d.as_millis() as u64)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Duration, D::Error> {
        Ok(Duration::from_millis(u64::deserialize(d)?))
    }
}
