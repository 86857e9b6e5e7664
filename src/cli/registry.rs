//! `tca registry`: what is registered with a running central.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_module::{Connector, Module};

use super::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct RegistryArgs {
    #[command(flatten)]
    connect: ConnectArgs,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(args: RegistryArgs) -> anyhow::Result<ExitCode> {
    let endpoint = args.connect.endpoint_or_default();
    let connector = Connector::zenoh(endpoint.clone());
    let me = Module::builder(format!("registry-{}", std::process::id()))
        .connect(&connector)
        .await
        .with_context(|| format!("cannot reach central at {endpoint}"))?;
    let registry = me.registry().await?;
    me.close().await;
    if args.json {
        let entries: Vec<_> = registry
            .entries
            .iter()
            .map(|e| {
                serde_json::json!({
                    "name": e.name.as_str(), "class": e.class.as_str(),
                    "handler": e.handler.as_str(), "connected": e.connected,
                    "waiting": e.waiting, "format": e.format.to_string(),
                    "reply": e.reply.as_ref().map(|r| r.to_string()),
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({ "modules": registry.modules.iter().map(|m| m.as_str()).collect::<Vec<_>>(), "messages": entries })
        );
        return Ok(ExitCode::SUCCESS);
    }
    let modules: Vec<&str> = registry.modules.iter().map(|m| m.as_str()).collect();
    println!("connected modules: {}", modules.join(", "));
    println!(
        "{:<24} {:<9} {:<16} {:>7}  format",
        "message", "class", "handler", "waiting"
    );
    for e in &registry.entries {
        let handler = if e.connected {
            e.handler.to_string()
        } else {
            format!("{} (down)", e.handler)
        };
        let mut format = e.format.to_string();
        if let Some(r) = &e.reply {
            format.push_str(&format!(" -> {r}"));
        }
        println!(
            "{:<24} {:<9} {:<16} {:>7}  {format}",
            e.name.as_str(),
            e.class.as_str(),
            handler,
            e.waiting
        );
    }
    Ok(ExitCode::SUCCESS)
}
