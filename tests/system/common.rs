//! Shared helpers of the whole-system tests: the test kit (`tca-testkit`), with the `tca`
//! binary of this package.

#![allow(dead_code, unreachable_pub, unused_imports)]

use std::process::ExitStatus;
use std::time::Duration;

pub use tca_testkit::{
    ALL, BOTH, STEP, TestCentral, TransportKind, free_endpoint, free_port, remove_local_socket,
    retry, unique_local_endpoint, wait_for_file, walk_report, within, within_for,
};

/// The `tca` binary under test.
pub fn tca() -> tca_testkit::Tca {
    tca_testkit::Tca::at(env!("CARGO_BIN_EXE_tca"))
}

/// Runs `tca ARGS` to its end with no input, waiting as long as it takes.
pub fn tca_output(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_tca"))
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("tca runs")
}

/// Body moves central has logged so far in the traffic log `log` (0 while it cannot be read).
pub fn body_moves(log: &std::path::Path) -> usize {
    tca_logs::LogFile::open(log)
        .map(|l| {
            tca_logs::stats(&l, tca_logs::TimeBase::Envelope)
                .by_name
                .get("bodyMove")
                .copied()
                .unwrap_or(0)
        })
        .unwrap_or(0)
}

/// A `tca` child process, killed when dropped.
pub type ChildProcess = tca_testkit::ChildProcess;

/// Starts `tca ARGS` in the background.
pub fn spawn_tca(args: &[&str]) -> ChildProcess {
    tca().spawn(args)
}

/// Runs `tca ARGS` to its end: its exit status, stdout and stderr.
pub async fn run_tca(what: &str, args: &[&str], limit: Duration) -> (ExitStatus, String, String) {
    let out = tca().run(what, args, limit).await;
    (out.status, out.stdout, out.stderr)
}

/// Waits until every module in `names` is registered with the central at `endpoint`.
pub async fn wait_for_modules(endpoint: &str, names: &[&str]) {
    tca().wait_for_modules(endpoint, names).await
}

/// Starts the shipped multi-legged system (`tca up walk-legged.toml`: central and the four
/// legged modules, each its own process) on a free endpoint, logging into `dir`, and waits
/// until every module has joined: the `tca up` process and the endpoint.
pub async fn start_legged_system(dir: &std::path::Path) -> (ChildProcess, String) {
    let endpoint = free_endpoint();
    let launch = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/walk-legged.toml"))
        .expect("the shipped launch file")
        .replace("tcp/127.0.0.1:7447", &endpoint)
        .replace("out/up-legged", dir.to_str().expect("a UTF-8 path"));
    let file = dir.join("walk-legged.toml");
    std::fs::write(&file, launch).expect("the launch file written");
    let up = spawn_tca(&["up", file.to_str().expect("a UTF-8 path")]);
    wait_for_modules(&endpoint, &["controller", "ism", "ltm", "gait"]).await;
    (up, endpoint)
}
