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
}

pub(crate) async fn run(args: PingArgs) -> anyhow::Result<ExitCode> {
    if args.n == 0 {
        anyhow::bail!("-n must be at least 1");
    }
    let (report, where_) = match &args.connect.connect {
        Some(endpoint) => {
            let connector = Connector::zenoh(endpoint.clone());
            let report = tca_ping::run(&connector, args.n, args.payload)
                .await
                .with_context(|| format!("ping through central at {endpoint}"))?;
            (report, format!("central at {endpoint} (zenoh)"))
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
