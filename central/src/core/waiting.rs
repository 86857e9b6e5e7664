//! Messages held in central for a module that is down (§3.1: modules connect, crash and restart
//! at will). Held messages are bounded by count (`max_waiting`) and age (`max_wait`); past either
//! bound the sender gets an error that says so. Messages for a module that is up but does not
//! keep up (see `congestion`) are held here too, bounded by their senders' queue limits only.

use tca_messages::{Class, Envelope, MessageName, ModuleName, RouteError};

use super::{Action, Central};

/// A query, inform or exception held for a module that is down.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Waiting {
    pub(super) envelope: Envelope,
    /// Since when it has waited for a module that is down.
    pub(super) since_ns: u64,
    /// It counts against its sender's queue limits.
    pub(super) charged: bool,
}

impl Waiting {
    pub(super) fn new(envelope: Envelope, now: u64) -> Self {
        Waiting {
            envelope,
            since_ns: now,
            charged: false,
        }
    }
}

impl Central {
    /// How many messages wait for a module that is down.
    fn held_count(&self, module: &ModuleName) -> usize {
        self.modules
            .get(module)
            .map_or(0, |m| m.waiting.len() + m.ready.len())
    }

    /// Checks the count bound before holding another message for `module`.
    pub(super) fn check_room(&self, module: &ModuleName) -> Result<(), RouteError> {
        let held = self.held_count(module);
        let down = self.modules.get(module).is_none_or(|m| m.link.is_none());
        if down && held >= self.config.max_waiting as usize {
            return Err(RouteError::QueueFull {
                module: module.to_string(),
                waiting: held as u32,
                limit: self.config.max_waiting,
            });
        }
        Ok(())
    }

    /// Holds a message for a module that is down.
    pub(super) fn hold(
        &mut self,
        module: &ModuleName,
        mut waiting: Waiting,
    ) -> Result<(), RouteError> {
        self.check_room(module)?;
        let (sender, bytes) = (&waiting.envelope.sender, waiting.envelope.data.len());
        self.check_quota(sender, bytes)?;
        self.charge(&sender.clone(), bytes);
        waiting.charged = true;
        let now = self.now;
        let state = self.modules.entry(module.clone()).or_insert_with(|| {
            // A module registered by name in an earlier life of central's state, never seen
            // connected in this one, cannot happen (registration needs a connection); keep a
            // placeholder anyway so nothing is lost.
            super::ModuleState {
                link: None,
                hello: tca_messages::control::Hello {
                    module: module.clone(),
                    capacity: 1,
                    pid: 0,
                    host: String::new(),
                    simulated_time: false,
                },
                capacity: 1,
                running: 0,
                ready: Default::default(),
                waiting: Default::default(),
                down_since: Some(now),
                grant: None,
            }
        });
        state.waiting.push_back(waiting);
        Ok(())
    }

    /// Delivers what waited for `module`, now that it is connected and registered (or has
    /// read down its outbox).
    pub(super) fn deliver_waiting(&mut self, module: &ModuleName, out: &mut Vec<Action>) {
        let Some(state) = self.modules.get_mut(module) else {
            return;
        };
        let mut held = std::mem::take(&mut state.waiting);
        let mut keep = std::collections::VecDeque::new();
        while let Some(w) = held.pop_front() {
            let routed_here = self
                .registry
                .get(&w.envelope.name)
                .is_some_and(|e| &e.handler == module);
            if !routed_here {
                keep.push_back(w);
                continue;
            }
            // Each send may congest the link: the rest then waits for it to drain.
            let Some(link) = self.work_link(module) else {
                keep.push_back(w);
                keep.append(&mut held);
                break;
            };
            if w.charged {
                self.refund(&w.envelope.sender, w.envelope.data.len());
            }
            self.send(link, &w.envelope, out);
        }
        if let Some(state) = self.modules.get_mut(module) {
            state.waiting = keep;
        }
    }

