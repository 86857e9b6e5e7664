//! Opening a journal: a fresh one, or a crashed central's state restored from it.

use std::fs::File;
use std::path::{Path, PathBuf};

use tca_logs::{LogFile, LogRecord};

use super::format::{self, Damage, Head};
use super::{Journal, JournalError, Result, io, lock, new_id};
use crate::config::CentralConfig;
use crate::core::{Action, Central};

/// What opening a journal gives: central's core (fresh or restored), what to write at the
/// start of the new traffic log, and the journal to start once that is written.
pub(crate) struct Recovered {
    /// The core.
    pub(crate) core: Central,
    /// Records for the start of the new traffic log: those of the crashed central's last
    /// moments its log lacks, then those of its links closing.
    pub(crate) log_prefix: Vec<LogRecord>,
    /// How many of `log_prefix` are the crashed central's, recovered.
    pub(crate) recovered: usize,
    /// What was restored, in words (None for a fresh journal).
    pub(crate) summary: Option<String>,
    /// Warnings about the traffic log (it could not be made whole).
    pub(crate) warnings: Vec<String>,
    /// The journal, to start with [`Pending::start`].
    pub(crate) pending: Pending,
}

/// A journal whose lock is held and whose head is yet to be written.
pub(crate) struct Pending {
    path: PathBuf,
    id: u64,
    lock: (PathBuf, File),
}

impl Pending {
    /// Writes the core's state as the journal's head, turns journaling on, and returns the
    /// journal. With a traffic log (`logging`), the head says that `log_prefix` follows at the
    /// start of the new log: written after the head, so that a crash before they are all in
    /// the log loses none of them. `log_kept_as` is where the log now at the log path is to be
    /// moved once this returns (see [`Head::log_kept_as`]).
    pub(crate) fn start(
        self,
        core: &mut Central,
        logging: bool,
        log_prefix: Vec<LogRecord>,
        log_kept_as: Option<PathBuf>,
    ) -> Result<Journal> {
        let mut head = head(core, self.id, logging.then_some(0), log_prefix).map_err(|reason| {
            JournalError::Restore {
                path: self.path.clone(),
                reason,
            }
        })?;
        head.log_kept_as = log_kept_as;
        let journal = Journal::create(&self.path, &head, self.lock)?;
        core.record_journal(self.id);
        Ok(journal)
    }
}

/// The head for the core's state now, the traffic log holding `log_records` records (`None`
/// without a log) to be followed by `log_prefix`.
pub(crate) fn head(
    core: &Central,
    id: u64,
    log_records: Option<u64>,
    log_prefix: Vec<LogRecord>,
) -> Result<Head, String> {
    Ok(Head {
        version: env!("CARGO_PKG_VERSION").to_owned(),
        id,
        config: core.config().clone(),
        log_records,
        log_prefix,
        log_kept_as: None,
        state: core
            .save()
            .map_err(|e| format!("central's state does not save: {e}"))?,
    })
}

