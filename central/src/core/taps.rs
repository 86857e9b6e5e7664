//! Taps: copies of the traffic of some message names for the modules that asked
//! (`tca.tap`; `tca echo`), and the task controls of the command line: kill a task by the id
//! of its message, kill every tree.
//!
//! A tapped message is copied, as a [`Tapped`] notice, when a module sends it to central or
//! when central sends it on its own (an error about it, a monitor's action); never control
//! traffic. Taps end when their module's link closes.
//!
//! On the simulated clock, a kill from a tool on the wall clock (a person at the command line)
//! acts at once instead of waiting its turn in the event queue: an emergency stop cannot wait
//! for a running handler (a move playing out) to finish. Killing every tree there also drops
//! the goals and commands still queued that would have started new trees. Under a policy, a module taps only names
//! it may send, and every name only if its `send` rules include `"*"`.

use rustc_hash::FxHashSet as HashSet;
use tca_messages::control::{CONTROL_PREFIX, ControlKind, ControlNotice, Tap, Tapped};
use tca_messages::{
    Class, Envelope, MessageId, MessageName, ModuleName, NodeId, RouteError, is_simulated_stamp,
};

use super::{Action, Central};

/// What one module taps.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) enum TapSet {
    /// Every name.
    All,
    /// These names.
    Names(HashSet<MessageName>),
}

impl TapSet {
    fn matches(&self, name: &MessageName) -> bool {
        match self {
            TapSet::All => true,
            TapSet::Names(names) => names.contains(name),
        }
    }
}

impl Central {
    /// Sets what `module` taps (replacing its previous tap).
    pub(super) fn set_tap(&mut self, module: &ModuleName, tap: Tap) -> Result<(), String> {
        if let Some(grant) = self.modules.get(module).and_then(|m| m.grant.as_ref()) {
            if tap.names.is_empty() && !grant.permissions().send.iter().any(|p| p == "*") {
                return Err(format!(
                    "tapping every message name needs send = [\"*\"] in the policy for {}; \
                     tap the names it may send instead",
                    grant.permissions().who
                ));
            }
            for name in &tap.names {
                grant
                    .may_send(name.as_str())
                    .map_err(|rule| format!("module {module} may not tap {name}: {rule}"))?;
            }
        }
        let set = if tap.names.is_empty() {
            TapSet::All
        } else {
            TapSet::Names(tap.names.into_iter().collect())
        };
        self.taps.insert(module.clone(), set);
        Ok(())
    }

    /// Forgets the tap of a module that left.
    pub(super) fn drop_tap(&mut self, module: &ModuleName) {
        self.taps.remove(module);
    }

    /// Copies `envelope` to every module that taps its name.
    pub(super) fn tap_copy(&mut self, envelope: &Envelope, out: &mut Vec<Action>) {
        if self.taps.is_empty()
            || envelope.class == Class::Control
            || envelope.name.as_str().starts_with(CONTROL_PREFIX)
        {
            return;
        }
        let mut links: Vec<_> = self
            .taps
            .iter()
            .filter(|(_, set)| set.matches(&envelope.name))
            .filter_map(|(m, _)| self.modules.get(m).and_then(|s| s.link))
            .collect();
        links.sort_unstable();
        if links.is_empty() {
            return;
        }
        let notice = ControlNotice::Tapped(Box::new(Tapped {
            envelope: envelope.clone(),
        }));
        for link in links {
            let copy = self.notice_envelope(&notice, None);
            self.send(link, &copy, out);
        }
    }

    /// Whether `envelope` is a kill from a module on the wall clock while central keeps the
    /// simulated clock: it acts now, not in its turn.
    pub(super) fn kill_acts_now(&self, envelope: &Envelope) -> bool {
        self.clock.on
            && envelope.class == Class::Control
            && !is_simulated_stamp(envelope.timestamp_ns)
            && matches!(
                ControlKind::from_name(envelope.name.as_str()),
                Some(ControlKind::Kill | ControlKind::KillTask | ControlKind::KillAll)
            )
    }

    /// Kills the node of the goal or command that message `task` created.
    pub(super) fn kill_task(
        &mut self,
        task: MessageId,
        cause: Option<MessageId>,
        out: &mut Vec<Action>,
    ) -> Result<(), String> {
        let Some(node) = self.tasks.get(&task).map(|t| t.node) else {
            // On the simulated clock it may still wait in the queue, not yet a task.
            if self.clock.on
                && let Some((link, envelope)) = self.clock.take_task_frame(task)
            {
                let reason = format!("{} {task} was killed before it started", envelope.class);
                self.send_error(link, &envelope, RouteError::Refused { reason }, out);
                return Ok(());
            }
            return Err(format!(
                "no live task was created by message {task} (it has ended, or was not a goal \
                 or command); `tca tree` shows the live nodes"
            ));
        };
        self.kill_node(NodeId(node), cause, out)
    }

    /// Kills every task tree; returns how many there were. The trees are all killed before
    /// central acts on what that frees, so no waiting task starts in between (an emergency
    /// stop must not release the next move).
    pub(super) fn kill_all(&mut self, cause: Option<MessageId>, out: &mut Vec<Action>) -> u64 {
        let mut roots: Vec<u64> = self
            .tasks
            .values()
            .filter(|t| t.root)
            .map(|t| t.node)
            .collect();
        roots.sort_unstable();
        roots.dedup();
        let mut killed = 0;
        let mut events = Vec::new();
        let now = self.tree_now();
        for node in roots {
            if !self.tree.contains(node) {
                continue;
            }
            match self.tree.kill(node, now, cause.map(|m| m.0), out) {
                Ok(e) => {
                    killed += 1;
                    events.extend(e);
                }
                Err(reason) => tracing::debug!(node, %reason, "a root could not be killed"),
            }
        }
        self.tree_events(events, out);
        if self.clock.on {
            for (link, envelope) in self.clock.take_root_tasks() {
                let reason = format!(
                    "every task tree was killed (an emergency stop) before this {} was started",
                    envelope.class
                );
                self.send_error(link, &envelope, RouteError::Refused { reason }, out);
            }
        }
        killed
    }
}
