//! `tca module NAME`: one built-in module as its own process.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_module::Connector;

use super::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct ModuleArgs {
    /// The built-in module to run (echo).
    name: String,
    #[command(flatten)]
    connect: ConnectArgs,
}

pub(crate) async fn run(args: ModuleArgs) -> anyhow::Result<ExitCode> {
    let endpoint = args
        .connect
        .connect
        .clone()
        .or_else(|| std::env::var("TCA_CONNECT").ok())
        .unwrap_or_else(|| args.connect.endpoint_or_default());
    let connector = Connector::zenoh(endpoint.clone());
    let module = tca::builtin::connect(&args.name, &connector)
        .await
        .with_context(|| format!("module {} cannot join central at {endpoint}", args.name))?;
    eprintln!("module {} connected to central at {endpoint}", args.name);
    tokio::select! {
        r = tokio::signal::ctrl_c() => { r.context("cannot wait for Ctrl-C")?; }
        _ = module.closed() => {
            anyhow::bail!("central closed the link to module {}", args.name);
        }
    }
    module.close().await;
    Ok(ExitCode::SUCCESS)
}