    /// Moves what waits under `name` from one handler to its replacement.
    pub(super) fn move_pending(&mut self, name: &MessageName, from: &ModuleName, to: &ModuleName) {
        let (moved_waiting, moved_ready) = match self.modules.get_mut(from) {
            Some(state) => {
                let (go, stay): (Vec<_>, Vec<_>) = std::mem::take(&mut state.waiting)
                    .into_iter()
                    .partition(|w| &w.envelope.name == name);
                state.waiting = stay.into();
                let tasks = &self.tasks;
                let (go_ready, stay_ready): (Vec<_>, Vec<_>) = std::mem::take(&mut state.ready)
                    .into_iter()
                    .partition(|id| tasks.get(id).is_some_and(|t| &t.envelope.name == name));
                state.ready = stay_ready.into();
                (go, go_ready)
            }
            None => return,
        };
        for id in &moved_ready {
            if let Some(t) = self.tasks.get_mut(id) {
                t.handler = to.clone();
            }
        }
        // Tasks of that name not yet ready change handler too.
        for t in self.tasks.values_mut() {
            if &t.envelope.name == name && &t.handler == from && !t.running {
                t.handler = to.clone();
            }
        }
        if let Some(state) = self.modules.get_mut(to) {
            state.waiting.extend(moved_waiting);
            state.ready.extend(moved_ready);
        }
        for q in self.queries.values_mut() {
            if &q.handler == from && &q.name == name {
                q.handler = to.clone();
            }
        }
    }

    /// When the oldest held message expires, if any.
    pub(super) fn earliest_expiry(&self) -> Option<u64> {
        let limit = self.config.max_wait.as_nanos() as u64;
        self.modules
            .values()
            .filter(|m| m.link.is_none())
            .flat_map(|m| {
                let held = m.waiting.iter().map(|w| w.since_ns);
                let ready = m
                    .ready
                    .iter()
                    .filter_map(|id| self.tasks.get(id))
                    .map(|t| t.ready_since.max(m.down_since.unwrap_or(0)));
                held.chain(ready)
            })
            .min()
            .map(|since| since.saturating_add(limit))
    }

    /// Expires held messages older than `max_wait`, telling their senders.
    pub(super) fn expire_waiting(&mut self, out: &mut Vec<Action>) {
        let limit = self.config.max_wait.as_nanos() as u64;
        let now = self.now;
        let mut down: Vec<ModuleName> = self
            .modules
            .iter()
            .filter(|(_, m)| m.link.is_none())
            .map(|(n, _)| n.clone())
            .collect();
        down.sort_unstable();
        for module in down {
            let mut expired = Vec::new();
            let mut expired_tasks = Vec::new();
            if let Some(state) = self.modules.get_mut(&module) {
                let (old, young): (Vec<_>, Vec<_>) = std::mem::take(&mut state.waiting)
                    .into_iter()
                    .partition(|w| now.saturating_sub(w.since_ns) >= limit);
                state.waiting = young.into();
                expired = old;
                let down_since = state.down_since.unwrap_or(0);
                let tasks = &self.tasks;
                let (old, young): (Vec<_>, Vec<_>) = std::mem::take(&mut state.ready)
                    .into_iter()
                    .partition(|id| {
                        tasks.get(id).is_some_and(|t| {
                            now.saturating_sub(t.ready_since.max(down_since)) >= limit
                        })
                    });
                state.ready = young.into();
                expired_tasks = old;
            }
            for w in expired {
                if w.charged {
                    self.refund(&w.envelope.sender, w.envelope.data.len());
                }
                let waited = now.saturating_sub(w.since_ns);
                if w.envelope.class == Class::Query {
                    self.queries.remove(&w.envelope.id);
                }
                let error = RouteError::Expired {
                    module: module.to_string(),
                    waited_ms: waited / 1_000_000,
                    limit_ms: limit / 1_000_000,
                };
                let sender = w.envelope.sender.clone();
                self.send_error_to_module(&sender, &w.envelope, error, out);
            }
            for id in expired_tasks {
                self.expire_task(id, &module, limit, out);
            }
        }
    }
}
