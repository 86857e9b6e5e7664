//! `tca log export --foxglove`: a traffic log as an MCAP file for Foxglove, with the traffic
//! channels (JSON with JSON schemas from the registered formats, see [`crate::traffic`]) and
//! the well-known channels ([`crate::wellknown`]), protobuf-encoded with Foxglove's own
//! schemas.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use foxglove::Encode;
use foxglove::messages::{FrameTransforms, Grid, Log, RawImage, SceneUpdate, log::Level};
use serde::Serialize;
use serde_json::json;
use tca_logs::{Direction, LogFile, RecordKind};

use crate::error::{FoxgloveError, Result};
use crate::geometry::timestamp;
use crate::traffic::{FormatTable, Formats, data_json, message_json, topic, topic_schema};
use crate::wellknown::{WellKnown, WellKnownState};

/// What an export wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ExportSummary {
    /// Messages written, all channels.
    pub messages: usize,
    /// Of which on traffic channels.
    pub traffic: usize,
    /// Messages per well-known topic.
    pub well_known: BTreeMap<String, usize>,
    /// Frames whose data did not decode through a registered format (left out).
    pub undecoded: usize,
}

/// The schema of the robot description channel: a URDF string (the shape the 3D panel's URDF
/// layer reads from a topic).
pub fn robot_description_schema() -> serde_json::Value {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "tca.RobotDescription",
        "type": "object",
        "properties": {"data": {"type": "string", "description": "the robot's URDF"}},
        "required": ["data"],
    })
}

/// An MCAP writer that adds each topic's schema and channel when its first message comes.
struct Out<W: std::io::Write + std::io::Seek> {
    mcap: mcap::Writer<W>,
    channels: HashMap<String, u16>,
    sequence: u32,
    summary: ExportSummary,
}

fn write_err(e: impl std::fmt::Display) -> FoxgloveError {
    FoxgloveError::Write(e.to_string())
}

impl<W: std::io::Write + std::io::Seek> Out<W> {
    fn channel(
        &mut self,
        topic: &str,
        schema: impl FnOnce() -> Option<(String, String, Vec<u8>)>,
        encoding: &str,
    ) -> Result<u16> {
        if let Some(&c) = self.channels.get(topic) {
            return Ok(c);
        }
        let schema_id = match schema() {
            Some((name, enc, data)) => self
                .mcap
                .add_schema(&name, &enc, &data)
                .map_err(write_err)?,
            None => 0,
        };
        let c = self
            .mcap
            .add_channel(schema_id, topic, encoding, &BTreeMap::new())
            .map_err(write_err)?;
        self.channels.insert(topic.to_owned(), c);
        Ok(c)
    }

    fn write(&mut self, channel: u16, at_ns: u64, data: &[u8]) -> Result<()> {
        self.sequence = self.sequence.wrapping_add(1);
        self.mcap
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence: self.sequence,
                    log_time: at_ns,
                    publish_time: at_ns,
                },
                data,
            )
            .map_err(write_err)?;
        self.summary.messages += 1;
        Ok(())
    }

    fn encoded<T: Encode>(&mut self, topic: &str, msg: &T, at_ns: u64) -> Result<()> {
        let c = self.channel(
            topic,
            || T::get_schema().map(|s| (s.name, s.encoding, s.data.into_owned())),
            &T::get_message_encoding(),
        )?;
        let mut buf = Vec::new();
        msg.encode(&mut buf).map_err(write_err)?;
        self.write(c, at_ns, &buf)?;
        *self.summary.well_known.entry(topic.to_owned()).or_default() += 1;
        Ok(())
    }

    fn well_known(&mut self, w: &WellKnown, at_ns: u64) -> Result<()> {
        let topic = w.topic().to_owned();
        match w {
            WellKnown::Transforms(m) => self.encoded::<FrameTransforms>(&topic, m, at_ns),
            WellKnown::Grid { grid, .. } => self.encoded::<Grid>(&topic, grid, at_ns),
            WellKnown::Scene(m) => self.encoded::<SceneUpdate>(&topic, m, at_ns),
            WellKnown::Image { image, .. } => self.encoded::<RawImage>(&topic, image, at_ns),
            WellKnown::Log(m) => self.encoded::<Log>(&topic, m, at_ns),
            WellKnown::RobotDescription(urdf) => {
                let c = self.channel(
                    &topic,
                    || {
                        Some((
                            "tca.RobotDescription".into(),
                            "jsonschema".into(),
                            robot_description_schema().to_string().into_bytes(),
                        ))
                    },
                    "json",
                )?;
                let data = serde_json::to_vec(&json!({ "data": urdf })).map_err(write_err)?;
                self.write(c, at_ns, &data)?;
                *self.summary.well_known.entry(topic).or_default() += 1;
                Ok(())
            }
        }
    }
}

