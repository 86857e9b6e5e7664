//! `--realtime PRIORITY`: the whole process under the kernel's first-in, first-out real-time
//! scheduler.
//!
//! Set on the main thread before the async runtime starts, so every thread the process makes
//! afterwards (the runtime's workers, the log writer, a bridge's delay lines, zenoh's threads)
//! inherits it, as do the processes `tca up` starts. A thread under this policy runs as soon
//! as it is woken, ahead of every ordinary process on the machine: on a loaded computer
//! central, a bridge or a controller then keeps its timing (see BENCHMARKS.md, "Telemetry
//! bridge"). It takes the right to do so: `CAP_SYS_NICE`, or an `rtprio` limit of at least
//! the priority.

use thread_priority::{
    RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue, ThreadSchedulePolicy,
};

/// Puts the calling thread (and so every thread and process it starts afterwards) under the
/// FIFO real-time scheduler at `priority`; the error says what was wrong and what to do.
pub(crate) fn enter(priority: u8) -> Result<(), String> {
    let value = ThreadPriorityValue::try_from(priority)
        .map_err(|e| format!("--realtime {priority}: {e}; give a priority from 1 to 99"))?;
    thread_priority::set_thread_priority_and_policy(
        thread_priority::thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|e| {
        format!(
            "cannot run under the real-time scheduler at priority {priority} ({e:?}): this \
             user may not. Allow it with an rtprio limit (a line `USER - rtprio 99` in \
             /etc/security/limits.conf, then log in again) or the capability \
             (`sudo setcap cap_sys_nice+ep $(command -v tca)`), or leave --realtime out"
        )
    })?;
    tracing::info!(
        priority,
        "running under the real-time FIFO scheduler (every thread of this process)"
    );
    Ok(())
}
