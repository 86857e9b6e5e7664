//! `tca tree`: the live task trees of a running central.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_module::{Connector, Module};

use super::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct TreeArgs {
    #[command(flatten)]
    connect: ConnectArgs,
}

pub(crate) async fn run(args: TreeArgs) -> anyhow::Result<ExitCode> {
    let endpoint = args.connect.endpoint_or_default();
    let connector = Connector::zenoh(endpoint.clone());
    let me = Module::builder(format!("tree-{}", std::process::id()))
        .connect(&connector)
        .await
        .with_context(|| format!("cannot reach central at {endpoint}"))?;
    let view = me.tree().await?;
    me.close().await;
    if view.text.trim().is_empty() {
        println!("(no live task nodes)");
    } else {
        print!("{}", view.text);
        if !view.text.ends_with('\n') {
            println!();
        }
    }
    Ok(ExitCode::SUCCESS)
}
