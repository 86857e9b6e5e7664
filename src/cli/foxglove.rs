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
    let live = Live::start(me, &args.host, args.port).await?;
    eprintln!(
        "serving the Foxglove WebSocket protocol on ws://{}:{} (in Foxglove: Open connection \
         → Foxglove WebSocket); Ctrl-C to stop",
        args.host,
        live.view.port()
    );
    live.serve(deadline, true).await
}

/// A live view tapping central's traffic.
struct Live {
    me: tca_module::Module,
    view: tca_foxglove::LiveView,
    registry: Registry,
    tapping: tca_module::module::Tapping,
}

impl Live {
    /// Serves on `host:port` the traffic `me` taps (every message name).
    async fn start(me: tca_module::Module, host: &str, port: u16) -> anyhow::Result<Self> {
        let mut view = tca_foxglove::LiveView::start(host, port).await?;
        let registry = me.registry().await?;
        view.set_formats(formats(&registry));
        let tapping = me.tap(&[]).await.context("central refused the tap")?;
        Ok(Live {
            me,
            view,
            registry,
            tapping,
        })
    }

    /// Publishes every tapped message until `deadline`, Ctrl-C (if `on_ctrl_c`) or central
    /// going away.
    async fn serve(
        mut self,
        deadline: Option<tokio::time::Instant>,
        on_ctrl_c: bool,
    ) -> anyhow::Result<ExitCode> {
        let result = loop {
            let next = async {
                match deadline {
                    Some(d) => tokio::time::timeout_at(d, self.tapping.next()).await.ok(),
                    None => Some(self.tapping.next().await),
                }
            };
            let ctrl_c = async {
                if on_ctrl_c {
                    tokio::signal::ctrl_c().await
                } else {
                    std::future::pending().await
                }
            };
            let envelope = tokio::select! {
                e = next => match e {
                    None => break Ok(ExitCode::SUCCESS),
                    Some(None) => break Err(anyhow::anyhow!("central went away or closed the link")),
                    Some(Some(e)) => e,
                },
                r = ctrl_c => {
                    break r.context("cannot wait for Ctrl-C").map(|_| ExitCode::SUCCESS);
                }
            };
            if !self
                .registry
                .entries
                .iter()
                .any(|e| e.name == envelope.name)
            {
                // A name registered since the view began.
                self.registry = self.me.registry().await?;
                self.view.set_formats(formats(&self.registry));
            }
            if let Err(e) = self.view.publish(&envelope, now_ns()) {
                tracing::warn!(error = %e, "cannot publish to Foxglove");
            }
        };
        self.view.stop().await;
        self.me.close().await;
        result
    }
}

/// `[HOST:]PORT` of `--foxglove` (loopback when no host is given).
fn host_port(text: &str) -> anyhow::Result<(String, u16)> {
    let (host, port) = match text.rsplit_once(':') {
        Some((h, p)) => (h.to_owned(), p),
        None => ("127.0.0.1".to_owned(), text),
    };
    let port = port.parse::<u16>().map_err(|_| {
        anyhow::anyhow!(
            "--foxglove {text:?} is not [HOST:]PORT; give e.g. 8765 or 0.0.0.0:8765 (0: any free port)"
        )
    })?;
    Ok((host, port))
}

/// A live view to attach to a run's in-process central (`--foxglove [HOST:]PORT` of
/// `tca walk` and `tca navigate`): it joins central before the run's modules, so it sees
/// everything, and serves until central shuts down at the end of the run.
pub(crate) fn live_attachment(text: &str) -> anyhow::Result<tca_module::Attachment> {
    let (host, port) = host_port(text)?;
    Ok(tca_module::Attachment::new(
        "the Foxglove live view",
        move |connector: tca_module::Connector| {
            let host = host.clone();
            async move {
                let me = tca_module::Module::builder(format!("foxglove-{}", std::process::id()))
                    .connect(&connector)
                    .await
                    .map_err(|e| format!("cannot join central: {e}"))?;
                let live = Live::start(me, &host, port)
                    .await
                    .map_err(|e| format!("{e:#}"))?;
                eprintln!(
                    "serving the Foxglove WebSocket protocol on ws://{host}:{} for this run (in \
                     Foxglove: Open connection → Foxglove WebSocket)",
                    live.view.port()
                );
                tokio::spawn(async move {
                    if let Err(e) = live.serve(None, false).await {
                        tracing::debug!(error = %e, "the live view ended");
                    }
                });
                Ok(())
            }
        },
    ))
}
