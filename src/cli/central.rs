//! `tca central`: central control over zenoh.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::Args;
use tca_central::runtime::StartOptions;
use tca_central::{CentralConfig, zenoh_transport::DEFAULT_ENDPOINT};

#[derive(Debug, Args)]
pub(crate) struct CentralArgs {
    /// zenoh endpoint to listen on (repeatable).
    #[arg(long, value_name = "ENDPOINT", default_value = DEFAULT_ENDPOINT)]
    listen: Vec<String>,
    /// Write the traffic log (MCAP) to this file.
    #[arg(long, value_name = "FILE")]
    log: Option<PathBuf>,
    /// Most messages held for one module while it is down.
    #[arg(long, default_value_t = CentralConfig::default().max_waiting)]
    max_waiting: u32,
    /// Longest a message is held for a module that is down, in milliseconds.
    #[arg(long, default_value_t = CentralConfig::default().max_wait.as_millis() as u64)]
    max_wait_ms: u64,
    /// Largest frame accepted, in bytes.
    #[arg(long, default_value_t = CentralConfig::default().max_frame_bytes)]
    max_frame_bytes: usize,
}

pub(crate) async fn run(args: CentralArgs) -> anyhow::Result<ExitCode> {
    let options = StartOptions {
        config: CentralConfig {
            max_waiting: args.max_waiting,
            max_wait: Duration::from_millis(args.max_wait_ms),
            max_frame_bytes: args.max_frame_bytes,
            ..CentralConfig::default()
        },
        log: args.log.clone(),
        listen: args.listen.clone(),
    };
    let central = tca_central::start(options)
        .await
        .context("cannot start central")?;
    eprintln!(
        "central listening on {}{}; Ctrl-C stops it",
        central.listening().join(", "),
        args.log
            .as_ref()
            .map(|l| format!(", logging to {}", l.display()))
            .unwrap_or_default()
    );
    tokio::signal::ctrl_c()
        .await
        .context("cannot wait for Ctrl-C")?;
    let stats = central.shutdown().await?;
    eprintln!(
        "central stopped: {} frames in, {} out, {} bad",
        stats.counters.frames_in, stats.counters.frames_out, stats.counters.bad_frames
    );
    Ok(ExitCode::SUCCESS)
}
