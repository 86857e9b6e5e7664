//! `tca foxglove`: a live view of a running system in Foxglove. Joins central, taps every
//! message name and serves the Foxglove WebSocket protocol (through Foxglove's SDK) with the
//! traffic channels and the walking systems' well-known channels (docs/foxglove.md).

use std::process::ExitCode;
use std::time::{SystemTime, UNIX_EPOCH};

use anyhow::Context as _;
use clap::Args;
use tca_foxglove::traffic::{FormatTable, Formats};
use tca_messages::control::Registry;

use crate::cli::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct FoxgloveArgs {
    #[command(flatten)]
    connect: ConnectArgs,
    /// Address to serve on (loopback by default; 0.0.0.0 serves every interface).
    #[arg(long, default_value = "127.0.0.1")]
    host: String,
    /// Port to serve on (Foxglove's default is 8765; 0: any free port, printed).
    #[arg(long, default_value_t = 8765)]
    port: u16,
    /// Stop after this many seconds (default: at Ctrl-C or when central goes away).
    #[arg(long, value_name = "SECONDS")]
    timeout: Option<f64>,
}

fn formats(registry: &Registry) -> FormatTable {
    registry
        .entries
        .iter()
        .map(|e| {
            (
                e.name.clone(),
                Formats {
                    format: e.format.clone(),
                    reply: e.reply.clone(),
                },
            )
        })
        .collect()
}

fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or_default()
}

pub(crate) async fn run(args: FoxgloveArgs) -> anyhow::Result<ExitCode> {
    let deadline = match args.timeout {
        Some(s) => Some(
            tokio::time::Instant::now()
                + std::time::Duration::try_from_secs_f64(s)
                    .ok()
                    .context("--timeout must be a number of seconds")?,
        ),
        None => None,
    };
    let me = super::bus::connect(&args.connect, "foxglove").await?;
    let mut view = tca_foxglove::LiveView::start(&args.host, args.port).await?;
    let mut registry = me.registry().await?;
    view.set_formats(formats(&registry));
    let mut tapping = me.tap(&[]).await.context("central refused the tap")?;
    eprintln!(
        "serving the Foxglove WebSocket protocol on ws://{}:{} (in Foxglove: Open connection \
         → Foxglove WebSocket); Ctrl-C to stop",
        args.host,
        view.port()
    );
    let result = loop {
        let next = async {
            match deadline {
                Some(d) => tokio::time::timeout_at(d, tapping.next()).await.ok(),
                None => Some(tapping.next().await),
            }
        };
        let envelope = tokio::select! {
            e = next => match e {
                None => break Ok(ExitCode::SUCCESS),
                Some(None) => break Err(anyhow::anyhow!("central went away or closed the link")),
                Some(Some(e)) => e,
            },
            r = tokio::signal::ctrl_c() => {
                break r.context("cannot wait for Ctrl-C").map(|_| ExitCode::SUCCESS);
            }
        };
        if !registry.entries.iter().any(|e| e.name == envelope.name) {
            // A name registered since the view began.
            registry = me.registry().await?;
            view.set_formats(formats(&registry));
        }
        if let Err(e) = view.publish(&envelope, now_ns()) {
            tracing::warn!(error = %e, "cannot publish to Foxglove");
        }
    };
    view.stop().await;
    me.close().await;
    result
}
