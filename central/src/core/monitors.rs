//! Execution monitoring (TCA): a condition query checked once when a node starts (point
//! monitor) or periodically while it is active (polling monitor). The condition is a
//! registered query whose reply is a `bool`; `true` triggers the monitor's action once: raise
//! an exception in the node's context, or send a goal, command or inform (goals and commands
//! become children of the node). A monitor ends with its node. Central itself sends the
//! condition queries (as module `central`), so they are logged like any other traffic.

use tca_messages::control::{Monitor, MonitorAction};
use tca_messages::{Class, DataFormat, Envelope, MessageId, ModuleName, SendOptions, decode_data};

use super::routing::OpenQuery;
use super::{Action, Central, clock};

/// A live monitor.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct MonitorState {
    spec: Monitor,
    started: bool,
    next_poll: Option<u64>,
    in_flight: Option<MessageId>,
}

impl Central {
    /// `tca.monitor`: installs a monitor.
    pub(super) fn add_monitor(
        &mut self,
        module: &ModuleName,
        spec: Monitor,
        out: &mut Vec<Action>,
    ) -> Result<(), String> {
        if !self.tree.contains(spec.node.0) {
            return Err(format!("node {} is not live", spec.node));
        }
        let entry = self
            .registry
            .get(&spec.query)
            .ok_or_else(|| format!("the condition {} is not a registered query", spec.query))?;
        let bool_format = DataFormat::of::<bool>().map_err(|e| e.to_string())?;
        if entry.class != Class::Query || entry.reply.as_ref() != Some(&bool_format) {
            return Err(format!(
                "the condition {} must be a query whose reply is a bool",
                spec.query
            ));
        }
        match &spec.action {
            MonitorAction::Raise { .. } => {}
            MonitorAction::Send { class, name, .. } => {
                if !matches!(class, Class::Goal | Class::Command | Class::Inform) {
                    return Err(format!(
                        "a monitor may send a goal, command or inform, not a {class}"
                    ));
                }
                match self.registry.get(name) {
                    Some(e) if e.class == *class => {}
                    _ => return Err(format!("{name} is not registered as a {class}")),
                }
            }
        }
        if spec.period_ms == Some(0) {
            return Err("a polling monitor's period must be at least 1 ms".into());
        }
        tracing::debug!(node = %spec.node, query = %spec.query, by = %module, "monitor installed");
        let node = spec.node.0;
        self.monitors.push(MonitorState {
            spec,
            started: false,
            next_poll: None,
            in_flight: None,
        });
        if self.tree.has_started(node) {
            self.monitors_node_started(node, out);
        }
        Ok(())
    }

    /// Sets when monitor `i` checks next; on the simulated clock that is an event.
    fn schedule_poll(&mut self, i: usize, at: Option<u64>) {
        let Some(m) = self.monitors.get_mut(i) else {
            return;
        };
        m.next_poll = at;
        if self.clock.on
            && let Some(t) = at
        {
            let node = m.spec.node.0;
            self.clock.push(t, clock::Deferred::Poll { node });
        }
    }

    /// A node's handler started: its monitors check their condition now.
    pub(super) fn monitors_node_started(&mut self, node: u64, out: &mut Vec<Action>) {
        let now = self.tree_now();
        let due: Vec<usize> = self
            .monitors
            .iter()
            .enumerate()
            .filter(|(_, m)| m.spec.node.0 == node && !m.started)
            .map(|(i, _)| i)
            .collect();
        for i in due {
            if let Some(m) = self.monitors.get_mut(i) {
                m.started = true;
                m.next_poll = Some(now);
            }
        }
        self.poll_monitors(out);
    }

    /// A node ended: its monitors end with it.
    pub(super) fn monitors_node_ended(&mut self, node: u64) {
        self.monitors.retain(|m| m.spec.node.0 != node);
        self.clock.drop_polls(node);
    }

