//! `tca --realtime PRIORITY`: every thread of the process under the kernel's FIFO real-time
//! scheduler at that priority, or, where this user may not, a refusal that says how to allow
//! it. Priorities outside 1-99 are refused.

use std::time::Duration;

use crate::common::*;

/// The scheduling policy and real-time priority of every thread of process `pid`, from
/// `/proc` (fields 41 and 40 of each thread's `stat`).
fn thread_policies(pid: u32) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return out;
    };
    for task in tasks.flatten() {
        let Ok(stat) = std::fs::read_to_string(task.path().join("stat")) else {
            continue;
        };
        // The command name, in parentheses, may hold spaces: count fields after it.
        let Some(after) = stat.rfind(')').map(|i| &stat[i + 2..]) else {
            continue;
        };
        let fields: Vec<&str> = after.split_whitespace().collect();
        // `after` starts at field 3 (the state).
        let rtprio = fields[40 - 3].parse().unwrap();
        let policy = fields[41 - 3].parse().unwrap();
        out.push((policy, rtprio));
    }
    out
}

/// Linux's number for the FIFO policy.
const SCHED_FIFO: u32 = 1;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_thread_of_a_realtime_central_runs_under_fifo_or_the_refusal_says_how() {
    let endpoint = format!("local/realtime-{}", std::process::id());
    let (status, _, stderr) = run_tca(
        "tca --realtime 7 (is it allowed?)",
        &[
            "--realtime",
            "7",
            "registry",
            "--connect",
            "local/none-here",
        ],
        STEP,
    )
    .await;
    if !status.success() && stderr.contains("cannot run under the real-time scheduler") {
        // This user may not: the refusal must say how to allow it.
        assert!(
            stderr.contains("rtprio") && stderr.contains("cap_sys_nice"),
            "{stderr}"
        );
        return;
    }
    let mut central = spawn_tca(&["central", "--realtime", "7", "--listen", &endpoint]);
    wait_for_modules(&endpoint, &[]).await;
    let pid = central.0.id();
    let threads = thread_policies(pid);
    assert!(
        threads.len() >= 3,
        "central's threads: {threads:?} (the main thread and the runtime's workers at least)"
    );
    for (policy, rtprio) in &threads {
        assert_eq!(
            (*policy, *rtprio),
            (SCHED_FIFO, 7),
            "every thread FIFO at 7: {threads:?}"
        );
    }
    // A module under the ordinary scheduler still reaches it.
    let _echo = spawn_tca(&["module", "echo", "--connect", &endpoint]);
    wait_for_modules(&endpoint, &["echo"]).await;
    central.kill();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn priorities_outside_1_to_99_are_refused() {
    for bad in ["0", "100", "high"] {
        let (status, _, stderr) = run_tca(
            "tca --realtime BAD",
            &["--realtime", bad, "ping", "-n", "10"],
            Duration::from_secs(30),
        )
        .await;
        assert!(!status.success(), "--realtime {bad} was taken");
        assert!(
            stderr.contains("--realtime <PRIORITY>"),
            "--realtime {bad}: {stderr}"
        );
    }
}