/// Opens the journal at `path` for a central with `config` starting at `now_ns`: a fresh core
/// if it holds nothing, else the crashed central's state restored, its events replayed and
/// its links closed. `log` is the new central's traffic log path, where the crashed central's
/// log still is (not yet moved aside): it is checked against what the replay logged.
pub(crate) fn open(
    path: &Path,
    config: CentralConfig,
    log: Option<&Path>,
    now_ns: u64,
) -> Result<Recovered> {
    let logging = log.is_some();
    let lock = lock(path)?;
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(io(path)(e)),
    };
    let contents = format::parse(&bytes).map_err(|damage| match damage {
        Damage::NotAJournal => JournalError::NotAJournal(path.to_owned()),
        Damage::Record {
            offset,
            index,
            reason,
        } => JournalError::Damaged {
            path: path.to_owned(),
            offset,
            index,
            reason,
        },
    })?;
    let Some(contents) = contents else {
        return Ok(Recovered {
            core: Central::new(config),
            log_prefix: Vec::new(),
            recovered: 0,
            summary: None,
            warnings: Vec::new(),
            pending: Pending {
                path: path.to_owned(),
                id: new_id(),
                lock,
            },
        });
    };
    let restore_error = |reason: String| JournalError::Restore {
        path: path.to_owned(),
        reason,
    };
    let running = env!("CARGO_PKG_VERSION");
    if contents.head.version != running {
        return Err(JournalError::Version {
            path: path.to_owned(),
            written: contents.head.version,
            running: running.to_owned(),
        });
    }
    if contents.head.config.simulated_time != config.simulated_time {
        let (kept, flag) = if contents.head.config.simulated_time {
            ("the simulated clock", "with --simulated-time")
        } else {
            ("the wall clock", "without --simulated-time")
        };
        return Err(restore_error(format!(
            "it was kept on {kept}; start central {flag}"
        )));
    }
    let mut core = Central::restore(&contents.head.state, contents.head.config.clone())
        .map_err(|e| restore_error(e.to_string()))?;
    core.set_journal_id(contents.head.id);
    let mut out = Vec::new();
    let mut replayed = Vec::new();
    let entries = contents.entries.len();
    for entry in contents.entries {
        core.replay(entry, &mut out)
            .map_err(|e| restore_error(e.to_string()))?;
        replayed.extend(out.drain(..).filter_map(|a| match a {
            Action::Log(record) => Some(record),
            _ => None,
        }));
    }
    core.set_config(config);
    let links = core.connected_modules().len();
    let live = core.live_nodes();
    core.links_lost(now_ns, &mut out);
    let closing: Vec<LogRecord> = out
        .drain(..)
        .filter_map(|a| match a {
            Action::Log(record) => Some(record),
            _ => None,
        })
        .collect();
    let mut warnings = Vec::new();
    let mut log_prefix = if logging {
        let mut expected = contents.head.log_prefix;
        expected.extend(replayed);
        let previous_log = log.filter(|l| written_by_head(l, contents.head.log_kept_as.as_deref()));
        missing_records(
            contents.head.log_records,
            previous_log,
            expected,
            &mut warnings,
        )
    } else {
        Vec::new()
    };
    let recovered = log_prefix.len();
    if logging {
        log_prefix.extend(closing);
    }
    let summary = format!(
        "restored from journal {}: {live} live task node(s), {links} module(s) to rejoin, {entries} \
         event(s) replayed after the saved state{}",
        path.display(),
        if contents.torn_bytes > 0 {
            format!(
                "; a torn last record ({} bytes, cut short by the crash) was dropped",
                contents.torn_bytes
            )
        } else {
            String::new()
        }
    );
    Ok(Recovered {
        core,
        log_prefix,
        recovered,
        summary: Some(summary),
        warnings,
        pending: Pending {
            path: path.to_owned(),
            id: contents.head.id,
            lock,
        },
    })
}

/// Whether the file at the log path `log` is the log of the central whose head says it was to
/// move its predecessor's log to `kept_as`: not when that move was never made (the file is the
/// predecessor's; the crashed central died before it had a log), nor when there is no file or
/// an empty one.
fn written_by_head(log: &Path, kept_as: Option<&Path>) -> bool {
    if kept_as.is_some_and(|k| !k.exists()) {
        return false;
    }
    std::fs::metadata(log).is_ok_and(|m| m.len() > 0)
}

