//! `tca ping`: query round-trip times through central.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_central::runtime::StartOptions;
use tca_module::Connector;

use super::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct PingArgs {
    #[command(flatten)]
    connect: ConnectArgs,
    /// Round trips to time.
    #[arg(short = 'n', default_value_t = 1000)]
    n: usize,
    /// Payload bytes per ping.
    #[arg(long, default_value_t = 64)]
    payload: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    /// Ping the echo module of this name, already connected to central (e.g. `tca module echo
    /// --connect E` in another process), instead of starting an echo in this process. Needs
    /// --connect.
    #[arg(long, value_name = "MODULE", requires = "connect")]
    target: Option<String>,
}

pub(crate) async fn run(args: PingArgs) -> anyhow::Result<ExitCode> {
    if args.n == 0 {
        anyhow::bail!("-n must be at least 1");
    }
    let (report, where_) = match &args.connect.connect {
        Some(endpoint) => {
            let connector = Connector::endpoint(endpoint.clone());
            let report = match &args.target {
                Some(target) => {
                    tca_ping::run_target(&connector, target, args.n, args.payload).await
                }
                None => tca_ping::run(&connector, args.n, args.payload).await,
            }
            .with_context(|| format!("ping through central at {endpoint}"))?;
            let link = if tca_link::LocalEndpoint::is_local(endpoint) {
                "local socket"
            } else {
                "zenoh"
            };
            let echo = match &args.target {
                Some(t) => format!(", echo module {t} in another process"),
                None => String::new(),
            };
            (report, format!("central at {endpoint} ({link}{echo})"))
        }
        None => {
            let central = tca_central::start(StartOptions::default()).await?;
            let connector = Connector::from(central.in_process());
            let report = tca_ping::run(&connector, args.n, args.payload).await?;
            central.shutdown().await?;
            (report, "in-process central".to_owned())
        }
    };
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!(
            "{} query round trips through {where_}: min {:.1} µs, p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs",
            report.n, report.min_us, report.p50_us, report.p99_us, report.max_us
        );
    }
    Ok(ExitCode::SUCCESS)
}
