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
    /// Writes the core's state as the journal's head (the traffic log having written
    /// `log_records` records, or `None` without a log), turns journaling on, and returns the
    /// journal.
    pub(crate) fn start(self, core: &mut Central, log_records: Option<u64>) -> Result<Journal> {
        let head = head(core, self.id, log_records).map_err(|reason| JournalError::Restore {
            path: self.path.clone(),
            reason,
        })?;
        let journal = Journal::create(&self.path, &head, self.lock)?;
        core.record_journal(self.id);
        Ok(journal)
    }
}

/// The head for the core's state now.
pub(crate) fn head(core: &Central, id: u64, log_records: Option<u64>) -> Result<Head, String> {
    Ok(Head {
        version: env!("CARGO_PKG_VERSION").to_owned(),
        id,
        config: core.config().clone(),
        log_records,
        state: core
            .save()
            .map_err(|e| format!("central's state does not save: {e}"))?,
    })
}

/// Opens the journal at `path` for a central with `config` starting at `now_ns`: a fresh core
/// if it holds nothing, else the crashed central's state restored, its events replayed and
/// its links closed. `previous_log` is the crashed central's traffic log (set aside), checked
/// against what the replay logged; `logging` says whether the new central keeps a log.
pub(crate) fn open(
    path: &Path,
    config: CentralConfig,
    previous_log: Option<&Path>,
    logging: bool,
    now_ns: u64,
) -> Result<Recovered> {
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
        missing_records(
            contents.head.log_records,
            previous_log,
            replayed,
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

/// The records the replay logged (`replayed`, which follow the `head_records` the crashed
/// log held when the head was written) that the crashed log `previous` lacks, checked against
/// those it has.
fn missing_records(
    head_records: Option<u64>,
    previous: Option<&Path>,
    replayed: Vec<LogRecord>,
    warnings: &mut Vec<String>,
) -> Vec<LogRecord> {
    let (Some(k), Some(previous)) = (head_records, previous) else {
        if head_records.is_some() && !replayed.is_empty() {
            warnings.push(format!(
                "the crashed central kept a traffic log, but it was not found where this one \
                 logs: the {} records of its last moments that the journal holds are not \
                 written again",
                replayed.len()
            ));
        }
        return Vec::new();
    };
    let log = match LogFile::open(previous) {
        Ok(log) => log,
        Err(e) => {
            warnings.push(format!(
                "the crashed central's log {} cannot be read ({e}): the records of its last \
                 moments are not written again",
                previous.display()
            ));
            return Vec::new();
        }
    };
    let k = k as usize;
    let held = log.records.len();
    let fits = held >= k && held <= k + replayed.len() && log.records[k..] == replayed[..held - k];
    if !fits {
        warnings.push(format!(
            "the crashed central's log {} does not match its journal ({held} records, the \
             journal's state follows record {k} and its events logged {} more): it is another \
             central's, or was changed; the records of the crashed central's last moments are \
             not written again",
            previous.display(),
            replayed.len()
        ));
        return Vec::new();
    }
    replayed.into_iter().skip(held - k).collect()
}
