//! Modules that do not keep up with what central sends them.
//!
//! Each link has an outbox: the frames central sent it that it has not taken yet. The core
//! counts every frame it sends to a link on top of the level last measured. When that count
//! reaches half of `max_outbox_frames` or `max_outbox_bytes` the link counts as congested and
//! the core asks the driver to measure it ([`Action::Measure`]); the driver answers with
//! [`Event::OutboxLevel`](super::Event::OutboxLevel). A level under half ends the congestion at
//! once; a level at half or more keeps it, and the driver watches the outbox and reports again
//! once the link has taken it down to a quarter.
//!
//! While a link is congested its module gets no new work: goals and commands stay in its queue
//! of ready tasks, queries and informs are held for it as for a module that is down (without
//! `max_waiting` and without expiring: the module is there, only slow). Both count against
//! their senders' queue limits, so the senders are refused with an over-limit error once they
//! have too much waiting: backpressure instead of memory. Held work goes out, in order, when the
//! congestion ends, and only as much as fits under half the bound (the count stops it again).
//! Answers to the module's own requests (replies, errors, task ends), cancels, exceptions and
//! central's condition queries still go out; they are bounded by what the module asked for.
//!
//! A module whose outbox still goes past the bound has not read the answers to its own
//! requests: the driver reports [`Event::OutboxFull`](super::Event::OutboxFull), and the module
//! is disconnected with a problem record and a last error frame that says why; central then
//! does for it what it does for any module that goes down (queries it was answering fail at
//! their askers, its tasks and held messages wait for it to come back).

use tca_messages::{ModuleName, RouteError};

use super::{Action, Central, LinkId, OutboxUse};

impl Central {
    /// The link to give `module` new work on: connected and not congested.
    pub(super) fn work_link(&self, module: &ModuleName) -> Option<LinkId> {
        let link = self.modules.get(module)?.link?;
        match self.links.get(&link) {
            Some(l) if l.congested => None,
            _ => Some(link),
        }
    }

    /// Counts a frame of `len` bytes sent to `link`; asks for a measurement when the count
    /// reaches the congestion mark.
    pub(super) fn count_out(&mut self, link: LinkId, len: usize, out: &mut Vec<Action>) {
        let limits = self.outbox_limits;
        let Some(l) = self.links.get_mut(&link) else {
            return;
        };
        l.unread.frames += 1;
        l.unread.bytes += len as u64;
        if !l.congested && limits.congested(l.unread.frames, l.unread.bytes) {
            l.congested = true;
            out.push(Action::Measure(link));
        }
    }

    /// The driver measured a link's outbox.
    pub(super) fn outbox_level(&mut self, link: LinkId, used: OutboxUse, out: &mut Vec<Action>) {
        let limits = self.outbox_limits;
        let Some(l) = self.links.get_mut(&link) else {
            return;
        };
        l.unread = used;
        if limits.congested(used.frames, used.bytes) {
            // The driver watches it now; the next report comes when it has drained.
            l.congested = true;
            self.counters.congestions += 1;
            tracing::debug!(link, module = ?l.module, ?used, "outbox congested: holding new work");
            return;
        }
        let was = std::mem::replace(&mut l.congested, false);
        let Some(module) = l.module.clone() else {
            return;
        };
        if was {
            self.deliver_waiting(&module, out);
            self.dispatch(&module, out);
        }
    }

    pub(super) fn outbox_full(&mut self, link: LinkId, used: OutboxUse, out: &mut Vec<Action>) {
        let Some(l) = self.links.get(&link) else {
            return;
        };
        let module = l.module.clone();
        let who = module
            .as_ref()
            .map_or_else(|| format!("link {link}"), |m| format!("module {m}"));
        let reason = format!(
            "central disconnected {who} as too slow: {} frames ({} bytes) it had not read were \
             waiting for it, past max_outbox_frames = {} or max_outbox_bytes = {}; a module \
             must keep reading its link, or the answers to its own requests pile up",
            used.frames, used.bytes, self.config.max_outbox_frames, self.config.max_outbox_bytes
        );
        self.counters.too_slow += 1;
        self.problem(Some(link), module.clone(), reason.clone(), &[], out);
        if module.is_some() {
            // The last frame on the link, one past the bound: why it closes.
            self.send_error_raw(link, None, RouteError::Refused { reason }, out);
        }
        self.link_closed(link, out);
        out.push(Action::Close(link));
    }
}
