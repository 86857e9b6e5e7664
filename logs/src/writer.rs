//! Writing records into an MCAP file, and the background sink central uses.

use std::collections::BTreeMap;

use rustc_hash::FxHashMap as HashMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Serialize;
use tca_messages::control::Registration;
use tca_messages::{DataFormat, MessageName};

use crate::error::{LogError, Result};
use crate::layout::*;
use crate::record::{
    LinkRecord, LogRecord, ProblemRecord, RecordKind, RegisteredRecord, TreeRecord,
};

/// How often the sink closes the current chunk and hands it to the operating system, so a
/// `kill -9` of central loses at most about this much of the log.
pub const FLUSH_INTERVAL: Duration = Duration::from_millis(50);

/// Writes records to an MCAP file.
pub struct LogWriter {
    path: PathBuf,
    mcap: mcap::Writer<BufWriter<File>>,
    /// Current schema version per message name (bumped by each registration that changes it).
    formats: HashMap<MessageName, (u32, String)>,
    /// Channel per (name, schema version).
    frame_channels: HashMap<(MessageName, u32), u16>,
    record_channels: HashMap<&'static str, u16>,
    sequence: u32,
    /// Reused encoding buffer.
    buffer: Vec<u8>,
}

impl LogWriter {
    /// Creates (or truncates) the log file.
    pub fn create(path: &Path) -> Result<Self> {
        let io = |source| LogError::Io {
            path: path.to_owned(),
            source,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let file = File::create(path).map_err(io)?;
        let mcap = mcap::WriteOptions::new()
            .profile(PROFILE)
            .library(concat!("tca-logs ", env!("CARGO_PKG_VERSION")))
            .compression(None)
            .chunk_size(Some(256 * 1024))
            // No CRCs: the reader does not check them, and they cost as much as the writing.
            .calculate_chunk_crcs(false)
            .calculate_data_section_crc(false)
            // No message indexes: the writer keeps every chunk's per-channel index offsets in
            // memory until the file ends (about 25 MiB per GB of log under load), and neither
            // our reader nor MCAP's (which fall back to scanning each chunk) needs them. The
            // chunk indexes stay, so viewers still find their way by time.
            .emit_message_indexes(false)
            .create(BufWriter::with_capacity(256 * 1024, file))
            .map_err(|e| LogError::Write(e.to_string()))?;
        Ok(LogWriter {
            path: path.to_owned(),
            mcap,
            formats: HashMap::default(),
            frame_channels: HashMap::default(),
            record_channels: HashMap::default(),
            sequence: 0,
            buffer: Vec::with_capacity(4096),
        })
    }

    /// The file written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends one record.
    pub fn append(&mut self, record: &LogRecord) -> Result<()> {
        match &record.kind {
            RecordKind::Frame(f) => {
                let channel = self.frame_channel(&f.name)?;
                let mut data = std::mem::take(&mut self.buffer);
                data.clear();
                let result = match postcard::to_io(f, &mut data) {
                    Ok(_) => self.write(channel, record.at_ns, &data),
                    Err(e) => Err(LogError::Write(e.to_string())),
                };
                self.buffer = data;
                result
            }
            RecordKind::Registered(r) => {
                self.note_registration(&r.registration);
                self.write_record::<RegisteredRecord>(REGISTERED_TOPIC, record.at_ns, r)
            }
            RecordKind::Link(r) => self.write_record::<LinkRecord>(LINK_TOPIC, record.at_ns, r),
            RecordKind::Tree(r) => self.write_record::<TreeRecord>(TREE_TOPIC, record.at_ns, r),
            RecordKind::Problem(r) => {
                self.write_record::<ProblemRecord>(PROBLEM_TOPIC, record.at_ns, r)
            }
        }
    }

    /// Closes the current chunk and flushes it to the operating system.
    pub fn flush(&mut self) -> Result<()> {
        self.mcap
            .flush()
            .map_err(|e| LogError::Write(e.to_string()))
    }

    /// Writes the summary and closes the file.
    pub fn finish(mut self) -> Result<()> {
        self.mcap
            .finish()
            .map_err(|e| LogError::Write(e.to_string()))?;
        Ok(())
    }

    fn write(&mut self, channel: u16, at_ns: u64, data: &[u8]) -> Result<()> {
        self.sequence = self.sequence.wrapping_add(1);
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: at_ns,
            publish_time: at_ns,
        };
        self.mcap
            .write_to_known_channel(&header, data)
            .map_err(|e| LogError::Write(e.to_string()))
    }

