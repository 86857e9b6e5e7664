//! [`LogSink`]: the log writer on a thread of its own, so that central never waits for the disk.
//!
//! Central hands the sink a batch of records after each round of routing. Waking a sleeping
//! thread costs a system call and, on a busy machine, a wait for a core, on the path of the very
//! message being routed. So the sink does not wake its thread for every batch: while traffic
//! flows the thread looks at the queue every [`POLL_INTERVAL`] by itself, and only a thread
//! that found nothing for [`IDLE_AFTER`] goes to sleep until the next batch wakes it (or until
//! [`WAKE_AT_RECORDS`] records wait, to keep the queue short under a flood). Every record is
//! still written, in order; the file is flushed every [`FLUSH_INTERVAL`] as before.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::error::{LogError, Result};
use crate::record::LogRecord;
use crate::writer::{FLUSH_INTERVAL, LogWriter};

/// How often the writer thread, while traffic flows, takes what is queued.
pub const POLL_INTERVAL: Duration = Duration::from_millis(1);

/// How long the writer thread finds nothing queued before it sleeps until woken.
pub const IDLE_AFTER: Duration = Duration::from_millis(20);

/// Records queued at which a batch wakes the writer thread even while it polls.
pub const WAKE_AT_RECORDS: usize = 4096;

/// What central and the writer thread share.
#[derive(Default)]
struct Queue {
    records: Vec<LogRecord>,
    /// Callers waiting for everything queued before them to be written and flushed.
    flushes: Vec<mpsc::Sender<()>>,
    /// The thread sleeps until woken (it does not poll).
    asleep: bool,
    finishing: bool,
}

