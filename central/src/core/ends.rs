//! How the latest watched tasks ended, and what a module asks about the tasks it sent
//! (`tca.taskStatus`).
//!
//! A task's end is told to its sender when the sender asked (a watched task), as a
//! `tca.taskEnded` notice on the sender's link. A sender that is away at that moment (its
//! process restarted, its link to a restarted central not yet back) misses the notice, and the
//! task is forgotten once it retires. So central remembers the ends of the latest
//! [`REMEMBERED`] watched tasks, told or not, and a module that comes back asks what became of
//! the tasks it still waits for: each is live (its end will be told), ended (and how), or
//! unknown to central (it never arrived, or ended too long ago).

use std::collections::VecDeque;

use rustc_hash::FxHashMap as HashMap;
use serde::{Deserialize, Serialize};
use tca_messages::control::{TaskOutcome, TaskState, TaskStatus, TaskStatusRequest};
use tca_messages::{MessageId, ModuleName};

use super::Central;

/// How many ends of watched tasks central remembers.
pub(super) const REMEMBERED: usize = 4096;

/// The ends of the latest watched tasks, by the id of the message that created each.
#[derive(Debug, Default, Serialize, Deserialize)]
pub(super) struct RecentEnds {
    by_id: HashMap<MessageId, (ModuleName, TaskOutcome)>,
    order: VecDeque<MessageId>,
}

impl RecentEnds {
    /// Remembers how task `id`, sent by `sender`, ended.
    pub(super) fn ended(&mut self, id: MessageId, sender: ModuleName, outcome: TaskOutcome) {
        if self.by_id.insert(id, (sender, outcome)).is_none() {
            self.order.push_back(id);
        }
        while self.order.len() > REMEMBERED {
            if let Some(old) = self.order.pop_front() {
                self.by_id.remove(&old);
            }
        }
    }

    fn outcome(&self, id: MessageId, sender: &ModuleName) -> Option<&TaskOutcome> {
        self.by_id
            .get(&id)
            .filter(|(s, _)| s == sender)
            .map(|(_, o)| o)
    }
}

impl Central {
    /// Where each task `module` asks about stands.
    pub(super) fn task_status(
        &self,
        module: &ModuleName,
        request: TaskStatusRequest,
    ) -> Vec<TaskStatus> {
        request
            .tasks
            .into_iter()
            .map(|task| {
                let live = self.tasks.get(&task).is_some_and(|t| &t.sender == module)
                    || self.clock.holds_task_frame(task, module);
                let state = if live {
                    TaskState::Live
                } else {
                    match self.ends.outcome(task, module) {
                        Some(outcome) => TaskState::Ended(outcome.clone()),
                        None => TaskState::Unknown,
                    }
                };
                TaskStatus { task, state }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_are_kept_for_their_sender_and_the_oldest_forgotten() {
        let m = |n: &str| ModuleName::new(n).unwrap();
        let mut ends = RecentEnds::default();
        ends.ended(MessageId::new(1, 1), m("walker"), TaskOutcome::Achieved);
        assert_eq!(
            ends.outcome(MessageId::new(1, 1), &m("walker")),
            Some(&TaskOutcome::Achieved)
        );
        assert_eq!(ends.outcome(MessageId::new(1, 1), &m("other")), None);
        for seq in 0..REMEMBERED as u32 {
            ends.ended(MessageId::new(2, seq), m("walker"), TaskOutcome::Killed);
        }
        assert_eq!(ends.outcome(MessageId::new(1, 1), &m("walker")), None);
        assert_eq!(ends.by_id.len(), REMEMBERED);
    }
}
