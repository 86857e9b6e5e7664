//! Central's journal: what it holds (task trees, waiting and held messages, the goals handed to
//! modules, monitors, constraints, the simulated clock) kept on disk, so that a central
//! restarted on the same journal after a crash (`kill -9`, a panic, the machine's supervisor
//! killing it) comes back whole.
//!
//! # How
//!
//! The core is a deterministic state machine (see `crate::core::journal`), so the journal keeps
//! its inputs: a saved state (the file's head) and every event handled since, with the few
//! facts the core looked up outside itself. A restarted central restores the state, replays the
//! events, and then treats every link of the crashed central as closed: each module went down
//! with it, as far as the restored core knows.
//!
//! - **Written ahead.** The driver writes a batch's entries (one `write` for the batch) before
//!   it sends anything the batch caused. Whatever a module has seen from central is in the
//!   journal; what was lost with a crash was never seen by anyone. A write is in the operating
//!   system's hands once it returns, so a `kill -9` of central loses nothing written; the
//!   journal is not synced to the disk at every batch, so a crash of the whole machine can lose
//!   its last moments (rewrites are synced).
//! - **Bounded.** When the entries after the head pass [`MIN_TAIL_BYTES`] and four times the
//!   head, the journal is rewritten as a new head (central's state now) followed by the
//!   entries made since, into a new file that then replaces the old one (so a crash
//!   mid-rewrite leaves the old, whole). Central's thread only saves its state: writing and
//!   syncing the new file, and waiting for the traffic log to flush, happen on a blocking
//!   thread while central goes on, its entries going to the old file and kept for the new.
//! - **Checked.** Each record carries its length and CRC-32. A torn last record (a crash in the
//!   middle of a write) is dropped; any other damage is refused with its place and what to do.
//! - **One central per journal.** A lock on `FILE.lock` is held while central runs; a second
//!   central on the same journal is refused.
//! - **The traffic log made whole.** The traffic log is written by its own thread and flushed
//!   every 50 ms, so a crash loses its last moments; the journal does not. Replaying the
//!   journal logs again what the crashed central logged since its head (the core is
//!   deterministic), so the restarted central writes at the start of its new log the records
//!   the crashed log lacks, checked against those it has. The logs of a central and its
//!   restarts, read in order, are then one complete history (`tca log audit` takes them
//!   together). For this, a head is put in place only once the traffic log has written
//!   everything handed to it before the head was taken.
//! - **A clean stop ends it.** A central stopped on purpose ([`RunningCentral::shutdown`])
//!   removes its journal: the next one starts afresh.
//!
//! # Exactly once across a restart
//!
//! A goal or command a module was running when central died is, for the restored central, a
//! task whose module went down: it is delivered again when the module has registered again,
//! marked as a redelivery (`Envelope::redelivery`), and the tasks its handler had created are
//! killed, as for any module that dies. Whether the module had finished it does not matter to
//! anyone but the module:
//!
//! - If its end reached central, the journal has it: the task is not delivered again.
//! - If not, nobody saw that end (central sends nothing before it has journaled what caused
//!   it), and a module that acts on the world answers a redelivery of a message id it has
//!   already carried out with the recorded outcome instead of acting twice (the simulated
//!   Controller keeps the outcomes of its latest commands by id in its state file); a planner
//!   simply plans again from the world as it is.
//!
//! Modules notice central's death at once (its liveliness token, or its socket), stop their
//! running handlers and fail their queries in flight (those are lost). A module that waits for
//! the end of a task it sent (a walker waiting for its walk) keeps waiting when the central it
//! rejoins welcomes it with the same journal id, and asks what became of the task
//! (`tca.taskStatus`): still live (its end will be told), ended while it was away (central
//! remembers the ends of the latest watched tasks), or unknown (it never reached central: the
//! wait fails with "central went away").
//!
//! [`RunningCentral::shutdown`]: crate::RunningCentral::shutdown

pub(crate) mod format;
mod recover;

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

pub use format::Head;
pub(crate) use recover::{head, open};

