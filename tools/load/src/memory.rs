//! The process's memory, from `/proc/self/status` (Linux; `None` elsewhere).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
use std::time::Duration;

fn status_kib(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Resident memory now (`VmRSS`), in KiB.
pub fn rss_kib() -> Option<u64> {
    status_kib("VmRSS:")
}

/// Peak resident memory (`VmHWM`), in KiB: since the process started, or since the last
/// successful [`reset_peak_rss`].
pub fn peak_rss_kib() -> Option<u64> {
    status_kib("VmHWM:")
}

/// Resets the peak resident memory to the current one (writes 5 to `/proc/self/clear_refs`),
/// so that a run's peak is its own. False where the kernel does not allow it.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Samples the resident memory every `period` while `on` holds; the samples in KiB.
pub(super) async fn sample_rss(on: Arc<AtomicBool>, period: Duration) -> Vec<u64> {
    let mut samples = Vec::new();
    let mut ticks = tokio::time::interval(period);
    while on.load(Relaxed) {
        ticks.tick().await;
        samples.extend(rss_kib());
    }
    samples
}
