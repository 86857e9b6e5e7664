//! The telemetry monitor: the ground-side module that takes the robot's telemetry (and its
//! support states and foot contacts) as they come across, keeps the latest for anyone who
//! asks, counts what was lost on the way and can record all of it.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use serde::Serialize;
use tca_legged_messages::{
    FootContact, LatestTelemetry, LatestTelemetryReply, SupportState, Telemetry,
};
use tca_messages::{Message, now_ns};
use tca_module::{Connector, Module, ModuleError};
use tokio::sync::mpsc;

/// The monitor's module name unless told otherwise.
pub const MONITOR_NAME: &str = "telemetry";

/// How the monitor runs.
#[derive(Clone, Debug)]
pub struct MonitorOptions {
    /// Its module name.
    pub name: String,
    /// Write everything received to this file, one JSON object a line:
    /// `{"received_ns": ..., "name": "legged.telemetry", "data": {...}}`.
    pub record: Option<PathBuf>,
}

impl Default for MonitorOptions {
    fn default() -> Self {
        MonitorOptions {
            name: MONITOR_NAME.to_owned(),
            record: None,
        }
    }
}

/// A telemetry sample as it arrived.
#[derive(Clone, Debug, PartialEq)]
pub struct Received {
    /// When it arrived, nanoseconds since the UNIX epoch.
    pub at_ns: u64,
    /// The sample.
    pub telemetry: Telemetry,
}

#[derive(Default)]
struct State {
    latest: Option<Received>,
    received: u64,
    missing: u64,
}

/// One line of the record file.
#[derive(Serialize)]
struct Line<'a, T: Serialize> {
    received_ns: u64,
    name: &'a str,
    data: &'a T,
}

struct Recorder(Mutex<BufWriter<File>>);

impl Recorder {
    fn write<T: Serialize>(&self, name: &str, data: &T) {
        let line = Line {
            received_ns: now_ns(),
            name,
            data,
        };
        let mut w = self.0.lock().unwrap_or_else(|p| p.into_inner());
        let written = serde_json::to_writer(&mut *w, &line)
            .map_err(std::io::Error::other)
            .and_then(|()| w.write_all(b"\n"))
            .and_then(|()| w.flush());
        if let Err(e) = written {
            tracing::warn!(error = %e, "the telemetry record could not be written");
        }
    }
}

/// Connects the monitor. Every telemetry sample received also goes to the returned
/// receiver (drop it if nobody reads).
pub async fn connect_monitor(
    connector: &Connector,
    options: MonitorOptions,
) -> Result<(Module, mpsc::UnboundedReceiver<Received>), ModuleError> {
    let recorder = match &options.record {
        Some(path) => {
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir).map_err(|e| {
                    ModuleError::Config(format!("cannot create {}: {e}", dir.display()))
                })?;
            }
            let file = File::create(path).map_err(|e| {
                ModuleError::Config(format!(
                    "cannot write the telemetry record {}: {e}",
                    path.display()
                ))
            })?;
            Some(Arc::new(Recorder(Mutex::new(BufWriter::new(file)))))
        }
        None => None,
    };
    let state = Arc::new(Mutex::new(State::default()));
    let (tx, rx) = mpsc::unbounded_channel();
    let module = Module::builder(options.name.clone())
        .handle({
            let state = state.clone();
            let recorder = recorder.clone();
            move |_ctx, t: Telemetry| {
                let at_ns = now_ns();
                if let Some(r) = &recorder {
                    r.write(Telemetry::NAME, &t);
                }
                {
                    let mut s = state.lock().unwrap_or_else(|p| p.into_inner());
                    if let Some(last) = &s.latest {
                        let last = last.telemetry.seq;
                        if t.seq > last + 1 {
                            s.missing += t.seq - last - 1;
                        }
                    }
                    s.received += 1;
                    s.latest = Some(Received {
                        at_ns,
                        telemetry: t.clone(),
                    });
                }
                let _ = tx.send(Received {
                    at_ns,
                    telemetry: t,
                });
                async { Ok(()) }
            }
        })
        .handle({
            let recorder = recorder.clone();
            move |_ctx, s: SupportState| {
                if let Some(r) = &recorder {
                    r.write(SupportState::NAME, &s);
                }
                async { Ok(()) }
            }
        })
        .handle(move |_ctx, c: FootContact| {
            if let Some(r) = &recorder {
                r.write(FootContact::NAME, &c);
            }
            async { Ok(()) }
        })
        .handle(move |_ctx, _q: LatestTelemetry| {
            let reply = {
                let s = state.lock().unwrap_or_else(|p| p.into_inner());
                LatestTelemetryReply {
                    latest: s.latest.as_ref().map(|r| r.telemetry.clone()),
                    received_ns: s.latest.as_ref().map_or(0, |r| r.at_ns),
                    received: s.received,
                    missing: s.missing,
                }
            };
            async move { Ok(reply) }
        })
        .connect(connector)
        .await?;
    Ok((module, rx))
}
