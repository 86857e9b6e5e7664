//! Reading a traffic log back, including one cut short by a crash.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use mcap::records::Record;
use tca_messages::{Class, DataFormat, Envelope, MessageName, Value};

use crate::error::{LogError, Result};
use crate::layout::*;
use crate::record::{
    FrameRecord, LinkRecord, LogRecord, ProblemRecord, RecordKind, RegisteredRecord, TreeRecord,
};

/// The registered formats of a message, as the log knows them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KnownFormat {
    /// Class registered.
    pub class: Class,
    /// Data format.
    pub format: DataFormat,
    /// Reply format (queries).
    pub reply: Option<DataFormat>,
}

/// A log read into memory.
#[derive(Debug)]
pub struct LogFile {
    /// The file.
    pub path: PathBuf,
    /// Every record, in file order (central's order).
    pub records: Vec<LogRecord>,
    /// Formats by message name, from the registrations in the log.
    pub formats: HashMap<MessageName, KnownFormat>,
    /// Set when the file ends early (central was killed): what was wrong and where.
    pub truncated: Option<String>,
}

impl LogFile {
    /// Reads a log file. A file cut short (central killed) is read up to its last complete
    /// record and `truncated` says so; a file that is not a tca log at all is an error.
    pub fn open(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|source| LogError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(path, &bytes)
    }

    /// The logs of one central and its restarts on its journal, read in order (the crashed
    /// ones, as `tca central` kept them, `traffic.1.mcap`, `traffic.2.mcap`, ..., then the
    /// last), as one log: their records one after the other (a restarted central's log starts
    /// with what the crashed one's lacked), the formats of all. `truncated` is the last one's.
    pub fn chain(logs: Vec<LogFile>) -> LogFile {
        let mut all = LogFile {
            path: PathBuf::new(),
            records: Vec::new(),
            formats: HashMap::new(),
            truncated: None,
        };
        for log in logs {
            all.path = log.path;
            all.records.extend(log.records);
            all.formats.extend(log.formats);
            all.truncated = log.truncated;
        }
        all
    }

    /// Parses log bytes (see [`LogFile::open`]).
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Self> {
        // The mcap crate can trip an arithmetic overflow check on some malformed chunks (a
        // record claiming more bytes than its chunk holds; found by fuzzing): a panic there
        // is a corrupt file, not a crash.
        std::panic::catch_unwind(|| Self::parse_unguarded(path, bytes)).unwrap_or_else(|_| {
            Err(LogError::Corrupt {
                path: path.to_owned(),
                reason: "a record inside a chunk claims more bytes than the chunk holds; the \
                         file is damaged (a log written by `tca central --log` never has this)"
                    .into(),
            })
        })
    }

    fn parse_unguarded(path: &Path, bytes: &[u8]) -> Result<Self> {
        let corrupt = |reason: String| LogError::Corrupt {
            path: path.to_owned(),
            reason,
        };
        if bytes.len() < mcap::MAGIC.len() || &bytes[..mcap::MAGIC.len()] != mcap::MAGIC {
            return Err(corrupt(
                "the file does not start with the MCAP magic bytes; give a log written by \
                 `tca central --log`"
                    .into(),
            ));
        }
        let options = enumset::EnumSet::only(mcap::read::Options::IgnoreEndMagic);
        let reader = mcap::read::ChunkFlattener::new_with_options(bytes, options)
            .map_err(|e| corrupt(e.to_string()))?;
        let mut log = LogFile {
            path: path.to_owned(),
            records: Vec::new(),
            formats: HashMap::new(),
            truncated: None,
        };
        // channel id -> (topic, message encoding)
        let mut channels: HashMap<u16, (String, String)> = HashMap::new();
        let mut skipped = 0usize;
        for item in reader {
            let record = match item {
                Ok(r) => r,
                Err(e) => {
                    log.truncated = Some(format!(
                        "the log ends early ({e}) after {} records; central probably stopped \
                         abruptly",
                        log.records.len()
                    ));
                    break;
                }
            };
            match record {
                Record::Channel(c) => {
                    channels.insert(c.id, (c.topic, c.message_encoding));
                }
                Record::Message { header, data } => {
                    let Some((topic, encoding)) = channels.get(&header.channel_id) else {
                        skipped += 1;
                        continue;
                    };
                    match decode_record(topic, encoding, &data) {
                        Some(kind) => {
                            if let RecordKind::Registered(r) = &kind {
                                log.formats.insert(
                                    r.registration.name.clone(),
                                    KnownFormat {
                                        class: r.registration.class,
                                        format: r.registration.format.clone(),
                                        reply: r.registration.reply.clone(),
                                    },
                                );
                            }
                            log.records.push(LogRecord {
                                at_ns: header.log_time,
                                kind,
                            });
                        }
                        None => skipped += 1,
                    }
                }
                _ => {}
            }
        }
        if skipped > 0 {
            tracing::warn!(
                skipped,
                "log messages that could not be decoded were skipped"
            );
        }
        Ok(log)
    }

