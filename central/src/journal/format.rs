//! The journal file's format: magic bytes, then records, each its payload's length and CRC-32
//! (both little-endian `u32`) and the payload (postcard). The first record is the [`Head`]
//! (central's saved state); every other one is a [`JournalEntry`](crate::core::JournalEntry).
//!
//! Central appends whole records with one write per batch of events, so a crash leaves at most
//! the last record torn (cut short, or zeros where the machine lost the end of the file): that
//! is dropped when the journal is read. A record that does not check out anywhere else means
//! the file was damaged; it is refused, saying where.

use serde::{Deserialize, Serialize};

use crate::config::CentralConfig;
use crate::core::JournalEntry;

/// The first bytes of a journal file.
pub(crate) const MAGIC: &[u8; 8] = b"TCAJRNL1";

/// Bytes before each record's payload: its length and its CRC-32.
pub(crate) const RECORD_HEADER: usize = 8;

/// Largest record accepted when reading (a corrupt length is not believed past it).
const MAX_RECORD: usize = 1 << 30;

/// The journal's first record: central's state when it was saved.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Head {
    /// The version of `tca-central` that wrote it: another version cannot replay it.
    pub version: String,
    /// The journal's id, kept across restarts and rewrites (modules learn it in their welcome).
    pub id: u64,
    /// The configuration central ran with (the policy is not kept: what it made of each hello
    /// is in the entries).
    pub config: CentralConfig,
    /// How many records the traffic log held before `log_prefix` when the state was saved (all
    /// of them written by then); `None` without a log.
    pub log_records: Option<u64>,
    /// Records that follow those `log_records` in the traffic log, written (or being written)
    /// after this head: a restarted central's first head carries what it puts at the start of
    /// its new log (the crashed central's last moments, its links closing), so that a crash
    /// before they are all written loses none of them; empty in later heads.
    pub log_prefix: Vec<tca_logs::LogRecord>,
    /// Where the central that wrote this head was to move its predecessor's traffic log
    /// before creating its own (`None` when there was none to move, and in rewritten heads).
    /// While nothing is there the move was not made: the log at the log path is still the
    /// predecessor's, and this head's log was never written.
    pub log_kept_as: Option<std::path::PathBuf>,
    /// The saved state ([`Central::save`](crate::Central::save)).
    pub state: Vec<u8>,
}

/// Appends `value` as one record to `buf` (nothing, if it does not serialize).
pub(crate) fn append_record<T: Serialize>(buf: &mut Vec<u8>, value: &T) -> postcard::Result<()> {
    let start = begin_record(buf);
    if let Err(e) = postcard::to_io(value, &mut *buf) {
        buf.truncate(start);
        return Err(e);
    }
    end_record(buf, start);
    Ok(())
}

/// Starts a record at the end of `buf`: its header, filled in by [`end_record`] once the
/// payload follows it. Returns where the record starts.
pub(crate) fn begin_record(buf: &mut Vec<u8>) -> usize {
    let start = buf.len();
    buf.extend_from_slice(&[0; RECORD_HEADER]);
    start
}

/// Ends the record begun at `start`: its header gets the length and CRC-32 of the payload
/// written after it.
pub(crate) fn end_record(buf: &mut [u8], start: usize) {
    let payload = &buf[start + RECORD_HEADER..];
    let len = (payload.len() as u32).to_le_bytes();
    let crc = crc32fast::hash(payload).to_le_bytes();
    buf[start..start + 4].copy_from_slice(&len);
    buf[start + 4..start + RECORD_HEADER].copy_from_slice(&crc);
}

/// What a journal file holds.
#[derive(Debug)]
pub(crate) struct Contents {
    /// The saved state.
    pub head: Head,
    /// The events after it, in order.
    pub entries: Vec<JournalEntry>,
    /// Bytes of a torn last record that were dropped (0 when the file ended cleanly).
    pub torn_bytes: usize,
}

/// Why a journal's bytes cannot be used.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Damage {
    /// It does not start with [`MAGIC`].
    NotAJournal,
    /// A record other than a torn last one does not check out.
    Record {
        /// Its position in the file.
        offset: usize,
        /// Which record (0 is the head).
        index: usize,
        /// What is wrong.
        reason: String,
    },
}

