//! `tca list [NAME]`: the modules of a running system, the messages each handles, their data
//! formats and a JSON template of each; with NAME, one message in full.

use std::collections::BTreeMap;
use std::process::ExitCode;

use clap::Args;
use tca_messages::control::RegistryEntry;

use crate::cli::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct ListArgs {
    /// One message to show in full (class, handler, format, JSON template).
    name: Option<String>,
    #[command(flatten)]
    connect: ConnectArgs,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

fn entry_json(e: &RegistryEntry) -> serde_json::Value {
    serde_json::json!({
        "name": e.name.as_str(),
        "class": e.class.as_str(),
        "handler": e.handler.as_str(),
        "connected": e.connected,
        "waiting": e.waiting,
        "format": e.format.to_string(),
        "template": e.format.json_template(),
        "reply": e.reply.as_ref().map(|r| r.to_string()),
        "reply_template": e.reply.as_ref().map(|r| r.json_template()),
    })
}

pub(crate) async fn run(args: ListArgs) -> anyhow::Result<ExitCode> {
    let me = super::connect(&args.connect, "list").await?;
    let registry = me.registry().await;
    me.close().await;
    let registry = registry?;
    if let Some(name) = &args.name {
        let e = super::find(&registry, name)?;
        if args.json {
            println!("{}", entry_json(e));
            return Ok(ExitCode::SUCCESS);
        }
        let state = if e.connected { "connected" } else { "down" };
        println!("{}: {} handled by {} ({state})", e.name, e.class, e.handler);
        println!("  data:      {}", e.format);
        println!("  template:  {}", e.format.json_template());
        if let Some(r) = &e.reply {
            println!("  reply:     {r}");
        }
        if e.waiting > 0 {
            println!("  waiting:   {} messages held for {}", e.waiting, e.handler);
        }
        return Ok(ExitCode::SUCCESS);
    }
    // Every module, connected or the handler of something; its messages by name.
    let mut modules: BTreeMap<String, (bool, Vec<&RegistryEntry>)> = BTreeMap::new();
    for m in registry.modules.iter().filter(|m| *m != me.name()) {
        modules.entry(m.to_string()).or_default().0 = true;
    }
    for e in &registry.entries {
        let slot = modules.entry(e.handler.to_string()).or_default();
        slot.0 |= e.connected;
        slot.1.push(e);
    }
    if args.json {
        let list: Vec<_> = modules
            .iter()
            .map(|(name, (connected, entries))| {
                serde_json::json!({
                    "name": name,
                    "connected": connected,
                    "messages": entries.iter().map(|e| entry_json(e)).collect::<Vec<_>>(),
                })
            })
            .collect();
        println!("{}", serde_json::json!({ "modules": list }));
        return Ok(ExitCode::SUCCESS);
    }
    for (name, (connected, entries)) in &modules {
        let state = if *connected { "" } else { " (down)" };
        if entries.is_empty() {
            println!("{name}{state}: registers nothing");
            continue;
        }
        println!("{name}{state}:");
        for e in entries {
            let mut format = e.format.json_template().to_string();
            if let Some(r) = &e.reply {
                format.push_str(&format!(" -> {}", r.json_template()));
            }
            println!("  {:<22} {:<9} {format}", e.name.as_str(), e.class.as_str());
        }
    }
    Ok(ExitCode::SUCCESS)
}
