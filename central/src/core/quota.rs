//! Per-module resource accounting: how many messages (and data bytes) each *sending* module has
//! held in central, not yet delivered. A send past `max_queued_messages` or `max_queued_bytes`
//! is refused with [`RouteError::OverLimit`], so a flooding module is throttled while the
//! others keep their share.

use bytes::Bytes;
use tca_messages::{ModuleName, RouteError};

use super::{Action, Central, InboxUse, LinkId};

/// Messages and data bytes held for one sender.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Usage {
    /// Messages held.
    pub messages: u64,
    /// Their data bytes.
    pub bytes: u64,
}

impl Central {
    /// What `module` has queued in central now.
    pub fn queued_by(&self, module: &ModuleName) -> Usage {
        self.queued.get(module).copied().unwrap_or_default()
    }

    /// The most any one sender has had queued in central at once since central started
    /// (messages and bytes, each the maximum on its own).
    pub fn queued_high_water(&self) -> Usage {
        self.queued_high
    }

    /// Checks that `sender` may have one more message of `bytes` data bytes held.
    pub(super) fn check_quota(&self, sender: &ModuleName, bytes: usize) -> Result<(), RouteError> {
        if self.is_central(sender) {
            return Ok(());
        }
        let used = self.queued_by(sender);
        let max_messages = u64::from(self.config.max_queued_messages);
        if used.messages >= max_messages {
            return Err(RouteError::OverLimit {
                module: sender.to_string(),
                what: "messages queued in central".into(),
                used: used.messages,
                limit: max_messages,
                setting: "max_queued_messages".into(),
            });
        }
        let after = used.bytes.saturating_add(bytes as u64);
        // One message always fits when nothing is queued, whatever its size.
        if used.messages > 0 && after > self.config.max_queued_bytes {
            return Err(RouteError::OverLimit {
                module: sender.to_string(),
                what: "data bytes queued in central".into(),
                used: used.bytes,
                limit: self.config.max_queued_bytes,
                setting: "max_queued_bytes".into(),
            });
        }
        Ok(())
    }

    /// Counts a message now held for `sender`.
    pub(super) fn charge(&mut self, sender: &ModuleName, bytes: usize) {
        let u = self.queued.entry(sender.clone()).or_default();
        u.messages += 1;
        u.bytes = u.bytes.saturating_add(bytes as u64);
        self.queued_high.messages = self.queued_high.messages.max(u.messages);
        self.queued_high.bytes = self.queued_high.bytes.max(u.bytes);
    }

    /// A message held for `sender` was delivered or dropped.
    pub(super) fn refund(&mut self, sender: &ModuleName, bytes: usize) {
        if let Some(u) = self.queued.get_mut(sender) {
            u.messages = u.messages.saturating_sub(1);
            u.bytes = u.bytes.saturating_sub(bytes as u64);
            if u.messages == 0 {
                self.queued.remove(sender);
            }
        }
    }

    /// A frame refused at a full inbox: answered with an error naming the limit, never routed.
    pub(super) fn inbox_full(
        &mut self,
        link: LinkId,
        frame: Bytes,
        used: InboxUse,
        out: &mut Vec<Action>,
    ) {
        self.counters.frames_in += 1;
        let peer = self.links.get(&link).and_then(|l| l.module.clone());
        let max_frames = u64::from(self.config.max_inbox_frames.max(1));
        let (what, used, limit, setting) = if used.frames >= max_frames {
            (
                "frames waiting in central's inbox",
                used.frames,
                max_frames,
                "max_inbox_frames",
            )
        } else {
            let limit = self.config.max_inbox_bytes;
            (
                "bytes waiting in central's inbox",
                used.bytes,
                limit,
                "max_inbox_bytes",
            )
        };
        let Some(module) = peer else {
            let reason =
                format!("link {link} sent a frame before hello while over its inbox limit");
            return self.problem(Some(link), None, reason, &[], out);
        };
        let error = RouteError::OverLimit {
            module: module.to_string(),
            what: what.into(),
            used,
            limit,
            setting: setting.into(),
        };
        self.problem(Some(link), Some(module), error.to_string(), &[], out);
        match tca_messages::decode(&frame, self.config.max_frame_bytes) {
            // Answers (replies, ends) have nobody to tell; the problem record says it.
            Ok(envelope)
                if envelope.class.is_handled()
                    || envelope.class == tca_messages::Class::Control =>
            {
                self.send_error(link, &envelope, error, out)
            }
            Ok(_) => {}
            Err(_) => {
                self.counters.bad_frames += 1;
                self.send_error_raw(link, None, error, out);
            }
        }
    }

    /// Frames dropped unanswered at a full inbox: logged, and the module told once.
    pub(super) fn inbox_dropped(&mut self, link: LinkId, count: u64, out: &mut Vec<Action>) {
        self.counters.frames_in += count;
        let peer = self.links.get(&link).and_then(|l| l.module.clone());
        let reason = format!(
            "{count} frames from link {link} were dropped unanswered: its inbox in central and \
             the queue of refusals were full; send more slowly or raise max_inbox_frames"
        );
        self.problem(Some(link), peer.clone(), reason.clone(), &[], out);
        if peer.is_some() {
            self.send_error_raw(link, None, RouteError::Refused { reason }, out);
        }
    }

    /// The accounting recomputed from scratch (tests check it against the running totals).
    #[cfg(test)]
    pub(super) fn recount_queued(&self) -> std::collections::BTreeMap<ModuleName, (u64, u64)> {
        let mut map = std::collections::BTreeMap::<ModuleName, (u64, u64)>::new();
        let held = self
            .modules
            .values()
            .flat_map(|m| m.waiting.iter())
            .filter(|w| w.charged)
            .map(|w| (&w.envelope.sender, w.envelope.data.len()));
        let tasks = self
            .tasks
            .values()
            .filter(|t| t.charged)
            .map(|t| (&t.sender, t.envelope.data.len()));
        for (sender, bytes) in held.chain(tasks) {
            let e = map.entry(sender.clone()).or_default();
            e.0 += 1;
            e.1 += bytes as u64;
        }
        map
    }

    /// The running totals, in the shape of [`Central::recount_queued`].
    #[cfg(test)]
    pub(super) fn queued_totals(&self) -> std::collections::BTreeMap<ModuleName, (u64, u64)> {
        self.queued
            .iter()
            .map(|(m, u)| (m.clone(), (u.messages, u.bytes)))
            .collect()
    }
}
