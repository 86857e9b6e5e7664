//! Load benchmark: 100 modules exchange queries, goals and informs with randomly chosen other
//! modules through one central, its traffic log on, for 60 s, in-process, then over zenoh
//! loopback, then over the local link (a Unix socket). Prints, for each run, what was sent,
//! handled and answered per class (and fails if anything was lost), the messages per second,
//! central's queue high-water marks against their limits, and the process's resident memory
//! while sending and at its peak.
//!
//! Run: `cargo bench --bench load` (figures in BENCHMARKS.md). Settings by environment:
//! `LOAD_SECONDS` (60), `LOAD_MODULES` (100), `LOAD_WINDOW` (queries and goals in flight per
//! module, 16), `LOAD_TRANSPORTS` (`inproc,zenoh,local`), `LOAD_MAX_QUEUED` (central's
//! `max_queued_messages`, its default unless set).

use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use tca_central::CentralConfig;
use tca_load::{LoadOptions, TransportKind};

/// The allocator the `tca` command uses, so that what is measured here is what it runs.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn setting<T: std::str::FromStr>(name: &str, default: T) -> anyhow::Result<T> {
    match std::env::var(name) {
        Ok(v) => v
            .parse()
            .map_err(|_| anyhow::anyhow!("{name}={v:?} is not a valid value")),
        Err(_) => Ok(default),
    }
}

fn main() -> anyhow::Result<ExitCode> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let defaults = CentralConfig::default();
    let config = CentralConfig {
        max_queued_messages: setting("LOAD_MAX_QUEUED", defaults.max_queued_messages)?,
        ..defaults
    };
    let base = LoadOptions {
        modules: setting("LOAD_MODULES", 100)?,
        duration: Duration::from_secs_f64(setting("LOAD_SECONDS", 60.0)?),
        window: setting("LOAD_WINDOW", 16)?,
        config,
        ..LoadOptions::default()
    };
    let transports = setting("LOAD_TRANSPORTS", "inproc,zenoh,local".to_owned())?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("no tokio runtime")?;
    let mut ok = true;
    for word in transports.split(',') {
        let transport = match word.trim() {
            "inproc" => TransportKind::InProcess,
            "zenoh" => TransportKind::Zenoh,
            "local" => TransportKind::Local,
            other => {
                anyhow::bail!("LOAD_TRANSPORTS: unknown transport {other:?} (inproc, zenoh, local)")
            }
        };
        let options = LoadOptions {
            transport,
            ..base.clone()
        };
        let dir = tempfile::tempdir().context("no temporary directory for the log")?;
        let report = runtime.block_on(tca_load::run(&options, dir.path()))?;
        print!("{}", report.table());
        ok &= report.losses().is_empty() && report.past_limits().is_empty();
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