/// The formats a log registered, by name.
pub fn log_formats(log: &LogFile) -> FormatTable {
    log.formats
        .iter()
        .map(|(name, k)| {
            (
                name.clone(),
                Formats {
                    format: k.format.clone(),
                    reply: k.reply.clone(),
                },
            )
        })
        .collect()
}

/// Writes `log` as an MCAP file for Foxglove at `out` (see the module docs). Only frames a
/// module sent are taken (not central's copies to their receivers), each at central's time.
pub fn export_foxglove(log: &LogFile, out: &Path) -> Result<ExportSummary> {
    let file = File::create(out).map_err(|source| FoxgloveError::Io {
        path: out.to_owned(),
        source,
    })?;
    let mcap = mcap::WriteOptions::new()
        .profile("")
        .library(concat!("tca-foxglove ", env!("CARGO_PKG_VERSION")))
        .create(BufWriter::new(file))
        .map_err(write_err)?;
    let mut w = Out {
        mcap,
        channels: HashMap::new(),
        sequence: 0,
        summary: ExportSummary::default(),
    };
    let formats = log_formats(log);
    let mut state = WellKnownState::new();
    for record in &log.records {
        let at_ns = record.at_ns;
        match &record.kind {
            RecordKind::Frame(f) if f.direction == Direction::In => {
                let Ok(envelope) = LogFile::envelope(f) else {
                    continue;
                };
                let Some(topic) = topic(envelope.name.as_str(), envelope.class) else {
                    continue;
                };
                match data_json(&envelope, &formats) {
                    Ok(data) => {
                        let c = w.channel(
                            &topic,
                            || {
                                topic_schema(
                                    &topic,
                                    envelope.name.as_str(),
                                    envelope.class,
                                    &formats,
                                )
                                .map(|s| {
                                    (
                                        format!("tca.{topic}"),
                                        "jsonschema".into(),
                                        s.to_string().into_bytes(),
                                    )
                                })
                            },
                            "json",
                        )?;
                        let bytes = serde_json::to_vec(&message_json(&envelope, data))
                            .map_err(write_err)?;
                        w.write(c, at_ns, &bytes)?;
                        w.summary.traffic += 1;
                    }
                    Err(why) => {
                        tracing::debug!(name = %envelope.name, %why, "frame left out");
                        w.summary.undecoded += 1;
                    }
                }
                for m in state.feed(&envelope, at_ns) {
                    w.well_known(&m, at_ns)?;
                }
            }
            RecordKind::Problem(p) => {
                let log_line = Log {
                    timestamp: Some(timestamp(at_ns)),
                    level: Level::Error as i32,
                    message: p.error.clone(),
                    name: p
                        .module
                        .as_ref()
                        .map(|m| m.to_string())
                        .unwrap_or_else(|| "central".into()),
                    file: String::new(),
                    line: 0,
                };
                w.well_known(&WellKnown::Log(log_line), at_ns)?;
            }
            _ => {}
        }
    }
    w.mcap.finish().map_err(write_err)?;
    Ok(w.summary)
}