/// The entries after a head may grow to this many bytes before the journal is rewritten (or
/// four times the head, if more).
pub const MIN_TAIL_BYTES: u64 = 8 << 20;

/// Errors of the journal.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// The file could not be read or written.
    #[error("journal {path}: {source}")]
    Io {
        /// The journal.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Another central holds the journal.
    #[error(
        "journal {0} is in use by another central; stop that central first, or give this one \
         another --journal"
    )]
    InUse(PathBuf),
    /// The file is not a journal.
    #[error(
        "{0} is not a central journal (it does not start with the journal's magic bytes); give \
         --journal a file of its own"
    )]
    NotAJournal(PathBuf),
    /// The file is damaged.
    #[error(
        "journal {path} is damaged at byte {offset} (record {index}: {reason}), so central \
         cannot trust it; move it aside (e.g. to {path}.damaged) to start central afresh, \
         without the task trees it held"
    )]
    Damaged {
        /// The journal.
        path: PathBuf,
        /// Where.
        offset: usize,
        /// Which record (0 is the head).
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// Another version of central wrote it.
    #[error(
        "journal {path} was written by tca-central {written}, this is {running}: its saved \
         state cannot be read; finish with the central that wrote it, or move the journal aside \
         to start afresh"
    )]
    Version {
        /// The journal.
        path: PathBuf,
        /// The version that wrote it.
        written: String,
        /// This version.
        running: String,
    },
    /// The saved state or an entry did not fit this central.
    #[error(
        "journal {path} cannot be restored: {reason}; move it aside to start central afresh, \
         without the task trees it held"
    )]
    Restore {
        /// The journal.
        path: PathBuf,
        /// What did not fit.
        reason: String,
    },
}

type Result<T, E = JournalError> = std::result::Result<T, E>;

/// An open journal: the file entries are appended to, and the lock held on it.
#[derive(Debug)]
pub(crate) struct Journal {
    path: PathBuf,
    file: File,
    id: u64,
    /// Bytes of the head record.
    head_bytes: u64,
    /// Bytes appended after it.
    tail_bytes: u64,
    /// The lock file, held while central runs.
    lock: (PathBuf, File),
    /// A rewrite under way, if any.
    rewriting: Option<Rewriting>,
}

/// A rewrite under way: the new head is written and synced to `FILE.new` off central's thread
/// (after the traffic log has flushed what the head counts on), while entries still go to
/// the old file and are kept here to follow the new head. Until the new file replaces the
/// old one, a crash finds the old journal whole.
#[derive(Debug)]
struct Rewriting {
    /// The new file, positioned after its head, and the head's bytes.
    done: tokio::sync::oneshot::Receiver<std::io::Result<(File, u64)>>,
    /// Entries appended since the head was taken.
    tail: Vec<u8>,
}

/// How long a rewrite waits for the traffic log to flush before it goes on without it.
const LOG_FLUSH_WAIT: std::time::Duration = std::time::Duration::from_secs(30);

fn io(path: &Path) -> impl Fn(std::io::Error) -> JournalError + '_ {
    move |source| JournalError::Io {
        path: path.to_owned(),
        source,
    }
}

/// `FILE.SUFFIX` next to `path`.
fn beside(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(suffix);
    PathBuf::from(name)
}

/// Takes the lock of the journal at `path` (held while the returned file is open).
fn lock(path: &Path) -> Result<(PathBuf, File)> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io(path))?;
    }
    let lock_path = beside(path, ".lock");
    let file = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lock_path)
        .map_err(io(&lock_path))?;
    match file.try_lock() {
        Ok(()) => Ok((lock_path, file)),
        Err(std::fs::TryLockError::WouldBlock) => Err(JournalError::InUse(path.to_owned())),
        Err(std::fs::TryLockError::Error(e)) => Err(io(&lock_path)(e)),
    }
}

impl Journal {
    /// The journal's id.
    pub(crate) fn id(&self) -> u64 {
        self.id
    }