    /// When the next poll is due on the wall clock (on the simulated clock polls are events).
    pub(super) fn next_poll(&self) -> Option<u64> {
        if self.clock.on {
            return None;
        }
        self.monitors
            .iter()
            .filter(|m| m.in_flight.is_none())
            .filter_map(|m| m.next_poll)
            .min()
    }

    /// Sends the condition queries that are due.
    pub(super) fn poll_monitors(&mut self, out: &mut Vec<Action>) {
        let now = self.tree_now();
        for i in 0..self.monitors.len() {
            let due = self
                .monitors
                .get(i)
                .is_some_and(|m| m.in_flight.is_none() && m.next_poll.is_some_and(|t| t <= now));
            if !due {
                continue;
            }
            let spec = self.monitors[i].spec.clone();
            let Some(handler) = self.registry.get(&spec.query).map(|e| e.handler.clone()) else {
                continue;
            };
            let Some(link) = self.modules.get(&handler).and_then(|m| m.link) else {
                // The condition's module is down: try again a period later.
                self.schedule_poll(i, spec.period_ms.map(|p| now + p * 1_000_000));
                continue;
            };
            let mut query = self.central_envelope(
                Class::Query,
                spec.query.clone(),
                None,
                spec.query_data.clone(),
            );
            query.context = Some(spec.node);
            self.queries.insert(
                query.id,
                OpenQuery {
                    asker: self.central_name.clone(),
                    handler,
                    name: spec.query.clone(),
                },
            );
            self.monitors[i].in_flight = Some(query.id);
            self.monitors[i].next_poll = None;
            self.send(link, &query, out);
        }
    }

    /// An answer to one of central's condition queries.
    pub(super) fn monitor_answer(
        &mut self,
        query: MessageId,
        answer: Envelope,
        out: &mut Vec<Action>,
    ) {
        let Some(i) = self
            .monitors
            .iter()
            .position(|m| m.in_flight == Some(query))
        else {
            return; // the node ended meanwhile
        };
        self.monitors[i].in_flight = None;
        let holds = match answer.class {
            Class::Reply => decode_data::<bool>(&answer.data).map_err(|e| e.to_string()),
            other => Err(format!("the condition answered with {other}")),
        };
        let spec = self.monitors[i].spec.clone();
        match holds {
            Ok(true) => {
                self.monitors.remove(i);
                tracing::info!(node = %spec.node, query = %spec.query, "monitor triggered");
                self.trigger(spec, out);
            }
            Ok(false) => match spec.period_ms {
                Some(p) => self.schedule_poll(i, Some(self.tree_now() + p * 1_000_000)),
                None => {
                    self.monitors.remove(i);
                }
            },
            Err(reason) => {
                let reason = format!(
                    "monitor of {} could not check {}: {reason}",
                    spec.node, spec.query
                );
                self.problem(None, None, reason, &[], out);
                let next = spec.period_ms.map(|p| self.tree_now() + p * 1_000_000);
                self.schedule_poll(i, next);
            }
        }
    }

    fn trigger(&mut self, spec: Monitor, out: &mut Vec<Action>) {
        let node = spec.node;
        match spec.action {
            MonitorAction::Raise { name, data } => {
                let mut e = self.central_envelope(Class::Exception, name, None, data);
                e.context = Some(node);
                self.raise_internal(e, node.0, out);
            }
            MonitorAction::Send { class, name, data } => {
                let mut e = self.central_envelope(class, name, None, data);
                e.context = Some(node);
                e.options = SendOptions::default();
                let me = self.central_name.clone();
                match class {
                    Class::Goal | Class::Command => self.new_task(0, me, e, out),
                    _ => self.route_by_name(0, me, e, out),
                }
            }
        }
    }

    /// Whether a condition's answer is for central itself.
    pub(super) fn is_central(&self, module: &ModuleName) -> bool {
        module == &self.central_name
    }
}