    fn write_record<T: Serialize + serde::de::DeserializeOwned>(
        &mut self,
        topic: &'static str,
        at_ns: u64,
        value: &T,
    ) -> Result<()> {
        let channel = match self.record_channels.get(topic) {
            Some(&c) => c,
            None => {
                let schema = DataFormat::of::<T>()
                    .ok()
                    .and_then(|f| serde_json::to_vec(&serde_json::json!({ "format": f })).ok())
                    .unwrap_or_default();
                let schema_id = self
                    .mcap
                    .add_schema(topic, FORMAT_SCHEMA_ENCODING, &schema)
                    .map_err(|e| LogError::Write(e.to_string()))?;
                let c = self
                    .mcap
                    .add_channel(schema_id, topic, RECORD_ENCODING, &BTreeMap::new())
                    .map_err(|e| LogError::Write(e.to_string()))?;
                self.record_channels.insert(topic, c);
                c
            }
        };
        let mut data = std::mem::take(&mut self.buffer);
        data.clear();
        let result = match postcard::to_io(value, &mut data) {
            Ok(_) => self.write(channel, at_ns, &data),
            Err(e) => Err(LogError::Write(e.to_string())),
        };
        self.buffer = data;
        result
    }

    fn note_registration(&mut self, reg: &Registration) {
        let schema = serde_json::json!({
            "class": reg.class.as_str(),
            "format": reg.format,
            "reply": reg.reply,
        })
        .to_string();
        match self.formats.get_mut(&reg.name) {
            Some((_, s)) if *s == schema => {}
            Some((version, s)) => {
                *version += 1;
                *s = schema;
            }
            None => {
                self.formats.insert(reg.name.clone(), (1, schema));
            }
        }
    }

    fn frame_channel(&mut self, name: &MessageName) -> Result<u16> {
        let (version, schema) = self
            .formats
            .get(name)
            .cloned()
            .unwrap_or_else(|| (0, "{}".to_owned()));
        if let Some(&c) = self.frame_channels.get(&(name.clone(), version)) {
            return Ok(c);
        }
        let schema_id = self
            .mcap
            .add_schema(name.as_str(), FORMAT_SCHEMA_ENCODING, schema.as_bytes())
            .map_err(|e| LogError::Write(e.to_string()))?;
        let channel = self
            .mcap
            .add_channel(schema_id, name.as_str(), FRAME_ENCODING, &BTreeMap::new())
            .map_err(|e| LogError::Write(e.to_string()))?;
        self.frame_channels.insert((name.clone(), version), channel);
        Ok(channel)
    }
}

/// Moves an existing, non-empty log at `path` aside to the first free `STEM.N.mcap` next to it
/// (N = 1, 2, ...) and returns where it went; `None` when there was nothing to keep.
///
/// A central restarted after a crash with the same `--log` must not overwrite the log that
/// tells what happened before the crash: central does this before it creates its log.
pub fn set_aside(path: &Path) -> Result<Option<PathBuf>> {
    let Some(kept) = aside_name(path)? else {
        return Ok(None);
    };
    std::fs::rename(path, &kept).map_err(|source| LogError::Io {
        path: path.to_owned(),
        source,
    })?;
    Ok(Some(kept))
}

/// Where [`set_aside`] would move the log at `path` now: the first free `STEM.N.mcap` next to
/// it, or `None` when there is no non-empty log to keep. Nothing is moved.
pub fn aside_name(path: &Path) -> Result<Option<PathBuf>> {
    let io = |source| LogError::Io {
        path: path.to_owned(),
        source,
    };
    match std::fs::metadata(path) {
        Ok(m) if m.len() > 0 => {}
        Ok(_) => return Ok(None),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io(e)),
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "traffic".into());
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mcap".into());
    for n in 1..100_000u32 {
        let candidate = path.with_file_name(format!("{stem}.{n}.{ext}"));
        if !candidate.exists() {
            return Ok(Some(candidate));
        }
    }
    Err(LogError::Write(format!(
        "{}: no free name to keep the previous log under; remove old {stem}.N.{ext} files",
        path.display()
    )))
}

#[cfg(test)]
mod set_aside_tests {
    use super::set_aside;

    #[test]
    fn an_earlier_log_is_kept_under_the_next_free_number() {
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("traffic.mcap");
        assert_eq!(set_aside(&log).unwrap(), None, "nothing to keep yet");
        std::fs::write(&log, b"").unwrap();
        assert_eq!(set_aside(&log).unwrap(), None, "an empty file is not kept");
        std::fs::write(&log, b"first").unwrap();
        let first = set_aside(&log).unwrap().unwrap();
        assert_eq!(first, dir.path().join("traffic.1.mcap"));
        std::fs::write(&log, b"second").unwrap();
        let second = set_aside(&log).unwrap().unwrap();
        assert_eq!(second, dir.path().join("traffic.2.mcap"));
        assert!(!log.exists());
        assert_eq!(std::fs::read(first).unwrap(), b"first");
        assert_eq!(std::fs::read(second).unwrap(), b"second");
    }
}
