//! `tca central`: central control, listening on local sockets and zenoh endpoints.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::Args;
use tca_central::runtime::StartOptions;
use tca_central::{CentralConfig, DEFAULT_ENDPOINT};

#[derive(Debug, Args)]
pub(crate) struct CentralArgs {
    /// Endpoint to listen on (repeatable, any mix): `local` or `local/NAME` (a Unix socket
    /// for modules on this machine, only this user may connect), or a zenoh endpoint such as
    /// tcp/0.0.0.0:7447 (modules on any machine).
    #[arg(long, value_name = "ENDPOINT", default_value = DEFAULT_ENDPOINT)]
    listen: Vec<String>,
    /// Also admit processes of this user id on the local sockets (repeatable); by default only
    /// central's own user may connect. The socket directory is private to central's user, so
    /// that user must also let the other one reach it (see TCA_LOCAL_DIR).
    #[arg(long, value_name = "UID")]
    local_allow_uid: Vec<u32>,
    /// Write the traffic log (MCAP) to this file. A log already there (say, of a central that
    /// crashed) is kept as FILE-STEM.N.mcap, never overwritten.
    #[arg(long, value_name = "FILE")]
    log: Option<PathBuf>,
    /// Keep central's task trees and queues in this journal. Started again on the same journal
    /// after a crash (kill -9, a panic, the machine's supervisor), central comes back with
    /// them: the modules rejoin by themselves, a goal a module was running is delivered to it
    /// again (marked as a redelivery) and an interrupted walk goes on to its goal. Stopping
    /// central with Ctrl-C ends its tasks and removes the journal.
    #[arg(long, value_name = "FILE")]
    journal: Option<PathBuf>,
    /// Most messages held for one module while it is down.
    #[arg(long, default_value_t = CentralConfig::default().max_waiting)]
    max_waiting: u32,
    /// Longest a message is held for a module that is down, in milliseconds.
    #[arg(long, default_value_t = CentralConfig::default().max_wait.as_millis() as u64)]
    max_wait_ms: u64,
    /// Largest frame accepted, in bytes.
    #[arg(long, default_value_t = CentralConfig::default().max_frame_bytes)]
    max_frame_bytes: usize,
    /// Registration policy (TOML): identities and secrets modules must present, what each may
    /// register and send, and optionally a zenoh users file and TLS files, with which the
    /// zenoh router confines each identity to its own keys (see policy.example.toml).
    #[arg(long, value_name = "FILE")]
    policy: Option<PathBuf>,
    /// Most frames of one module waiting to be handled by central; more are refused.
    #[arg(long, default_value_t = CentralConfig::default().max_inbox_frames)]
    max_inbox_frames: u32,
    /// Most bytes of one module's frames waiting to be handled by central.
    #[arg(long, default_value_t = CentralConfig::default().max_inbox_bytes)]
    max_inbox_bytes: u64,
    /// Most messages of one sender held in central (goals waiting for their handler, messages
    /// for a module that is down); more are refused.
    #[arg(long, default_value_t = CentralConfig::default().max_queued_messages)]
    max_queued_messages: u32,
    /// Most data bytes of one sender's messages held in central.
    #[arg(long, default_value_t = CentralConfig::default().max_queued_bytes)]
    max_queued_bytes: u64,
    /// Most frames sent to one module and not yet read by it: at half, central gives it no
    /// new work until it has read them down; past it, the module is disconnected as too slow.
    #[arg(long, default_value_t = CentralConfig::default().max_outbox_frames)]
    max_outbox_frames: u32,
    /// Most bytes of the frames sent to one module and not yet read by it (same two marks).
    #[arg(long, default_value_t = CentralConfig::default().max_outbox_bytes)]
    max_outbox_bytes: u64,
    /// Most log records waiting for the log writer; at this many central stops taking frames
    /// from modules until the writer is back under half.
    #[arg(long, default_value_t = CentralConfig::default().max_log_backlog)]
    max_log_backlog: u32,
    /// Listen on endpoints other machines can reach (tcp/0.0.0.0:7447, a LAN address) with
    /// no --policy, or with a policy that authenticates no zenoh client (no zenoh users file,
    /// no TLS). Without it central refuses to: an open central admits anyone who finds it, and
    /// a router that cannot tell clients apart lets each read and speak for the others.
    #[arg(long)]
    insecure: bool,
    /// Keep the system's simulated clock: release messages in simulated-time order (for
    /// simulations such as the walking system; a real robot's system runs on the wall clock).
    #[arg(long)]
    simulated_time: bool,
}

pub(crate) async fn run(args: CentralArgs) -> anyhow::Result<ExitCode> {
    let policy = match &args.policy {
        Some(path) => Some(std::sync::Arc::new(
            tca_central::Policy::load(path).context("cannot load the policy")?,
        )),
        None => None,
    };
    let options = StartOptions {
        config: CentralConfig {
            max_waiting: args.max_waiting,
            max_wait: Duration::from_millis(args.max_wait_ms),
            max_frame_bytes: args.max_frame_bytes,
            max_inbox_frames: args.max_inbox_frames,
            max_inbox_bytes: args.max_inbox_bytes,
            max_queued_messages: args.max_queued_messages,
            max_queued_bytes: args.max_queued_bytes,
            max_outbox_frames: args.max_outbox_frames,
            max_outbox_bytes: args.max_outbox_bytes,
            max_log_backlog: args.max_log_backlog,
            policy,
            local_peer_uids: args.local_allow_uid.clone(),
            simulated_time: args.simulated_time,
            ..CentralConfig::default()
        },
        log: args.log.clone(),
        listen: args.listen.clone(),
        insecure: args.insecure,
        journal: args.journal.clone(),
        keep_previous_log: true,
    };
    let central = tca_central::start(options)
        .await
        .context("cannot start central")?;
    if let (Some(log), Some(kept)) = (&args.log, central.kept_log()) {
        eprintln!(
            "the previous log {} is kept as {}",
            log.display(),
            kept.display()
        );
    }
    if let Some(restored) = central.restored() {
        eprintln!("{}", restored.summary);
        if restored.log_records_recovered > 0 {
            eprintln!(
                "the new log starts with {} record(s) of the crashed central's last moments, \
                 which its log lacked",
                restored.log_records_recovered
            );
        }
        for w in &restored.warnings {
            eprintln!("warning: {w}");
        }
    }
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
        "central stopped: {} frames in, {} out, {} bad, {} messages refused by the router's \
         access control",
        stats.counters.frames_in,
        stats.counters.frames_out,
        stats.counters.bad_frames,
        stats.refused_by_router
    );
    Ok(ExitCode::SUCCESS)
}
