//! Answers that may arrive late through no fault of their sender: a reply to a query whose
//! asker went down, the end of a task that was killed (or whose sender died) while its handler
//! ran. Central remembers the last [`LATE_MEMORY`] of them so such an answer is dropped quietly
//! (a debug line; the frame itself is in the log) instead of being reported as bad input.

use std::collections::{HashMap, VecDeque};

use tca_messages::{MessageId, ModuleName};

/// How many expected late answers central remembers.
pub(super) const LATE_MEMORY: usize = 4096;

/// Ids whose answer from a given module would now come too late.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct LateAnswers {
    by_id: HashMap<MessageId, ModuleName>,
    order: VecDeque<MessageId>,
}

impl LateAnswers {
    /// An answer to `id` from `module` may still come and should be dropped.
    pub(super) fn expect(&mut self, id: MessageId, module: ModuleName) {
        if self.by_id.insert(id, module).is_none() {
            self.order.push_back(id);
        }
        while self.order.len() > LATE_MEMORY {
            if let Some(old) = self.order.pop_front() {
                self.by_id.remove(&old);
            }
        }
    }

    /// Whether an answer to `id` from `module` was expected to be late (and forgets it).
    pub(super) fn take(&mut self, id: MessageId, module: &ModuleName) -> bool {
        // Called for every task dispatched: nearly always with nothing remembered.
        if self.by_id.is_empty() {
            return false;
        }
        if self.by_id.get(&id) == Some(module) {
            self.by_id.remove(&id);
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembers_the_latest_and_only_for_their_module() {
        let m = |n: &str| ModuleName::new(n).unwrap();
        let mut late = LateAnswers::default();
        late.expect(MessageId::new(1, 1), m("ltm"));
        assert!(!late.take(MessageId::new(1, 1), &m("gait")));
        assert!(late.take(MessageId::new(1, 1), &m("ltm")));
        assert!(!late.take(MessageId::new(1, 1), &m("ltm")), "taken once");
        for seq in 0..(LATE_MEMORY as u32 + 5) {
            late.expect(MessageId::new(2, seq), m("ltm"));
        }
        assert!(
            !late.take(MessageId::new(2, 0), &m("ltm")),
            "the oldest are forgotten"
        );
        assert!(late.take(MessageId::new(2, LATE_MEMORY as u32 + 4), &m("ltm")));
    }
}
