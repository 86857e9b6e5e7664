//! The async driver around the core: one task owns the [`Central`] state machine, every link
//! feeds one channel, and the driver carries out the actions (send, log, close).

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use bytes::Bytes;
use tca_logs::LogSink;
use tca_messages::{ModuleName, now_ns};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use crate::core::{Action, Central, Counters, Event, LinkId};
use crate::inproc::InProcLink;
use crate::zenoh_transport::ZenohCentral;
use crate::{CentralConfig, CentralError, Result};

/// What reaches the driver task.
#[derive(Debug)]
pub(crate) enum Input {
    /// An event for the core.
    Event(Event),
    /// A new link and where to send its frames (precedes its `Opened` event).
    Attach(LinkId, mpsc::UnboundedSender<Bytes>),
    /// A request for statistics.
    Inspect(oneshot::Sender<Stats>),
    /// Stop.
    Shutdown,
}

/// A snapshot of central's state.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Running totals.
    pub counters: Counters,
    /// Connected modules.
    pub modules: Vec<ModuleName>,
    /// Live task-tree nodes.
    pub live_nodes: usize,
    /// The task trees as text.
    pub tree: String,
}

/// A cheap, cloneable handle to a running central.
#[derive(Clone, Debug)]
pub struct CentralHandle {
    tx: mpsc::UnboundedSender<Input>,
    next_link: Arc<AtomicU32>,
}

impl CentralHandle {
    /// Opens an in-process link, as a module in this process connecting.
    pub fn connect_in_process(&self) -> Result<InProcLink> {
        let link = self.allocate_link();
        let (sink, from_central) = mpsc::unbounded_channel();
        self.tx
            .send(Input::Attach(link, sink))
            .map_err(|_| CentralError::Stopped)?;
        self.tx
            .send(Input::Event(Event::Opened(link)))
            .map_err(|_| CentralError::Stopped)?;
        Ok(InProcLink::new(link, self.tx.clone(), from_central))
    }

    /// Central's current statistics.
    pub async fn stats(&self) -> Result<Stats> {
        let (tx, rx) = oneshot::channel();
        self.tx
            .send(Input::Inspect(tx))
            .map_err(|_| CentralError::Stopped)?;
        rx.await.map_err(|_| CentralError::Stopped)
    }

    pub(crate) fn allocate_link(&self) -> LinkId {
        self.next_link.fetch_add(1, Ordering::Relaxed)
    }

    pub(crate) fn input(&self) -> &mpsc::UnboundedSender<Input> {
        &self.tx
    }
}

/// A central running in this process.
pub struct RunningCentral {
    handle: CentralHandle,
    task: JoinHandle<Result<Stats>>,
    zenoh: Option<ZenohCentral>,
}

impl RunningCentral {
    /// The handle.
    pub fn handle(&self) -> CentralHandle {
        self.handle.clone()
    }

    /// The zenoh endpoints central listens on, if the zenoh transport is on.
    pub fn listening(&self) -> Vec<String> {
        self.zenoh
            .as_ref()
            .map(|z| z.endpoints().to_vec())
            .unwrap_or_default()
    }

    /// Stops central: closes every link, finishes the log and returns the final statistics.
    pub async fn shutdown(self) -> Result<Stats> {
        let _ = self.handle.tx.send(Input::Shutdown);
        let stats = self.task.await.map_err(|_| CentralError::Stopped)??;
        if let Some(z) = self.zenoh {
            z.close().await;
        }
        Ok(stats)
    }

    /// Waits until central stops by itself (it does not, unless the runtime fails).
    pub async fn wait(self) -> Result<Stats> {
        self.task.await.map_err(|_| CentralError::Stopped)?
    }
}

/// How to start central.
#[derive(Clone, Debug, Default)]
pub struct StartOptions {
    /// Limits and defaults.
    pub config: CentralConfig,
    /// Write the traffic log here (MCAP).
    pub log: Option<PathBuf>,
    /// Also serve modules over zenoh, listening on these endpoints
    /// (e.g. `tcp/127.0.0.1:7447`).
    pub listen: Vec<String>,
}

/// Starts central on the current tokio runtime.
pub async fn start(options: StartOptions) -> Result<RunningCentral> {
    let (tx, rx) = mpsc::unbounded_channel();
    let handle = CentralHandle {
        tx,
        next_link: Arc::new(AtomicU32::new(1)),
    };
    let log = match &options.log {
        Some(path) => Some(LogSink::create(path)?),
        None => None,
    };
    let zenoh = if options.listen.is_empty() {
        None
    } else {
        Some(ZenohCentral::start(&options.listen, handle.clone()).await?)
    };
    let core = Central::new(options.config);
    let task = tokio::spawn(drive(core, rx, log));
    Ok(RunningCentral {
        handle,
        task,
        zenoh,
    })
}

/// Most inputs handled between two hand-overs to the log writer.
const MAX_BATCH: usize = 512;

/// The driver loop.
async fn drive(
    mut core: Central,
    mut rx: mpsc::UnboundedReceiver<Input>,
    mut log: Option<LogSink>,
) -> Result<Stats> {
    let mut sinks: HashMap<LinkId, mpsc::UnboundedSender<Bytes>> = HashMap::new();
    let mut actions = Vec::with_capacity(256);
    let mut records = Vec::new();
    let mut stop = false;
    while !stop {
        let deadline = core.next_deadline();
        let first = match deadline {
            Some(at) => {
                let wait = Duration::from_nanos(at.saturating_sub(now_ns()));
                match tokio::time::timeout(wait, rx.recv()).await {
                    Ok(input) => input,
                    Err(_) => Some(Input::Event(Event::Tick)),
                }
            }
            None => rx.recv().await,
        };
        let Some(first) = first else { break };
        // Handle what is already queued as one batch: one clock read, one log hand-over.
        let now = now_ns();
        let mut next = Some(first);
        let mut handled = 0;
        while let Some(input) = next.take() {
            match input {
                Input::Event(event) => core.handle(now, event, &mut actions),
                Input::Attach(link, sink) => {
                    sinks.insert(link, sink);
                }
                Input::Inspect(reply) => {
                    let _ = reply.send(stats(&core));
                }
                Input::Shutdown => {
                    stop = true;
                    break;
                }
            }
            // Carry out sends as we go so closes and sends keep their order.
            for action in actions.drain(..) {
                match action {
                    Action::Send(link, frame) => {
                        if let Some(sink) = sinks.get(&link) {
                            // A closed sink means the module is gone; its Closed event follows.
                            let _ = sink.send(frame);
                        }
                    }
                    Action::Log(record) => records.push(record),
                    Action::Close(link) => {
                        sinks.remove(&link);
                    }
                }
            }
            handled += 1;
            if handled < MAX_BATCH {
                next = rx.try_recv().ok();
            }
        }
        if let Some(l) = log.as_mut() {
            l.append_batch(std::mem::take(&mut records));
        } else {
            records.clear();
        }
    }
    let final_stats = stats(&core);
    drop(sinks);
    if let Some(l) = log {
        l.finish()?;
    }
    Ok(final_stats)
}

fn stats(core: &Central) -> Stats {
    Stats {
        counters: core.counters(),
        modules: core.connected_modules(),
        live_nodes: core.live_nodes(),
        tree: core.render_tree(),
    }
}
