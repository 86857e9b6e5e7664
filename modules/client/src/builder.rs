//! Building a module: its name, capacity and handlers, then connecting.

use std::collections::HashMap;
use std::future::Future;
use std::time::Duration;

use tca_link::FrameReceiver;
use tca_messages::control::{
    ControlRequest, Credentials, Hello, Register, RegisterOutcome, Welcome,
};
use tca_messages::{
    Class, DEFAULT_MAX_FRAME_BYTES, Envelope, Message, MessageId, MessageName, ModuleName,
    RouteError, decode, decode_data, encode,
};

use crate::connector::Connector;
use crate::context::Context;
use crate::credentials::{credentials_from_env, hello_request};
use crate::error::{HandlerError, ModuleError, Result};
use crate::handler::{HandlerEntry, erase};
use crate::module::{DEFAULT_QUERY_TIMEOUT, Module, Settings};
use crate::rejoin::{Greeting, Rejoiner, bootstrap};

/// A sensible [`ModuleBuilder::requery_after_crash`] for modules whose peers are restarted
/// when they crash: a query survives this many crashes of the module answering it.
pub const REQUERIES_AFTER_CRASH: u32 = 3;

/// How long connecting waits for central's welcome and registration answer.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);

/// Builds a module. See the crate documentation for an example.
pub struct ModuleBuilder {
    name: String,
    capacity: u32,
    query_timeout: Duration,
    requery_after_crash: u32,
    max_frame_bytes: usize,
    replace: bool,
    sim_time: bool,
    handlers: HashMap<MessageName, HandlerEntry>,
    error: Option<ModuleError>,
    credentials: Option<Credentials>,
}

impl Module {
    /// Starts building a module named `name`.
    pub fn builder(name: impl Into<String>) -> ModuleBuilder {
        ModuleBuilder {
            name: name.into(),
            capacity: 1,
            query_timeout: DEFAULT_QUERY_TIMEOUT,
            requery_after_crash: 0,
            max_frame_bytes: DEFAULT_MAX_FRAME_BYTES,
            replace: false,
            sim_time: false,
            handlers: HashMap::new(),
            error: None,
            credentials: None,
        }
    }
}

impl ModuleBuilder {
    /// How many goals/commands central may give this module at once (default 1, TCA's
    /// resource management). Queries and informs are not counted.
    pub fn capacity(mut self, capacity: u32) -> Self {
        self.capacity = capacity.max(1);
        self
    }

    /// How long queries wait for their answer (default 30 s).
    pub fn query_timeout(mut self, timeout: Duration) -> Self {
        self.query_timeout = timeout;
        self
    }

    /// Send a query again, up to `times` times, when the module answering it dies before it
    /// answers (central then fails the query with
    /// [`RouteError::HandlerDied`](tca_messages::RouteError::HandlerDied)); the new query waits
    /// in central until that module is back. Queries only ask for information, so asking again
    /// is safe. Default 0: the caller sees the failure at once.
    pub fn requery_after_crash(mut self, times: u32) -> Self {
        self.requery_after_crash = times;
        self
    }

    /// Largest frame this module sends.
    pub fn max_frame_bytes(mut self, bytes: usize) -> Self {
        self.max_frame_bytes = bytes;
        self
    }

    /// Stamp messages with simulated time instead of the wall clock: each handler's clock
    /// starts at the time its message was sent, follows the answers it receives and advances
    /// by what it [`spend`](Module::spend)s. Modules of a simulation (a simulated controller
    /// whose moves take simulated seconds) use it so that durations are comparable with the
    /// real mechanism's while the simulation runs as fast as it can.
    pub fn simulated_time(mut self, on: bool) -> Self {
        self.sim_time = on;
        self
    }

    /// Log in to central as `identity` with `secret` (checked against central's policy file).
    /// Without it the module uses `TCA_IDENTITY` and `TCA_SECRET` when both are set, else
    /// connects anonymously.
    pub fn identity(mut self, identity: impl Into<String>, secret: impl Into<String>) -> Self {
        self.credentials = Some(Credentials {
            identity: identity.into(),
            secret: secret.into(),
        });
        self
    }

    /// Take over the messages this module registers from any module that registered them
    /// before (swapping implementations, e.g. the simulator for the real controller).
    pub fn replace(mut self, replace: bool) -> Self {
        self.replace = replace;
        for entry in self.handlers.values_mut() {
            entry.registration.replace = replace;
        }
        self
    }

    /// Registers the handler of message type `M` (a query, goal, command, inform or
    /// exception). For queries the handler returns the reply; for the others `()`.
    ///
    /// Order: the handler (the closure) is called in the order its messages arrive, one at a
    /// time, and the future it returns then runs beside the others. Work the closure does
    /// before it returns its future (writing a record, taking a sample into a queue) is
    /// therefore done in arrival order; work inside the future may interleave. Keep that
    /// synchronous part short: the module receives nothing else while it runs.
    pub fn handle<M, F, Fut>(self, handler: F) -> Self
    where
        M: Message,
        F: Fn(Context, M) -> Fut + Send + Sync + 'static,
        Fut: Future<Output = Result<M::Reply, HandlerError>> + Send + 'static,
    {
        let replace = self.replace;
        self.add_handler(erase::<M, F, Fut>(handler, replace))
    }