struct Shared {
    queue: Mutex<Queue>,
    wake: Condvar,
    /// Records queued and not yet written.
    backlog: AtomicUsize,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Queue> {
        self.queue.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// A log writer on its own thread: `append` never blocks central on disk I/O, and seldom
/// wakes the thread (see the module documentation). The thread flushes every
/// [`FLUSH_INTERVAL`], so the file is readable up to ~50 ms before a crash.
pub struct LogSink {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<Result<()>>>,
}

impl LogSink {
    /// Creates the file and starts the writer thread.
    pub fn create(path: &std::path::Path) -> Result<Self> {
        let writer = LogWriter::create(path)?;
        let shared = Arc::new(Shared {
            queue: Mutex::new(Queue::default()),
            wake: Condvar::new(),
            backlog: AtomicUsize::new(0),
        });
        let theirs = shared.clone();
        let thread = std::thread::Builder::new()
            .name("tca-log".into())
            .spawn(move || run(writer, &theirs))
            .map_err(|e| LogError::WriterGone(e.to_string()))?;
        Ok(LogSink {
            shared,
            thread: Some(thread),
        })
    }

    /// Records queued and not yet written: what the writer thread has still to do.
    pub fn backlog(&self) -> usize {
        self.shared.backlog.load(Ordering::Relaxed)
    }

    /// Queues a record.
    pub fn append(&mut self, record: LogRecord) {
        self.append_batch(vec![record]);
    }

    /// Queues records, in order after those queued before.
    pub fn append_batch(&mut self, mut records: Vec<LogRecord>) {
        if records.is_empty() {
            return;
        }
        if self.thread.as_ref().is_none_or(|t| t.is_finished()) {
            tracing::error!("log writer thread has stopped; traffic is no longer logged");
            return;
        }
        self.shared
            .backlog
            .fetch_add(records.len(), Ordering::Relaxed);
        let mut q = self.shared.lock();
        if q.records.is_empty() {
            // Hand the whole vector over rather than copying it.
            std::mem::swap(&mut q.records, &mut records);
        } else {
            q.records.append(&mut records);
        }
        if q.asleep || q.records.len() >= WAKE_AT_RECORDS {
            q.asleep = false;
            drop(q);
            self.shared.wake.notify_one();
        }
    }

    /// Asks the writer thread to write and flush to the operating system every record queued
    /// so far; the receiver gets `()` once it has (or is dropped if the thread has stopped).
    pub fn flush(&mut self) -> mpsc::Receiver<()> {
        let (tx, rx) = mpsc::channel();
        if self.thread.as_ref().is_some_and(|t| !t.is_finished()) {
            let mut q = self.shared.lock();
            q.flushes.push(tx);
            q.asleep = false;
            drop(q);
            self.shared.wake.notify_one();
        }
        rx
    }

    /// Writes what is queued, the summary, and closes the file.
    pub fn finish(mut self) -> Result<()> {
        self.stop()
    }

    fn stop(&mut self) -> Result<()> {
        let Some(thread) = self.thread.take() else {
            return Ok(());
        };
        self.shared.lock().finishing = true;
        self.shared.wake.notify_one();
        thread
            .join()
            .map_err(|_| LogError::WriterGone("writer thread panicked".into()))?
    }
}

impl Drop for LogSink {
    fn drop(&mut self) {
        let _ = self.stop();
    }
}

/// The writer thread: takes what is queued, writes it, flushes on time, and polls or sleeps.
fn run(mut writer: LogWriter, shared: &Shared) -> Result<()> {
    let mut batch = Vec::new();
    let mut flushes = Vec::new();
    let mut dirty = false;
    let mut last_flush = Instant::now();
    let mut last_record = Instant::now();
    loop {
        let finishing = {
            let mut q = shared.lock();
            loop {
                if !q.records.is_empty() || !q.flushes.is_empty() || q.finishing {
                    break;
                }
                let flush_in = dirty.then(|| FLUSH_INTERVAL.saturating_sub(last_flush.elapsed()));
                if flush_in == Some(Duration::ZERO) {
                    break;
                }
                if last_record.elapsed() < IDLE_AFTER {
                    // Traffic flows: look again shortly, unasked.
                    let wait = flush_in.map_or(POLL_INTERVAL, |f| f.min(POLL_INTERVAL));
                    q = shared
                        .wake
                        .wait_timeout(q, wait)
                        .unwrap_or_else(|p| p.into_inner())
                        .0;
                    if q.records.is_empty() && q.flushes.is_empty() {
                        // A poll that finds nothing ends here; the idle clock goes on.
                        break;
                    }
                } else {
                    // Quiet: sleep until a batch wakes us (or the next flush is due).
                    q.asleep = true;
                    q = match flush_in {
                        Some(f) => {
                            shared
                                .wake
                                .wait_timeout(q, f)
                                .unwrap_or_else(|p| p.into_inner())
                                .0
                        }
                        None => shared.wake.wait(q).unwrap_or_else(|p| p.into_inner()),
                    };
                    q.asleep = false;
                }
            }
            std::mem::swap(&mut batch, &mut q.records);
            std::mem::swap(&mut flushes, &mut q.flushes);
            q.finishing
        };
        if !batch.is_empty() {
            for r in &batch {
                if let Err(e) = writer.append(r) {
                    tracing::error!(error = %e, "cannot write log record");
                }
            }
            shared.backlog.fetch_sub(batch.len(), Ordering::Relaxed);
            batch.clear();
            dirty = true;
            last_record = Instant::now();
        }
        if !flushes.is_empty() {
            writer.flush()?;
            dirty = false;
            last_flush = Instant::now();
            for done in flushes.drain(..) {
                let _ = done.send(());
            }
        }
        if finishing {
            break;
        }
        if dirty && last_flush.elapsed() >= FLUSH_INTERVAL {
            writer.flush()?;
            dirty = false;
            last_flush = Instant::now();
        }
    }
    writer.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::reader::LogFile;
    use crate::record::{LinkEvent, LinkRecord, RecordKind};

    fn link_record(i: u64) -> LogRecord {
        LogRecord {
            at_ns: i,
            kind: RecordKind::Link(LinkRecord {
                link: i as u32,
                event: LinkEvent::Opened,
                module: None,
                detail: String::new(),
            }),
        }
    }

    #[test]
    fn every_record_is_written_in_order_whether_the_thread_polls_or_sleeps() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sink.mcap");
        let mut sink = LogSink::create(&path).unwrap();
        let mut next = 0;
        // A flood (polled, and past WAKE_AT_RECORDS), then pauses long enough for the thread
        // to fall asleep, then single records.
        for _ in 0..20 {
            sink.append_batch((next..next + 500).map(link_record).collect());
            next += 500;
        }
        for _ in 0..3 {
            std::thread::sleep(IDLE_AFTER * 2);
            sink.append(link_record(next));
            next += 1;
        }
        sink.finish().unwrap();
        let links: Vec<u64> = LogFile::open(&path)
            .unwrap()
            .records
            .into_iter()
            .filter_map(|r| match r.kind {
                RecordKind::Link(_) => Some(r.at_ns),
                _ => None,
            })
            .collect();
        assert_eq!(links, (0..next).collect::<Vec<_>>());
    }

    #[test]
    fn a_flush_returns_once_every_earlier_record_is_on_disk() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sink.mcap");
        let mut sink = LogSink::create(&path).unwrap();
        std::thread::sleep(IDLE_AFTER * 2);
        sink.append_batch((0..100).map(link_record).collect());
        sink.flush()
            .recv_timeout(Duration::from_secs(10))
            .expect("the flush is answered");
        assert_eq!(sink.backlog(), 0);
        sink.finish().unwrap();
    }

    #[test]
    fn a_sleeping_writer_still_flushes_what_it_was_given() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sink.mcap");
        let mut sink = LogSink::create(&path).unwrap();
        std::thread::sleep(IDLE_AFTER * 2);
        sink.append(link_record(1));
        // Written and flushed while the sink is still open (as a crash would find it).
        let deadline = Instant::now() + Duration::from_secs(5);
        while sink.backlog() > 0 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(sink.backlog(), 0);
        drop(sink);
    }
}
