//! The registry: which module handles which message, with which data format.

use tca_logs::{LogRecord, RecordKind, RegisteredRecord};
use tca_messages::control::{Register, RegisterOutcome, Registration, Registry, RegistryEntry};
use tca_messages::{Class, DataFormat, Envelope, MessageName, ModuleName, RouteError};

use super::{Action, Central, LinkId};

/// One registered message.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Entry {
    pub(super) class: Class,
    pub(super) handler: ModuleName,
    pub(super) format: DataFormat,
    pub(super) reply: Option<DataFormat>,
}

impl Central {
    pub(super) fn register(
        &mut self,
        link: LinkId,
        module: ModuleName,
        envelope: &Envelope,
        request: Register,
        out: &mut Vec<Action>,
    ) {
        let mut outcome = RegisterOutcome::default();
        for entry in request.entries {
            let name = entry.name.clone();
            match self.register_one(&module, entry, out) {
                Ok(()) => outcome.accepted.push(name),
                Err(reason) => {
                    self.problem(Some(link), Some(module.clone()), reason.clone(), &[], out);
                    outcome.refused.push((name, reason));
                }
            }
        }
        self.reply_control(link, envelope, &outcome, out);
        // Whatever waited for this module can go now that it handles its messages again.
        self.deliver_waiting(&module, out);
        self.dispatch(&module, out);
    }

    fn register_one(
        &mut self,
        module: &ModuleName,
        reg: Registration,
        out: &mut Vec<Action>,
    ) -> Result<(), String> {
        let name = &reg.name;
        if let Err(reason) = self.permit_registration(module, name.as_str()) {
            self.counters.not_permitted += 1;
            return Err(reason);
        }
        if name.is_control() {
            return Err(format!(
                "{name}: names starting with \"tca.\" are reserved for central"
            ));
        }
        if !reg.class.is_handled() {
            return Err(format!(
                "{name}: a module cannot handle class {}; register query, goal, command, \
                 inform or exception",
                reg.class
            ));
        }
        reg.format.validate().map_err(|e| format!("{name}: {e}"))?;
        match (&reg.reply, reg.class) {
            (None, Class::Query) => {
                return Err(format!("{name}: a query registration needs a reply format"));
            }
            (Some(_), c) if c != Class::Query => {
                return Err(format!("{name}: only queries have a reply format"));
            }
            (Some(r), _) => r.validate().map_err(|e| format!("{name} reply: {e}"))?,
            _ => {}
        }
        if let Some(existing) = self.registry.get(name) {
            if existing.class != reg.class {
                return Err(format!(
                    "{name} is already registered as a {} (by {}); it cannot be registered as a {}",
                    existing.class, existing.handler, reg.class
                ));
            }
            let mut diffs = existing.format.differences(&reg.format);
            if let (Some(a), Some(b)) = (&existing.reply, &reg.reply) {
                diffs.extend(a.differences(b).into_iter().map(|d| format!("reply {d}")));
            }
            if !diffs.is_empty() {
                return Err(format!(
                    "{name}: data format differs from the one registered by {}: {}",
                    existing.handler,
                    diffs.join("; ")
                ));
            }
            if &existing.handler != module {
                if !reg.replace {
                    return Err(format!(
                        "{name} is already handled by module {}; to take it over, register it \
                         with replace",
                        existing.handler
                    ));
                }
                let previous = existing.handler.clone();
                tracing::info!(%name, from = %previous, to = %module, "handler replaced");
                self.move_pending(name, &previous, module);
            }
        } else if let Some(similar) = self.folded.get(&name.fold()) {
            // Not an error (names differ), but worth a warning: §7.1 lost days to this.
            tracing::warn!(%name, %similar, "registered name differs from another only in spelling");
        }
        self.folded.insert(name.fold(), name.clone());
        self.registry.insert(
            name.clone(),
            Entry {
                class: reg.class,
                handler: module.clone(),
                format: reg.format.clone(),
                reply: reg.reply.clone(),
            },
        );
        out.push(Action::Log(LogRecord {
            at_ns: self.now,
            kind: RecordKind::Registered(RegisteredRecord {
                module: module.clone(),
                registration: reg,
            }),
        }));
        Ok(())
    }

    /// The registry, for `tca.registry`.
    pub(super) fn registry_view(&self) -> Registry {
        let entries = self
            .registry
            .iter()
            .map(|(name, e)| {
                let module = self.modules.get(&e.handler);
                let waiting = module.map_or(0, |m| {
                    m.waiting
                        .iter()
                        .filter(|w| &w.envelope.name == name)
                        .count()
                        + m.ready
                            .iter()
                            .filter(|id| {
                                self.tasks.get(id).is_some_and(|t| &t.envelope.name == name)
                            })
                            .count()
                });
                RegistryEntry {
                    name: name.clone(),
                    class: e.class,
                    handler: e.handler.clone(),
                    connected: module.is_some_and(|m| m.link.is_some()),
                    format: e.format.clone(),
                    reply: e.reply.clone(),
                    waiting: waiting as u32,
                }
            })
            .collect();
        Registry {
            entries,
            modules: self.connected_modules(),
        }
    }

    /// Looks up the handler of a message, checking its class.
    pub(super) fn lookup(&self, envelope: &Envelope) -> Result<&Entry, RouteError> {
        match self.registry.get(&envelope.name) {
            Some(e) if e.class == envelope.class => Ok(e),
            Some(e) => Err(RouteError::WrongClass {
                name: envelope.name.to_string(),
                registered: e.class.to_string(),
                sent: envelope.class.to_string(),
            }),
            None => Err(RouteError::UnknownMessage {
                name: envelope.name.to_string(),
                suggestion: self
                    .folded
                    .get(&envelope.name.fold())
                    .map(MessageName::to_string),
            }),
        }
    }
}
