//! What a load run counted, and whether anything was lost or went past a limit.

use std::fmt::Write as _;
use std::time::Duration;

use tca_central::{CentralConfig, Stats};

use super::TransportKind;

/// Log records one batch of central's driver may add past `max_log_backlog` (512 inputs of a
/// few records each).
const LOG_BATCH_ALLOWANCE: u64 = 512 * 8;

/// The messages of one class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClassCounts {
    /// Distinct messages sent and accepted by central (queries and goals: each counted once,
    /// however often refused and sent again).
    pub sent: u64,
    /// Times a handler ran.
    pub handled: u64,
    /// Queries answered with their own data, goals ended achieved, informs handled.
    pub completed: u64,
    /// Refusals for being over a limit, each followed by sending again (backpressure).
    pub refused: u64,
    /// Sends that failed otherwise (losses).
    pub failed: u64,
}

/// A load run.
#[derive(Clone, Debug)]
pub struct LoadReport {
    /// Modules connected.
    pub modules: usize,
    /// How central was reached.
    pub transport: TransportKind,
    /// Queries and goals one module had in flight at most.
    pub window: usize,
    /// How long the modules sent.
    pub duration: Duration,
    /// How long connecting the modules took.
    pub connect_time: Duration,
    /// From the first send until the last query and goal were answered.
    pub sending: Duration,
    /// From the first send until the last inform was handled too.
    pub elapsed: Duration,
    /// Queries.
    pub queries: ClassCounts,
    /// Goals.
    pub goals: ClassCounts,
    /// Informs (their `completed` is their `handled`).
    pub informs: ClassCounts,
    /// Central's final statistics, with its queues' high-water marks.
    pub central: Stats,
    /// Central's limits.
    pub config: CentralConfig,
    /// Resident memory once the modules were connected, in KiB.
    pub rss_before_kib: Option<u64>,
    /// Resident memory every second of the run, in KiB.
    pub rss_samples_kib: Vec<u64>,
    /// Peak resident memory, in KiB: of the run when `peak_reset`, else of the process.
    pub peak_rss_kib: Option<u64>,
    /// The peak was reset when the run started.
    pub peak_reset: bool,
    /// Size of the traffic log.
    pub log_bytes: u64,
}

impl LoadReport {
    /// Every way in which a message went missing; empty when none did.
    pub fn losses(&self) -> Vec<String> {
        let mut lost = Vec::new();
        for (class, c, answered) in [
            ("queries", &self.queries, "answered"),
            ("goals", &self.goals, "achieved"),
        ] {
            if c.completed != c.sent || c.handled != c.sent {
                lost.push(format!(
                    "{class}: {} sent, {} handled, {} {answered}",
                    c.sent, c.handled, c.completed
                ));
            }
        }
        if self.informs.handled != self.informs.sent {
            lost.push(format!(
                "informs: {} sent, {} handled",
                self.informs.sent, self.informs.handled
            ));
        }
        for (class, c) in self.classes() {
            if c.failed > 0 {
                lost.push(format!("{class}: {} sends failed", c.failed));
            }
        }
        if self.central.counters.too_slow > 0 {
            lost.push(format!(
                "{} modules disconnected as too slow",
                self.central.counters.too_slow
            ));
        }
        lost
    }

    /// Every queue of central whose high-water mark went past its limit (a one-frame
    /// allowance for the outbox's last frame and an empty queue's first frame).
    pub fn past_limits(&self) -> Vec<String> {
        let h = &self.central.high_water;
        let c = &self.config;
        let frame = c.max_frame_bytes as u64;
        let checks = [
            (
                "inbox frames",
                h.inbox_frames,
                u64::from(c.max_inbox_frames),
            ),
            ("inbox bytes", h.inbox_bytes, c.max_inbox_bytes + frame),
            (
                "outbox frames",
                h.outbox_frames,
                u64::from(c.max_outbox_frames) + 1,
            ),
            ("outbox bytes", h.outbox_bytes, c.max_outbox_bytes + frame),
            (
                "queued messages",
                h.queued_messages,
                u64::from(c.max_queued_messages),
            ),
            ("queued bytes", h.queued_bytes, c.max_queued_bytes + frame),
            // One batch of the driver's goes out before it looks at the writer.
            (
                "log records",
                h.log_records,
                u64::from(c.max_log_backlog) + LOG_BATCH_ALLOWANCE,
            ),
        ];
        checks
            .into_iter()
            .filter(|(_, high, limit)| high > limit)
            .map(|(what, high, limit)| format!("{what}: {high} past {limit}"))
            .collect()
    }

