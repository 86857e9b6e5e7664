//! Writing the bridge's log: a tca traffic log (MCAP, `tca log show` reads it) of everything
//! that crossed.
//!
//! - Each crossing is two frame records with the same message id `m0.N` (N its number): `in`
//!   when the bridge got it, on the link of the side it left (1 robot, 2 ground), and `out`
//!   when the bridge handed it to the other side, on that side's link. A record's peer is
//!   the side (`robot`, `ground`); the envelope's sender is the module that sent the message
//!   on the side it left, its `cause` the message's id on that side's central (for `in`) or on
//!   the other side's (for `out`), when known; answers and outcomes come as reply, success
//!   or failure, exceptions as exception, each with `correlation` the crossing it refers to; a
//!   kill of a forwarded task as `tca.killTask`.
//! - Each forwarded message is a registration record whose module is the side the bridge
//!   registered it on (`ground` for what crosses up, `robot` for what crosses down), with the
//!   format its handler registered on the other side.
//! - Link records say when the bridge joined, lost and joined again each side's central;
//!   the first of each side has, as its detail, the bridge's settings as JSON
//!   ([`Settings`]).
//! - Problem records say what could not be forwarded.

use std::path::Path;
use std::sync::Mutex;

use serde::{Deserialize, Serialize};
use tca_logs::{
    Direction as Way, FrameRecord, LinkEvent, LinkRecord, LogRecord, LogSink, ProblemRecord,
    RecordKind, RegisteredRecord,
};
use tca_messages::control::Registration;
use tca_messages::{Envelope, ModuleName, encode, now_ns};

use crate::error::Result;
use crate::side::Side;

/// The bridge's settings as its log records them (the detail of each side's first link
/// record, as JSON).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// The bridge's module name.
    pub bridge: String,
    /// The side this record is about.
    pub side: String,
    /// Where that side's central was.
    pub endpoint: String,
    /// The delay up (ground to robot), seconds.
    pub up_delay_s: f64,
    /// The delay down (robot to ground), seconds.
    pub down_delay_s: f64,
}

/// The bridge's log, written on its own thread.
pub(crate) struct BridgeLog {
    sink: Mutex<Option<LogSink>>,
}

impl BridgeLog {
    /// Creates the log at `path`; an earlier log there is kept as `STEM.N.mcap`.
    pub(crate) fn create(path: &Path) -> Result<Self> {
        if let Some(kept) = tca_logs::set_aside(path)? {
            tracing::info!(kept = %kept.display(), "the earlier bridge log was kept");
        }
        Ok(BridgeLog {
            sink: Mutex::new(Some(LogSink::create(path)?)),
        })
    }

    fn append(&self, at_ns: u64, kind: RecordKind) {
        let mut sink = self.sink.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(sink) = sink.as_mut() {
            sink.append(LogRecord { at_ns, kind });
        }
    }

    /// A side's central joined (with the settings), lost or joined again.
    pub(crate) fn link(&self, side: Side, event: LinkEvent, bridge: &ModuleName, detail: String) {
        self.append(
            now_ns(),
            RecordKind::Link(LinkRecord {
                link: side.link(),
                event,
                module: Some(bridge.clone()),
                detail,
            }),
        );
    }

    /// The bridge registered a message on `side`.
    pub(crate) fn registered(&self, side: Side, registration: Registration) {
        self.append(
            now_ns(),
            RecordKind::Registered(RegisteredRecord {
                module: side_module(side),
                registration,
            }),
        );
    }

    /// A crossing came in from `side` or went out to it.
    pub(crate) fn frame(&self, way: Way, side: Side, envelope: &Envelope, at_ns: u64) {
        let frame = match encode(envelope) {
            Ok(f) => f,
            Err(e) => {
                tracing::error!(error = %e, "a crossing cannot be logged");
                return;
            }
        };
        self.append(
            at_ns,
            RecordKind::Frame(FrameRecord {
                direction: way,
                link: side.link(),
                peer: Some(side_module(side)),
                name: envelope.name.clone(),
                class: envelope.class,
                frame: frame.into(),
            }),
        );
    }

    /// Something could not be forwarded.
    pub(crate) fn problem(&self, side: Option<Side>, error: String) {
        self.append(
            now_ns(),
            RecordKind::Problem(ProblemRecord {
                link: side.map(Side::link),
                module: side.map(side_module),
                error,
                frame_prefix: Vec::new(),
            }),
        );
    }

    /// Writes what is queued and closes the file.
    pub(crate) fn finish(&self) {
        let sink = self.sink.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(sink) = sink
            && let Err(e) = sink.finish()
        {
            tracing::error!(error = %e, "the bridge's log could not be finished");
        }
    }
}

/// How the log names a side as a module: `robot` or `ground`.
pub(crate) fn side_module(side: Side) -> ModuleName {
    ModuleName::new(side.label()).expect("`robot` and `ground` are valid module names")
}