    /// Registers a handler of encoded data: the registration (name, class, data and reply
    /// formats) is given at run time instead of by a Rust type, and the handler gets the
    /// postcard data and returns the postcard reply (queries; ignored for the other classes).
    /// For tools that stand in for a module they were not compiled with, such as
    /// `tca log replay`, which plays a module back from a traffic log. `registration.replace`
    /// follows [`ModuleBuilder::replace`]. Called in arrival order as [`ModuleBuilder::handle`]
    /// says.
    pub fn handle_raw<F, Fut>(
        self,
        mut registration: tca_messages::control::Registration,
        handler: F,
    ) -> Self
    where
        F: Fn(Context, Vec<u8>) -> Fut + Send + Sync + 'static,
        Fut: Future<Output = Result<Vec<u8>, HandlerError>> + Send + 'static,
    {
        registration.replace = self.replace;
        self.add_handler(crate::handler::erase_raw(registration, handler))
    }

    /// Adds an erased handler, keeping the first error (a bad type, a second handler).
    fn add_handler(mut self, entry: Result<HandlerEntry>) -> Self {
        let error = match entry {
            Ok(entry) => {
                let name = entry.registration.name.clone();
                match self.handlers.insert(name.clone(), entry) {
                    Some(_) => Some(ModuleError::Usage(format!(
                        "two handlers for {name} in module {}",
                        self.name
                    ))),
                    None => None,
                }
            }
            Err(e) => Some(e),
        };
        if self.error.is_none() {
            self.error = error;
        }
        self
    }

    /// Connects to central, says hello, registers every handler and starts serving.
    pub async fn connect(self, connector: &Connector) -> Result<Module> {
        if let Some(e) = self.error {
            return Err(e);
        }
        let name =
            ModuleName::new(self.name.clone()).map_err(|e| ModuleError::Usage(e.to_string()))?;
        let mut link = connector.open().await?;
        // Hello, before the link number is known: id 0.0.
        let hello = Hello {
            module: name.clone(),
            capacity: self.capacity,
            pid: std::process::id(),
            host: tca_messages::control::this_host(),
            simulated_time: self.sim_time,
        };
        let credentials = self.credentials.or_else(credentials_from_env);
        let hello = hello_request(hello, credentials);
        let hello_env = bootstrap(&name, &hello, MessageId::new(0, 0))?;
        link.sender.send(encode(&hello_env)?.into())?;
        // Central may deliver messages waiting for this module as soon as it is welcomed,
        // before the registration is answered: they are kept and handled first.
        let mut early = Vec::new();
        let answer = next_answer(&mut link.receiver, hello_env.id, connector, &mut early).await?;
        let welcome: Welcome = match answer.class {
            Class::Control => decode_data(&answer.data)?,
            _ => {
                let reason = decode_data::<RouteError>(&answer.data)
                    .map(|e| e.to_string())
                    .unwrap_or_else(|e| e.to_string());
                return Err(ModuleError::Refused {
                    module: name.to_string(),
                    reason,
                });
            }
        };
        // Register every handler, in name order (the same registration on every run).
        let mut entries: Vec<_> = self
            .handlers
            .values()
            .map(|h| h.registration.clone())
            .collect();
        entries.sort_by(|a, b| a.name.cmp(&b.name));
        let register = ControlRequest::Register(Register { entries });
        let reg_id = MessageId::new(welcome.link, 1);
        let reg_env = bootstrap(&name, &register, reg_id)?;
        link.sender.send(encode(&reg_env)?.into())?;
        let answer = next_answer(&mut link.receiver, reg_id, connector, &mut early).await?;
        if answer.class != Class::Reply {
            let reason = decode_data::<RouteError>(&answer.data)
                .map(|e| e.to_string())
                .unwrap_or_else(|e| e.to_string());
            return Err(ModuleError::Registration(vec![reason]));
        }
        let outcome: RegisterOutcome = decode_data(&answer.data)?;
        if !outcome.refused.is_empty() {
            return Err(ModuleError::Registration(
                outcome
                    .refused
                    .into_iter()
                    .map(|(n, r)| format!("{n}: {r}"))
                    .collect(),
            ));
        }
        let handlers = self.handlers.len();
        let module = Module::new(
            Settings {
                name: name.clone(),
                link_no: welcome.link,
                first_seq: 2,
                handlers: self.handlers,
                query_timeout: self.query_timeout,
                requery_after_crash: self.requery_after_crash,
                max_frame_bytes: self.max_frame_bytes,
                sim_time: self.sim_time,
                central_clock: welcome.simulated_clock,
                journal: welcome.journal,
            },
            link.sender,
            link.keep,
        );
        tracing::info!(module = %name, link = welcome.link, handlers, "connected to {}", connector.describe());
        // Where central can die and come back: keep what it takes to join it again.
        let rejoiner = link
            .presence
            .is_some()
            .then(|| Rejoiner::new(Greeting { hello, register }));
        tokio::spawn(Module::receive_loop(
            std::sync::Arc::downgrade(&module.shared),
            link.receiver,
            link.presence,
            rejoiner,
            early,
        ));
        Ok(module)
    }
}

/// Waits for central's answer to a bootstrap message, keeping whatever else arrives first in
/// `early`.
async fn next_answer(
    rx: &mut FrameReceiver,
    id: MessageId,
    connector: &Connector,
    early: &mut Vec<Envelope>,
) -> Result<Envelope> {
    let deadline = tokio::time::Instant::now() + CONNECT_TIMEOUT;
    loop {
        let frame = tokio::time::timeout_at(deadline, rx.recv())
            .await
            .map_err(|_| {
                ModuleError::Connect(format!(
                    "{} did not answer within {CONNECT_TIMEOUT:?}",
                    connector.describe()
                ))
            })?
            .ok_or(ModuleError::Disconnected)?;
        let envelope = decode(&frame, usize::MAX)?;
        if envelope.correlation == Some(id) {
            return Ok(envelope);
        }
        early.push(envelope);
    }
}