    /// The file.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// A journal holding `head` alone, at `path`, whose lock is held.
    fn create(path: &Path, head: &Head, lock: (PathBuf, File)) -> Result<Journal> {
        let (file, head_bytes) = write_head(path, head)?;
        Ok(Journal {
            path: path.to_owned(),
            file,
            id: head.id,
            head_bytes,
            tail_bytes: 0,
            lock,
            rewriting: None,
        })
    }

    /// Appends framed entries.
    pub(crate) fn append(&mut self, entries: &[u8]) -> std::io::Result<()> {
        self.file.write_all(entries)?;
        self.tail_bytes += entries.len() as u64;
        if let Some(r) = self.rewriting.as_mut() {
            r.tail.extend_from_slice(entries);
        }
        Ok(())
    }

    /// Whether the entries have grown enough for a rewrite (and none is under way).
    pub(crate) fn wants_rewrite(&self) -> bool {
        self.rewriting.is_none() && self.tail_bytes >= MIN_TAIL_BYTES.max(4 * self.head_bytes)
    }

    /// Starts rewriting the journal as `head` and the entries appended from now on: the head
    /// is written and synced to `FILE.new` on a blocking thread, once `log_flushed` says the
    /// traffic log holds the records the head counts on (or after [`LOG_FLUSH_WAIT`]);
    /// [`Journal::finish_rewrite`] puts the new file in place. Must run in a tokio runtime.
    pub(crate) fn start_rewrite(
        &mut self,
        head: &Head,
        log_flushed: Option<std::sync::mpsc::Receiver<()>>,
    ) -> Result<()> {
        let bytes = head_bytes(&self.path, head)?;
        let new = beside(&self.path, ".new");
        let (tx, done) = tokio::sync::oneshot::channel();
        tokio::task::spawn_blocking(move || {
            if let Some(flushed) = log_flushed
                && let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                    flushed.recv_timeout(LOG_FLUSH_WAIT)
            {
                tracing::warn!("the traffic-log writer did not flush within 30 s");
            }
            let written = File::create(&new).and_then(|mut f| {
                f.write_all(&bytes)?;
                f.sync_data()?;
                Ok((f, bytes.len() as u64))
            });
            let _ = tx.send(written);
        });
        self.rewriting = Some(Rewriting {
            done,
            tail: Vec::new(),
        });
        Ok(())
    }

    /// Puts a finished rewrite in place: the entries appended meanwhile follow the new head,
    /// then the new file replaces the old. `None` while it is still being written (or when no
    /// rewrite is under way).
    pub(crate) fn finish_rewrite(&mut self) -> Option<Result<()>> {
        use tokio::sync::oneshot::error::TryRecvError;
        let written = match self.rewriting.as_mut()?.done.try_recv() {
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Closed) => Err(std::io::Error::other(
                "the thread writing the new journal stopped",
            )),
            Ok(written) => written,
        };
        let tail = self.rewriting.take().map(|r| r.tail).unwrap_or_default();
        let new = beside(&self.path, ".new");
        let installed = written.and_then(|(mut file, head_bytes)| {
            file.write_all(&tail)?;
            std::fs::rename(&new, &self.path)?;
            Ok((file, head_bytes))
        });
        Some(match installed {
            Ok((file, head_bytes)) => {
                self.file = file;
                self.head_bytes = head_bytes;
                self.tail_bytes = tail.len() as u64;
                Ok(())
            }
            Err(e) => Err(io(&self.path)(e)),
        })
    }

    /// Removes the journal (a clean stop: the next central starts afresh).
    pub(crate) fn remove(self) -> Result<()> {
        if self.rewriting.is_some() {
            let _ = std::fs::remove_file(beside(&self.path, ".new"));
        }
        std::fs::remove_file(&self.path).map_err(io(&self.path))?;
        let (lock_path, lock) = self.lock;
        drop(lock);
        let _ = std::fs::remove_file(lock_path);
        Ok(())
    }
}