/// Reads a journal's bytes. An empty input is `Ok(None)` (a journal not yet written).
pub(crate) fn parse(bytes: &[u8]) -> Result<Option<Contents>, Damage> {
    if bytes.is_empty() {
        return Ok(None);
    }
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(Damage::NotAJournal);
    }
    let mut offset = MAGIC.len();
    let mut index = 0usize;
    let mut head: Option<Head> = None;
    let mut entries = Vec::new();
    let mut torn_bytes = 0;
    while offset < bytes.len() {
        let rest = &bytes[offset..];
        let damage = |reason: String| Damage::Record {
            offset,
            index,
            reason,
        };
        let torn = rest.len() < RECORD_HEADER || rest.iter().all(|b| *b == 0) || {
            let len = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
            len > MAX_RECORD || RECORD_HEADER + len > rest.len()
        };
        if torn {
            if index == 0 {
                return Err(damage("the head record is cut short".into()));
            }
            torn_bytes = rest.len();
            break;
        }
        let len = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        let crc = u32::from_le_bytes([rest[4], rest[5], rest[6], rest[7]]);
        let payload = &rest[RECORD_HEADER..RECORD_HEADER + len];
        let last = RECORD_HEADER + len == rest.len();
        let decoded: Result<(), String> = if crc32fast::hash(payload) != crc {
            Err("its checksum does not match".into())
        } else if index == 0 {
            postcard::from_bytes::<Head>(payload)
                .map(|h| head = Some(h))
                .map_err(|e| format!("the head does not decode: {e}"))
        } else {
            postcard::from_bytes::<JournalEntry>(payload)
                .map(|e| entries.push(e))
                .map_err(|e| format!("the entry does not decode: {e}"))
        };
        if let Err(reason) = decoded {
            if last && index > 0 {
                // A last record written only in part (the machine lost its end).
                torn_bytes = rest.len();
                break;
            }
            return Err(damage(reason));
        }
        offset += RECORD_HEADER + len;
        index += 1;
    }
    let Some(head) = head else {
        return Err(Damage::Record {
            offset: MAGIC.len(),
            index: 0,
            reason: "there is no head record".into(),
        });
    };
    Ok(Some(Contents {
        head,
        entries,
        torn_bytes,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::{Fact, JournaledEvent};

    fn journal(entries: usize) -> (Vec<u8>, Vec<usize>) {
        let mut bytes = MAGIC.to_vec();
        let head = Head {
            version: "v".into(),
            id: 7,
            config: CentralConfig::default(),
            log_records: Some(3),
            log_prefix: Vec::new(),
            log_kept_as: None,
            state: vec![1, 2, 3],
        };
        append_record(&mut bytes, &head).unwrap();
        let mut ends = vec![bytes.len()];
        for i in 0..entries {
            let entry = JournalEntry {
                at_ns: i as u64,
                event: JournaledEvent::Frame(1, bytes::Bytes::from(vec![i as u8; 40])),
                facts: vec![Fact::ProcessGone(i % 2 == 0)],
            };
            append_record(&mut bytes, &entry).unwrap();
            ends.push(bytes.len());
        }
        (bytes, ends)
    }

    #[test]
    fn records_read_back() {
        let (bytes, _) = journal(3);
        let c = parse(&bytes).unwrap().unwrap();
        assert_eq!(c.head.id, 7);
        assert_eq!(c.head.state, vec![1, 2, 3]);
        assert_eq!(c.entries.len(), 3);
        assert_eq!(c.entries[2].at_ns, 2);
        assert_eq!(c.torn_bytes, 0);
        assert!(parse(&[]).unwrap().is_none());
    }

    #[test]
    fn a_torn_last_record_is_dropped_wherever_it_was_cut() {
        let (bytes, ends) = journal(3);
        for cut in ends[2] + 1..ends[3] {
            let c = parse(&bytes[..cut]).unwrap().unwrap();
            assert_eq!(c.entries.len(), 2, "cut at {cut}");
            assert_eq!(c.torn_bytes, cut - ends[2]);
        }
        // The end of the file lost to zeros, or its last payload garbled.
        let mut zeroed = bytes.clone();
        zeroed.extend_from_slice(&[0; 100]);
        assert_eq!(parse(&zeroed).unwrap().unwrap().entries.len(), 3);
        let mut garbled = bytes.clone();
        let last = garbled.len() - 1;
        garbled[last] ^= 0xff;
        let c = parse(&garbled).unwrap().unwrap();
        assert_eq!(c.entries.len(), 2);
    }

    #[test]
    fn damage_before_the_end_is_refused_with_its_place() {
        let (mut bytes, ends) = journal(3);
        bytes[ends[1] + 10] ^= 0xff;
        match parse(&bytes) {
            Err(Damage::Record {
                offset,
                index,
                reason,
            }) => {
                assert_eq!((offset, index), (ends[1], 2));
                assert!(reason.contains("checksum"), "{reason}");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(parse(b"TCAJRNL0....").unwrap_err(), Damage::NotAJournal);
        assert!(matches!(
            parse(&journal(0).0[..MAGIC.len() + 12]),
            Err(Damage::Record { index: 0, .. })
        ));
    }
}
