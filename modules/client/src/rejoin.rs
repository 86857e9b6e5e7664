//! Rejoining central after it died and came back (zenoh and local links).
//!
//! A module over zenoh watches central's liveliness token. When the token is withdrawn, central
//! is gone (its process was killed, or the network dropped): the module goes *offline*. What
//! was in flight is lost with central, so the module fails its waiting queries at once with
//! [`ModuleError::CentralLost`](crate::ModuleError::CentralLost), stops its running handlers
//! (a central that comes back delivers their goals again, marked as redeliveries, or has
//! forgotten them), and refuses new sends with the same error. Its task watchers (the ends of
//! goals and commands it sent, awaited) fail the same way, unless central keeps a journal (its
//! welcome named one): then they wait for the central that comes back. Its zenoh session meanwhile keeps trying to reach the router,
//! backing off (see `tca_link::zenoh::RETRY_PERIOD_INIT_MS`).
//!
//! Over the local link the same happens when central's socket ends (EOF): the link says
//! central is down at once, connects again with the same backoff, and says it is up when a
//! central accepts the connection again.
//!
//! When central's token is back, the module says hello again and registers the same handlers;
//! when central welcomes it, it is *online* again and serves as before. Until then it repeats
//! its hello with exponential backoff ([`FIRST_RETRY`] doubling up to [`LONGEST_RETRY`]) in case
//! a hello was lost while the new central was starting.
//!
//! A central that welcomes it back with the same journal id restored the tasks of the one that
//! went away: the module asks it what became of the tasks its watchers wait for
//! (`tca.taskStatus`), delivers the ends told while it was away, fails those central never
//! received with `CentralLost`, and lets the live ones wait on. A central with another journal,
//! or none, knows nothing of them: they fail with `CentralLost`.

use std::time::Duration;

use tca_link::Presence;
use tca_messages::control::{ControlRequest, RegisterOutcome, Welcome};
use tca_messages::{
    Class, Envelope, MessageId, MessageName, ModuleName, RouteError, SendOptions, decode_data,
    now_ns,
};
use tokio::time::Instant;

use crate::error::{ModuleError, Result};
use crate::module::Module;

/// The first wait before saying hello again to a central that has not answered.
pub const FIRST_RETRY: Duration = Duration::from_millis(250);

/// The longest wait between two hellos.
pub const LONGEST_RETRY: Duration = Duration::from_secs(5);

/// How long a registration may go unanswered before the module starts over with a hello.
const REGISTER_PATIENCE: Duration = Duration::from_secs(5);

/// What a module says to join central: kept to say it again.
#[derive(Clone, Debug)]
pub(crate) struct Greeting {
    /// The hello (with credentials, when the module has them).
    pub(crate) hello: ControlRequest,
    /// The registration of every handler.
    pub(crate) register: ControlRequest,
}

/// Where a module stands with central.
#[derive(Debug)]
enum Phase {
    /// Registered; frames flow.
    Online,
    /// Central is gone or has not welcomed us yet: say hello at `next`.
    Hello { attempt: u32, next: Instant },
    /// Welcomed; the registration `id` awaits its answer until `deadline`.
    Register { id: MessageId, deadline: Instant },
}

/// The rejoin state machine of one zenoh module's receive loop.
#[derive(Debug)]
pub(crate) struct Rejoiner {
    greeting: Greeting,
    phase: Phase,
    /// Envelopes central sent between its welcome and the registration's answer: handled
    /// once the module is online again, never dropped.
    held: Vec<Envelope>,
    /// The central being rejoined keeps the journal of the one that went away: once online,
    /// ask it what became of the tasks the module waits for.
    resume: bool,
}

/// What the receive loop should do with an envelope after the rejoiner saw it.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// An ordinary envelope: handle it.
    Handle,
    /// Consumed by the handshake, or stale while offline: drop it.
    Consumed,
    /// Registered again: handle these envelopes (held during the registration) now.
    Online(Vec<Envelope>),
    /// Central refused the module on rejoining: the module cannot serve any more.
    Refused(String),
}

impl Rejoiner {
    pub(crate) fn new(greeting: Greeting) -> Self {
        Rejoiner {
            greeting,
            phase: Phase::Online,
            held: Vec::new(),
            resume: false,
        }
    }

    /// When the loop must wake up for the next hello or to give up on a registration.
    pub(crate) fn deadline(&self) -> Option<Instant> {
        match self.phase {
            Phase::Online => None,
            Phase::Hello { next, .. } => Some(next),
            Phase::Register { deadline, .. } => Some(deadline),
        }
    }

