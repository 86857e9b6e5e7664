//! Reading a bridge's log back: the session it recorded, crossing by crossing, and the delays
//! measured.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use tca_logs::{Direction as Way, LinkEvent, LogFile, RecordKind};
use tca_messages::control::Registration;
use tca_messages::{Class, MessageId, MessageName, ModuleName};

use crate::error::{BridgeError, Result};
use crate::log::Settings;
use crate::side::{Direction, Side};
use crate::stats::DelayStats;
use crate::worst::{LateCrossing, worst};

/// One crossing as the log recorded it.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedCrossing {
    /// Its number.
    pub id: u32,
    /// The way it crossed.
    pub direction: Direction,
    /// Its class in the log (answers as reply, success or failure; a kill as control).
    pub class: Class,
    /// The message name.
    pub name: MessageName,
    /// Its data (an answer's as central carries it).
    pub data: Vec<u8>,
    /// Who sent it on the side it left.
    pub sender: ModuleName,
    /// The crossing it refers to: the request an answer answers, the task an exception was
    /// raised in or a kill kills.
    pub refers_to: Option<u32>,
    /// When the bridge got it, nanoseconds since the UNIX epoch.
    pub in_ns: Option<u64>,
    /// When the bridge handed it to the other side.
    pub out_ns: Option<u64>,
    /// Its message id on the side it left.
    pub in_cause: Option<MessageId>,
    /// Its message id on the side it reached.
    pub out_cause: Option<MessageId>,
}

impl RecordedCrossing {
    /// How long it was on the bridge, seconds (when it both came in and went out).
    pub fn delay_s(&self) -> Option<f64> {
        match (self.in_ns, self.out_ns) {
            (Some(a), Some(b)) => Some(b.saturating_sub(a) as f64 / 1e9),
            _ => None,
        }
    }
}

/// A bridge's recorded session.
#[derive(Debug)]
pub struct Recorded {
    /// The log.
    pub log: LogFile,
    /// The bridge's module name, as it recorded it.
    pub bridge: Option<String>,
    /// The delays it was set to (up, down), seconds, as it recorded them.
    pub delays_s: Option<(f64, f64)>,
    /// Each side's settings as recorded when the bridge joined it.
    pub settings: Vec<Settings>,
    /// What the bridge registered on each side.
    pub registrations: Vec<(Side, Registration)>,
    /// Every crossing, by number.
    pub crossings: BTreeMap<u32, RecordedCrossing>,
}

impl Recorded {
    /// Reads a bridge's log.
    pub fn open(path: &Path) -> Result<Self> {
        Self::from_log(LogFile::open(path)?)
    }

    /// The session a log read into memory recorded; a log that is not a bridge's is refused.
    pub fn from_log(log: LogFile) -> Result<Self> {
        let mut settings = Vec::new();
        let mut registrations = Vec::new();
        let mut crossings: BTreeMap<u32, RecordedCrossing> = BTreeMap::new();
        for record in &log.records {
            match &record.kind {
                RecordKind::Link(l) if l.event == LinkEvent::Connected => {
                    if let Ok(s) = serde_json::from_str::<Settings>(&l.detail) {
                        settings.push(s);
                    }
                }
                RecordKind::Registered(r) => {
                    if let Some(side) = Side::from_label(r.module.as_str()) {
                        registrations.push((side, r.registration.clone()));
                    }
                }
                RecordKind::Frame(f) => {
                    let Some(side) = Side::from_link(f.link) else {
                        continue;
                    };
                    let Ok(env) = LogFile::envelope(f) else {
                        continue;
                    };
                    if env.id.link() != 0 {
                        continue;
                    }
                    let id = env.id.seq();
                    let direction = match f.direction {
                        Way::In => Direction::leaving(side),
                        Way::Out => Direction::leaving(side.other()),
                    };
                    let c = crossings.entry(id).or_insert_with(|| RecordedCrossing {
                        id,
                        direction,
                        class: env.class,
                        name: env.name.clone(),
                        data: env.data.clone(),
                        sender: env.sender.clone(),
                        refers_to: env.correlation.map(|c| c.seq()),
                        in_ns: None,
                        out_ns: None,
                        in_cause: None,
                        out_cause: None,
                    });
                    match f.direction {
                        Way::In => {
                            c.in_ns = Some(record.at_ns);
                            c.in_cause = env.cause;
                        }
                        Way::Out => {
                            c.out_ns = Some(record.at_ns);
                            c.out_cause = env.cause;
                        }
                    }
                }
                _ => {}
            }
        }
        let Some(first) = settings.first() else {
            return Err(BridgeError::Playback(format!(
                "{} is not a bridge's log (no bridge settings in it); give the file `tca bridge \
                 run` wrote (`log =` in the bridge file, or --log)",
                log.path.display()
            )));
        };
        let bridge = Some(first.bridge.clone());
        let delays_s = Some((first.up_delay_s, first.down_delay_s));
        Ok(Recorded {
            log,
            bridge,
            delays_s,
            settings,
            registrations,
            crossings,
        })
    }

    /// The file.
    pub fn path(&self) -> &PathBuf {
        &self.log.path
    }

    /// The delays measured each way (up, down) against the recorded settings.
    pub fn delay_stats(&self) -> Vec<DelayStats> {
        DelayStats::both_ways(self.delays_s.unwrap_or((0.0, 0.0)), |d| {
            self.crossings
                .values()
                .filter(|c| c.direction == d)
                .filter_map(RecordedCrossing::delay_s)
                .collect()
        })
    }

    /// The `n` crossings the bridge held longest past their way's setting, worst first.
    pub fn worst(&self, n: usize) -> Vec<LateCrossing> {
        worst(
            self.crossings.values(),
            self.delays_s.unwrap_or((0.0, 0.0)),
            n,
            RecordedCrossing::delay_s,
        )
    }

    /// Crossings of one message name, one way, in order.
    pub fn crossings_of<'a>(
        &'a self,
        direction: Direction,
        name: &'a str,
    ) -> impl Iterator<Item = &'a RecordedCrossing> + 'a {
        self.crossings
            .values()
            .filter(move |c| c.direction == direction && c.name.as_str() == name)
    }
}
