//! `tca log export --json`: a copy of a log with every message as JSON, which Foxglove Studio
//! (and any MCAP tool) opens without knowing tca's formats. One channel per message name (as in
//! the original) plus the link, registration, tree and problem channels; each message is a
//! JSON object with the envelope header and the data decoded through the registered format.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use serde_json::{Value as J, json};

use crate::error::{LogError, Result};
use crate::reader::LogFile;
use crate::record::RecordKind;

/// Writes `log` as a JSON-encoded MCAP file at `out`; returns the number of messages written.
pub fn export_json(log: &LogFile, out: &Path) -> Result<usize> {
    let io = |source| LogError::Io {
        path: out.to_owned(),
        source,
    };
    let file = File::create(out).map_err(io)?;
    let mut mcap = mcap::WriteOptions::new()
        .profile("")
        .library(concat!("tca-logs ", env!("CARGO_PKG_VERSION")))
        .compression(None)
        .create(BufWriter::new(file))
        .map_err(|e| LogError::Write(e.to_string()))?;
    let mut channels: HashMap<String, u16> = HashMap::new();
    let mut written = 0usize;
    let mut sequence = 0u32;
    for record in &log.records {
        let (topic, value) = match &record.kind {
            RecordKind::Frame(f) => {
                let envelope = match LogFile::envelope(f) {
                    Ok(e) => e,
                    Err(_) => continue,
                };
                let data = match log.data_value(&envelope) {
                    Ok(v) => v.to_json(),
                    Err(e) => json!({ "undecoded_bytes": envelope.data.len(), "why": e }),
                };
                let peer = f.peer.as_ref().map(|p| p.to_string());
                let (from, to) = match f.direction {
                    crate::Direction::In => (peer, Some("central".to_owned())),
                    crate::Direction::Out => (Some(envelope.sender.to_string()), peer),
                };
                (
                    envelope.name.to_string(),
                    json!({
                        "direction": format!("{:?}", f.direction).to_lowercase(),
                        "class": envelope.class.as_str(),
                        "from": from,
                        "to": to,
                        "id": envelope.id.to_string(),
                        "node": envelope.node.map(|n| n.0),
                        "context": envelope.context.map(|n| n.0),
                        "correlation": envelope.correlation.map(|c| c.to_string()),
                        "timestamp_ns": envelope.timestamp_ns,
                        "redelivery": envelope.redelivery,
                        "data": data,
                    }),
                )
            }
            RecordKind::Link(l) => (
                crate::layout::LINK_TOPIC.to_owned(),
                serde_json::to_value(l).unwrap_or(J::Null),
            ),
            RecordKind::Registered(r) => (
                crate::layout::REGISTERED_TOPIC.to_owned(),
                json!({
                    "module": r.module.as_str(),
                    "name": r.registration.name.as_str(),
                    "class": r.registration.class.as_str(),
                    "format": r.registration.format.to_string(),
                    "reply": r.registration.reply.as_ref().map(|f| f.to_string()),
                }),
            ),
            RecordKind::Tree(t) => (
                crate::layout::TREE_TOPIC.to_owned(),
                serde_json::to_value(t).unwrap_or(J::Null),
            ),
            RecordKind::Problem(p) => (
                crate::layout::PROBLEM_TOPIC.to_owned(),
                json!({ "link": p.link, "module": p.module.as_ref().map(|m| m.as_str()), "error": p.error }),
            ),
        };
        let channel = match channels.get(&topic) {
            Some(&c) => c,
            None => {
                let c = mcap
                    .add_channel(0, &topic, "json", &BTreeMap::new())
                    .map_err(|e| LogError::Write(e.to_string()))?;
                channels.insert(topic.clone(), c);
                c
            }
        };
        let data = serde_json::to_vec(&value).map_err(|e| LogError::Write(e.to_string()))?;
        sequence = sequence.wrapping_add(1);
        mcap.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: channel,
                sequence,
                log_time: record.at_ns,
                publish_time: record.at_ns,
            },
            &data,
        )
        .map_err(|e| LogError::Write(e.to_string()))?;
        written += 1;
    }
    mcap.finish().map_err(|e| LogError::Write(e.to_string()))?;
    Ok(written)
}