    /// Decodes the envelope of a frame record.
    pub fn envelope(frame: &FrameRecord) -> Result<Envelope, String> {
        tca_messages::decode(&frame.frame, usize::MAX).map_err(|e| e.to_string())
    }

    /// Decodes an envelope's data through the format registered for its name (replies use the
    /// reply format; errors and failures their fixed types).
    pub fn data_value(&self, envelope: &Envelope) -> Result<Value, String> {
        let fixed = |f: Result<DataFormat, tca_messages::FormatError>| {
            f.map_err(|e| e.to_string())
                .and_then(|f| f.decode_value(&envelope.data).map_err(|e| e.to_string()))
        };
        match envelope.class {
            Class::Error => return fixed(DataFormat::of::<tca_messages::RouteError>()),
            Class::Failure => return fixed(DataFormat::of::<tca_messages::Failure>()),
            Class::Success => return fixed(DataFormat::of::<()>()),
            _ => {}
        }
        if let Some(v) = control_value(envelope) {
            return v;
        }
        let known = self.formats.get(&envelope.name).ok_or_else(|| {
            format!(
                "{} was never registered in this log; data not decoded",
                envelope.name
            )
        })?;
        let format = match envelope.class {
            Class::Reply => known
                .reply
                .as_ref()
                .ok_or_else(|| format!("{} has no reply format", envelope.name))?,
            _ => &known.format,
        };
        format
            .decode_value(&envelope.data)
            .map_err(|e| e.to_string())
    }
}

/// Decodes central's own control payloads.
fn control_value(envelope: &Envelope) -> Option<Result<Value, String>> {
    use tca_messages::control::{self, names};
    fn with<T: serde::de::DeserializeOwned>(e: &Envelope) -> Result<Value, String> {
        DataFormat::of::<T>()
            .map_err(|x| x.to_string())
            .and_then(|f| f.decode_value(&e.data).map_err(|x| x.to_string()))
    }
    let reply = envelope.class == Class::Reply;
    Some(match envelope.name.as_str() {
        names::HELLO => with::<control::Hello>(envelope),
        names::WELCOME => with::<control::Welcome>(envelope),
        names::REGISTER if reply => with::<control::RegisterOutcome>(envelope),
        names::REGISTER => with::<control::Register>(envelope)
            .map(|_| Value::Str("(registrations, see tca.log.registered)".into())),
        names::REGISTRY if reply => {
            with::<control::Registry>(envelope).map(|_| Value::Str("(registry)".into()))
        }
        names::REGISTRY => with::<()>(envelope),
        names::CANCEL => with::<control::Cancel>(envelope),
        names::KILL if reply => with::<()>(envelope),
        names::KILL => with::<control::Kill>(envelope),
        names::CONSTRAIN if reply => with::<()>(envelope),
        names::CONSTRAIN => with::<control::Constrain>(envelope),
        names::TREE if reply => with::<control::TreeView>(envelope),
        names::TREE => with::<()>(envelope),
        names::TASK_ENDED => with::<control::TaskEnded>(envelope),
        names::BYE => with::<()>(envelope),
        _ => return None,
    })
}

fn decode_record(topic: &str, encoding: &str, data: &[u8]) -> Option<RecordKind> {
    fn de<T: serde::de::DeserializeOwned>(data: &[u8]) -> Option<T> {
        tca_messages::decode_data(data).ok()
    }
    match (topic, encoding) {
        (LINK_TOPIC, RECORD_ENCODING) => de::<LinkRecord>(data).map(RecordKind::Link),
        (REGISTERED_TOPIC, RECORD_ENCODING) => {
            de::<RegisteredRecord>(data).map(RecordKind::Registered)
        }
        (TREE_TOPIC, RECORD_ENCODING) => de::<TreeRecord>(data).map(RecordKind::Tree),
        (PROBLEM_TOPIC, RECORD_ENCODING) => de::<ProblemRecord>(data).map(RecordKind::Problem),
        (_, FRAME_ENCODING) => de::<FrameRecord>(data).map(RecordKind::Frame),
        _ => None,
    }
}