/// The records the crashed central logged or was to log after the `head_records` its log
/// held when its head was written (`expected`: the head's prefix, then what the replay logged)
/// that the crashed log `previous` lacks, checked against those it has. A log that was never
/// written (not found) holds none.
fn missing_records(
    head_records: Option<u64>,
    previous: Option<&Path>,
    expected: Vec<LogRecord>,
    warnings: &mut Vec<String>,
) -> Vec<LogRecord> {
    let Some(k) = head_records else {
        return Vec::new();
    };
    let k = k as usize;
    let held: Vec<LogRecord> = match previous {
        None if k == 0 => Vec::new(),
        None => {
            if !expected.is_empty() {
                warnings.push(format!(
                    "the crashed central kept a traffic log, but it was not found where this \
                     one logs: the {} records of its last moments that the journal holds are \
                     not written again",
                    expected.len()
                ));
            }
            return Vec::new();
        }
        Some(previous) => match LogFile::open(previous) {
            Ok(log) => log.records,
            Err(e) => {
                warnings.push(format!(
                    "the crashed central's log {} cannot be read ({e}): the records of its \
                     last moments are not written again",
                    previous.display()
                ));
                return Vec::new();
            }
        },
    };
    let n = held.len();
    let fits = n >= k && n <= k + expected.len() && held[k..] == expected[..n - k];
    if !fits {
        warnings.push(format!(
            "the crashed central's log {} does not match its journal ({n} records, the \
             journal's state follows record {k} and {} more were to follow): it is another \
             central's, or was changed; the records of the crashed central's last moments are \
             not written again",
            previous.map_or_else(|| "(none)".into(), |p| p.display().to_string()),
            expected.len()
        ));
        return Vec::new();
    }
    expected.into_iter().skip(n - k).collect()
}

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};

    use super::{missing_records, open};
    use crate::config::CentralConfig;
    use crate::core::Central;
    use crate::journal::format::{self, Head};
    use tca_logs::{LinkEvent, LinkRecord, LogRecord, LogWriter, RecordKind};

    fn record(i: u64) -> LogRecord {
        LogRecord {
            at_ns: i,
            kind: RecordKind::Link(LinkRecord {
                link: i as u32,
                event: LinkEvent::Closed,
                module: None,
                detail: String::new(),
            }),
        }
    }

    #[test]
    fn a_crashed_log_never_written_lacks_all_that_its_head_announced() {
        let expected: Vec<LogRecord> = (0..5).map(record).collect();
        let mut warnings = Vec::new();
        let missing = missing_records(Some(0), None, expected.clone(), &mut warnings);
        assert_eq!(missing, expected);
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    #[test]
    fn a_log_missing_after_it_held_records_is_said_and_nothing_is_made_up() {
        let expected: Vec<LogRecord> = (0..5).map(record).collect();
        let mut warnings = Vec::new();
        let missing = missing_records(Some(7), None, expected, &mut warnings);
        assert!(missing.is_empty());
        assert!(warnings[0].contains("not found"), "{warnings:?}");
    }

    #[test]
    fn without_a_log_nothing_is_missing() {
        let mut warnings = Vec::new();
        assert!(missing_records(None, None, vec![record(1)], &mut warnings).is_empty());
        assert!(warnings.is_empty());
    }

    /// A journal at `path` holding `head` alone: a central that wrote its first head and was
    /// killed before anything else.
    fn write_journal(path: &Path, log_prefix: Vec<LogRecord>, log_kept_as: Option<PathBuf>) {
        let config = CentralConfig::default();
        let head = Head {
            version: env!("CARGO_PKG_VERSION").to_owned(),
            id: 9,
            state: Central::new(config.clone()).save().unwrap(),
            config,
            log_records: Some(0),
            log_prefix,
            log_kept_as,
        };
        let mut bytes = format::MAGIC.to_vec();
        format::append_record(&mut bytes, &head).unwrap();
        std::fs::write(path, bytes).unwrap();
    }

    fn write_log(path: &Path, records: &[LogRecord]) {
        let mut log = LogWriter::create(path).unwrap();
        for r in records {
            log.append(r).unwrap();
        }
        log.finish().unwrap();
    }

    #[test]
    fn a_central_killed_before_it_moved_its_predecessors_log_had_no_log() {
        // The predecessor logged 0..5 (all in its log, still at the log path); the central
        // restarted after it wrote a head announcing 100..102 and was killed before it moved
        // that log to traffic.1.mcap and created its own.
        let dir = tempfile::tempdir().unwrap();
        let (journal, log) = (dir.path().join("j"), dir.path().join("traffic.mcap"));
        write_log(&log, &(0..5).map(record).collect::<Vec<_>>());
        let announced: Vec<LogRecord> = (100..102).map(record).collect();
        write_journal(
            &journal,
            announced.clone(),
            Some(dir.path().join("traffic.1.mcap")),
        );
        let r = open(&journal, CentralConfig::default(), Some(&log), 0).unwrap();
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        assert_eq!(
            r.recovered, 2,
            "what the killed central announced, and no more"
        );
        assert_eq!(r.log_prefix[..2], announced[..]);
    }

    #[test]
    fn a_central_that_moved_its_predecessors_log_is_checked_against_its_own() {
        let dir = tempfile::tempdir().unwrap();
        let (journal, log) = (dir.path().join("j"), dir.path().join("traffic.mcap"));
        let kept = dir.path().join("traffic.1.mcap");
        write_log(&kept, &(0..5).map(record).collect::<Vec<_>>());
        let announced: Vec<LogRecord> = (100..103).map(record).collect();
        write_log(&log, &announced[..1]);
        write_journal(&journal, announced.clone(), Some(kept));
        let r = open(&journal, CentralConfig::default(), Some(&log), 0).unwrap();
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        assert_eq!(r.recovered, 2, "the two its log lacks");
        assert_eq!(r.log_prefix[..2], announced[1..]);
    }

    #[test]
    fn another_centrals_log_at_the_log_path_is_not_taken_for_its_own() {
        // Without the head saying where the predecessor's log was to go, a log that does not
        // match is refused with a warning rather than written twice.
        let dir = tempfile::tempdir().unwrap();
        let (journal, log) = (dir.path().join("j"), dir.path().join("traffic.mcap"));
        write_log(&log, &(0..5).map(record).collect::<Vec<_>>());
        write_journal(&journal, (100..102).map(record).collect(), None);
        let r = open(&journal, CentralConfig::default(), Some(&log), 0).unwrap();
        assert_eq!(r.recovered, 0);
        assert!(r.warnings[0].contains("does not match"), "{:?}", r.warnings);
    }
}