    /// Completed messages per second of the run.
    pub fn rate(&self, c: &ClassCounts) -> f64 {
        c.completed as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }

    fn classes(&self) -> [(&'static str, &ClassCounts); 3] {
        [
            ("query", &self.queries),
            ("goal", &self.goals),
            ("inform", &self.informs),
        ]
    }

    /// All three classes together.
    pub fn total(&self) -> ClassCounts {
        let mut t = ClassCounts::default();
        for (_, c) in self.classes() {
            t.sent += c.sent;
            t.handled += c.handled;
            t.completed += c.completed;
            t.refused += c.refused;
            t.failed += c.failed;
        }
        t
    }

    /// The run as a text table.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "load: {} modules, {}, {:.0} s of sending (window {}), modules connected in {:.2} s",
            self.modules,
            self.transport.label(),
            self.duration.as_secs_f64(),
            self.window,
            self.connect_time.as_secs_f64()
        );
        let _ = writeln!(
            s,
            "  {:<7} {:>10} {:>10} {:>10} {:>9} {:>7} {:>11}",
            "class", "sent", "handled", "completed", "refused", "failed", "per second"
        );
        let total = self.total();
        for (class, c) in self.classes().into_iter().chain([("total", &total)]) {
            let _ = writeln!(
                s,
                "  {:<7} {:>10} {:>10} {:>10} {:>9} {:>7} {:>11.0}",
                class,
                c.sent,
                c.handled,
                c.completed,
                c.refused,
                c.failed,
                self.rate(c)
            );
        }
        let k = &self.central.counters;
        let _ = writeln!(
            s,
            "  over {:.1} s until all were answered ({:.1} s for queries and goals); central: {} \
             frames in, {} out, {} over-limit refusals, {} congestions, {} too slow, {} waits \
             for the log writer",
            self.elapsed.as_secs_f64(),
            self.sending.as_secs_f64(),
            k.frames_in,
            k.frames_out,
            k.over_limit,
            k.congestions,
            k.too_slow,
            self.central.log_waits
        );
        let h = &self.central.high_water;
        let _ = writeln!(
            s,
            "  central's high water: inbox {} frames / {} B, outbox {} frames / {} B, queued by \
             one sender {} messages / {} B, log writer {} records",
            h.inbox_frames,
            h.inbox_bytes,
            h.outbox_frames,
            h.outbox_bytes,
            h.queued_messages,
            h.queued_bytes,
            h.log_records
        );
        let mib =
            |k: Option<u64>| k.map_or("?".to_owned(), |k| format!("{:.0}", k as f64 / 1024.0));
        let (lo, hi) = (
            self.rss_samples_kib.iter().min().copied(),
            self.rss_samples_kib.iter().max().copied(),
        );
        let _ = writeln!(
            s,
            "  memory: RSS {} MiB connected, {}..{} MiB while sending (sampled each second), \
             peak {} MiB ({}); traffic log {:.0} MB",
            mib(self.rss_before_kib),
            mib(lo),
            mib(hi),
            mib(self.peak_rss_kib),
            if self.peak_reset {
                "of this run"
            } else {
                "of the process"
            },
            self.log_bytes as f64 / 1e6
        );
        let series: Vec<String> = self
            .rss_samples_kib
            .iter()
            .map(|k| format!("{:.0}", *k as f64 / 1024.0))
            .collect();
        let _ = writeln!(s, "  RSS each second (MiB): {}", series.join(" "));
        let lost = self.losses();
        let past = self.past_limits();
        let _ = writeln!(
            s,
            "  loss: {}; limits: {}",
            if lost.is_empty() {
                "none".to_owned()
            } else {
                lost.join("; ")
            },
            if past.is_empty() {
                "kept".to_owned()
            } else {
                past.join("; ")
            }
        );
        s
    }
}