    /// Central appeared or vanished.
    pub(crate) fn on_presence(&mut self, module: &Module, presence: Presence) {
        if module.is_closed() {
            // Closed by the module itself: nothing to rejoin.
            return;
        }
        match (presence, &self.phase) {
            (Presence::Down, Phase::Online) => {
                tracing::warn!(module = %module.name(), "central went away; failing what was in flight and waiting for it to come back");
                module.go_offline();
                self.phase = Phase::Hello {
                    attempt: 0,
                    next: Instant::now() + FIRST_RETRY,
                };
            }
            (Presence::Down, _) => {
                self.phase = Phase::Hello {
                    attempt: 0,
                    next: Instant::now() + FIRST_RETRY,
                };
            }
            (Presence::Up, Phase::Online) => {}
            (Presence::Up, _) => {
                tracing::info!(module = %module.name(), "central is back; saying hello");
                self.say_hello(module, 0);
            }
        }
    }

    /// The deadline passed.
    pub(crate) fn on_timer(&mut self, module: &Module) {
        match self.phase {
            Phase::Online => {}
            Phase::Hello { attempt, .. } => self.say_hello(module, attempt + 1),
            Phase::Register { .. } => {
                tracing::warn!(module = %module.name(), "central did not answer the registration; saying hello again");
                self.say_hello(module, 0);
            }
        }
    }

    /// Sees every envelope from central first.
    pub(crate) fn on_envelope(&mut self, module: &Module, envelope: &Envelope) -> Verdict {
        match self.phase {
            Phase::Online => Verdict::Handle,
            Phase::Hello { attempt, next } => {
                if envelope.correlation != Some(MessageId::new(0, 0)) {
                    tracing::debug!(name = %envelope.name, "dropped while rejoining central");
                    return Verdict::Consumed;
                }
                if envelope.class != Class::Control {
                    return Verdict::Refused(refusal(envelope));
                }
                let welcome: Welcome = match decode_data(&envelope.data) {
                    Ok(w) => w,
                    Err(e) => {
                        tracing::warn!(error = %e, "bad welcome from central");
                        self.phase = Phase::Hello { attempt, next };
                        return Verdict::Consumed;
                    }
                };
                module.set_link(welcome.link);
                module.set_central_clock(welcome.simulated_clock);
                self.resume = module.rejoined(welcome.journal);
                let id = module.next_id();
                match self.send(module, &self.greeting.register, id) {
                    Ok(()) => {
                        self.phase = Phase::Register {
                            id,
                            deadline: Instant::now() + REGISTER_PATIENCE,
                        }
                    }
                    Err(e) => tracing::warn!(error = %e, "cannot send the registration"),
                }
                Verdict::Consumed
            }
            Phase::Register { id, .. } => {
                if envelope.correlation != Some(id) {
                    // Central may deliver before it answers the registration: keep it.
                    self.held.push(envelope.clone());
                    return Verdict::Consumed;
                }
                if envelope.class != Class::Reply {
                    return Verdict::Refused(refusal(envelope));
                }
                match decode_data::<RegisterOutcome>(&envelope.data) {
                    Ok(outcome) if outcome.refused.is_empty() => {
                        tracing::info!(module = %module.name(), link = id.link(), "rejoined central: registered again");
                        self.phase = Phase::Online;
                        module.go_online();
                        if std::mem::take(&mut self.resume) {
                            let module = module.clone();
                            tokio::spawn(async move { module.resume_watchers().await });
                        }
                        Verdict::Online(std::mem::take(&mut self.held))
                    }
                    Ok(outcome) => Verdict::Refused(
                        outcome
                            .refused
                            .into_iter()
                            .map(|(n, r)| format!("{n}: {r}"))
                            .collect::<Vec<_>>()
                            .join("; "),
                    ),
                    Err(e) => Verdict::Refused(format!("unreadable registration answer: {e}")),
                }
            }
        }
    }

    fn say_hello(&mut self, module: &Module, attempt: u32) {
        self.held.clear();
        let wait = FIRST_RETRY
            .saturating_mul(1 << attempt.min(8))
            .min(LONGEST_RETRY);
        if let Err(e) = self.send(module, &self.greeting.hello, MessageId::new(0, 0)) {
            tracing::warn!(error = %e, "cannot say hello to central");
        }
        self.phase = Phase::Hello {
            attempt,
            next: Instant::now() + wait,
        };
    }

    fn send(&self, module: &Module, request: &ControlRequest, id: MessageId) -> Result<()> {
        module.send_bootstrap(&bootstrap(module.name(), request, id)?)
    }
}

/// A handshake envelope: hello (id 0.0, before the link number is known) or registration.
pub(crate) fn bootstrap(
    name: &ModuleName,
    request: &ControlRequest,
    id: MessageId,
) -> Result<Envelope> {
    let data = request.encode_data()?;
    Ok(Envelope {
        id,
        class: Class::Control,
        name: MessageName::new(request.name()).map_err(|e| ModuleError::Usage(e.to_string()))?,
        sender: name.clone(),
        context: None,
        node: None,
        correlation: None,
        cause: None,
        timestamp_ns: now_ns(),
        options: SendOptions::default(),
        redelivery: 0,
        data,
    })
}

fn refusal(envelope: &Envelope) -> String {
    decode_data::<RouteError>(&envelope.data)
        .map(|e| e.to_string())
        .unwrap_or_else(|e| format!("unreadable answer: {e}"))
}
