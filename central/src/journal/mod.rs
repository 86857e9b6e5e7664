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
//!   head, the journal is rewritten as a new head (central's state now) and nothing after it,
//!   into a new file that then replaces the old one (so a crash mid-rewrite leaves the old,
//!   whole).
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
//!   together). For this, a head is written only once the traffic log has written everything
//!   handed to it before.
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
}

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
        })
    }

    /// Appends framed entries.
    pub(crate) fn append(&mut self, entries: &[u8]) -> std::io::Result<()> {
        self.file.write_all(entries)?;
        self.tail_bytes += entries.len() as u64;
        Ok(())
    }

    /// Whether the entries have grown enough for a rewrite.
    pub(crate) fn wants_rewrite(&self) -> bool {
        self.tail_bytes >= MIN_TAIL_BYTES.max(4 * self.head_bytes)
    }

    /// Rewrites the journal as `head` alone (the lock stays held).
    pub(crate) fn rewrite(&mut self, head: &Head) -> Result<()> {
        let (file, head_bytes) = write_head(&self.path, head)?;
        self.file = file;
        self.head_bytes = head_bytes;
        self.tail_bytes = 0;
        Ok(())
    }

    /// Removes the journal (a clean stop: the next central starts afresh).
    pub(crate) fn remove(self) -> Result<()> {
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
    let mut bytes = format::MAGIC.to_vec();
    format::append_record(&mut bytes, head)
        .map_err(|e| io(path)(std::io::Error::other(e.to_string())))?;
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

/// A new journal id: the time and this process, mixed.
pub(crate) fn new_id() -> u64 {
    let mut x = tca_messages::now_ns() ^ (u64::from(std::process::id()) << 40);
    // splitmix64's finaliser.
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (x ^ (x >> 31)).max(1)
}