/// Writes `head` as the whole journal at `path` (into `FILE.new`, synced, then renamed over
/// it, so a crash leaves either journal whole) and opens it for appending; returns the file and
/// the bytes written.
fn write_head(path: &Path, head: &Head) -> Result<(File, u64)> {
    let bytes = head_bytes(path, head)?;
    let new = beside(path, ".new");
    File::create(&new)
        .and_then(|mut f| f.write_all(&bytes).and_then(|()| f.sync_data()))
        .and_then(|()| std::fs::rename(&new, path))
        .map_err(io(path))?;
    let file = OpenOptions::new()
        .append(true)
        .open(path)
        .map_err(io(path))?;
    Ok((file, bytes.len() as u64))
}

/// The bytes of a journal holding `head` alone (for the journal at `path`, in errors).
fn head_bytes(path: &Path, head: &Head) -> Result<Vec<u8>> {
    let mut bytes = format::MAGIC.to_vec();
    format::append_record(&mut bytes, head)
        .map_err(|e| io(path)(std::io::Error::other(e.to_string())))?;
    Ok(bytes)
}

/// A new journal id: the time and this process, mixed.
pub(crate) fn new_id() -> u64 {
    let mut x = tca_messages::now_ns() ^ (u64::from(std::process::id()) << 40);
    // splitmix64's finaliser.
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (x ^ (x >> 31)).max(1)
}

#[cfg(test)]
mod rewrite_tests {
    use super::format::{self, Head, append_record};
    use super::{Journal, beside, lock};
    use crate::config::CentralConfig;
    use crate::core::{Fact, JournalEntry, JournaledEvent};

    fn head(id: u64, state: u8) -> Head {
        Head {
            version: "v".into(),
            id,
            config: CentralConfig::default(),
            log_records: None,
            log_prefix: Vec::new(),
            log_kept_as: None,
            state: vec![state],
        }
    }

    fn entry(i: u64) -> Vec<u8> {
        let mut bytes = Vec::new();
        let e = JournalEntry {
            at_ns: i,
            event: JournaledEvent::Frame(1, bytes::Bytes::from(vec![i as u8; 20])),
            facts: vec![Fact::ProcessGone(false)],
        };
        append_record(&mut bytes, &e).unwrap();
        bytes
    }

    fn read(path: &std::path::Path) -> (u8, Vec<u64>) {
        let c = format::parse(&std::fs::read(path).unwrap())
            .unwrap()
            .unwrap();
        (c.head.state[0], c.entries.iter().map(|e| e.at_ns).collect())
    }

    #[tokio::test]
    async fn a_rewrite_keeps_the_entries_made_while_it_was_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("j");
        let mut j = Journal::create(&path, &head(7, 1), lock(&path).unwrap()).unwrap();
        j.append(&entry(1)).unwrap();
        // The log has not flushed yet: the new head waits, and entries go on meanwhile.
        let (flushed, log_flushed) = std::sync::mpsc::channel();
        j.start_rewrite(&head(7, 2), Some(log_flushed)).unwrap();
        assert!(!j.wants_rewrite(), "one rewrite at a time");
        j.append(&entry(2)).unwrap();
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
        assert!(j.finish_rewrite().is_none(), "still waiting for the log");
        // A crash now finds the old journal whole, with every entry.
        assert_eq!(read(&path), (1, vec![1, 2]));
        flushed.send(()).unwrap();
        let mut installed = None;
        for _ in 0..200 {
            j.append(&entry(3)).unwrap();
            installed = j.finish_rewrite();
            if installed.is_some() {
                break;
            }
            tokio::time::sleep(std::time::Duration::from_millis(10)).await;
        }
        installed.expect("the rewrite finished").unwrap();
        j.append(&entry(4)).unwrap();
        let (state, entries) = read(&path);
        assert_eq!(state, 2, "the new head");
        assert_eq!(
            entries[0], 2,
            "what came after the head was taken follows it"
        );
        assert_eq!(*entries.last().unwrap(), 4);
        assert!(entries[1..entries.len() - 1].iter().all(|&e| e == 3));
        assert!(!beside(&path, ".new").exists());
        j.remove().unwrap();
        assert!(!path.exists());
    }
}
