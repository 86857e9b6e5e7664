//! `tca echo NAME...`: the traffic of some message names as it happens, decoded through the
//! registered formats: each query, goal, command, inform or exception of those names that a
//! module sends, the reply, success or failure that answers it, and central's errors about
//! it. One line each (one JSON object with `--json`).

use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::Args;
use tca_messages::control::Registry;
use tca_messages::{Class, Envelope, Failure, RouteError, decode_data, is_simulated_stamp};

use crate::cli::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct EchoArgs {
    /// The message names to echo, e.g. bodyMove legMove.
    #[arg(required_unless_present = "all")]
    names: Vec<String>,
    /// Echo every message name.
    #[arg(long, conflicts_with = "names")]
    all: bool,
    #[command(flatten)]
    connect: ConnectArgs,
    /// Stop after this many messages.
    #[arg(long, value_name = "N")]
    count: Option<u64>,
    /// Stop after this many seconds (an error if --count messages were not seen by then).
    #[arg(long, value_name = "SECONDS")]
    timeout: Option<f64>,
    /// One JSON object per message: time_s, simulated, class, name, sender, id, re, node,
    /// data.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(args: EchoArgs) -> anyhow::Result<ExitCode> {
    let limit = match args.timeout {
        Some(s) => Some(
            Duration::try_from_secs_f64(s)
                .ok()
                .context("--timeout must be a number of seconds")?,
        ),
        None => None,
    };
    let me = super::connect(&args.connect, "echo").await?;
    let result = echo(&me, &args, limit).await;
    me.close().await;
    result
}

async fn echo(
    me: &tca_module::Module,
    args: &EchoArgs,
    limit: Option<Duration>,
) -> anyhow::Result<ExitCode> {
    let mut registry = me.registry().await?;
    for name in &args.names {
        super::find(&registry, name)?;
    }
    let names: Vec<&str> = args.names.iter().map(String::as_str).collect();
    let mut tapping = me.tap(&names).await.context("central refused the tap")?;
    let what = if args.all {
        "every message".to_owned()
    } else {
        args.names.join(", ")
    };
    eprintln!("echoing {what} (Ctrl-C to stop)");
    let deadline = limit.map(|l| tokio::time::Instant::now() + l);
    let mut seen = 0u64;
    while args.count.is_none_or(|n| seen < n) {
        let next = async {
            match deadline {
                Some(d) => tokio::time::timeout_at(d, tapping.next()).await.ok(),
                None => Some(tapping.next().await),
            }
        };
        let envelope = tokio::select! {
            e = next => match e {
                None => break,
                Some(None) => anyhow::bail!("central went away or closed the link"),
                Some(Some(e)) => e,
            },
            r = tokio::signal::ctrl_c() => {
                r.context("cannot wait for Ctrl-C")?;
                break;
            }
        };
        if !registry.entries.iter().any(|e| e.name == envelope.name) {
            // A name registered since the echo began.
            registry = me.registry().await?;
        }
        let line = describe(&registry, &envelope);
        if args.json {
            println!("{line}");
        } else {
            println!("{}", text(&line));
        }
        seen += 1;
    }
    match args.count {
        Some(n) if seen < n => anyhow::bail!("saw {seen} of {n} messages of {what} in time"),
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// One tapped message as JSON, its data decoded through the registered formats.
fn describe(registry: &Registry, e: &Envelope) -> serde_json::Value {
    let entry = registry.entries.iter().find(|r| r.name == e.name);
    let data = match e.class {
        Class::Reply => match entry.and_then(|r| r.reply.as_ref()) {
            Some(f) => super::decode(f, &e.data),
            None => serde_json::Value::Null,
        },
        Class::Success => serde_json::Value::Null,
        Class::Failure => match decode_data::<Failure>(&e.data) {
            Ok(f) => serde_json::json!({ "reason": f.reason }),
            Err(err) => serde_json::json!({ "undecodable": err.to_string() }),
        },
        Class::Error => match decode_data::<RouteError>(&e.data) {
            Ok(r) => serde_json::json!({ "error": r.to_string() }),
            Err(err) => serde_json::json!({ "undecodable": err.to_string() }),
        },
        _ => match entry {
            Some(r) => super::decode(&r.format, &e.data),
            None => serde_json::json!({ "unregistered": e.data.len() }),
        },
    };
    serde_json::json!({
        "time_s": e.timestamp_ns as f64 / 1e9,
        "simulated": is_simulated_stamp(e.timestamp_ns),
        "class": e.class.as_str(),
        "name": e.name.as_str(),
        "sender": e.sender.as_str(),
        "id": e.id.to_string(),
        "re": e.correlation.map(|c| c.to_string()),
        "node": e.node.map(|n| n.to_string()),
        "data": data,
    })
}

/// The line of text for one tapped message.
fn text(line: &serde_json::Value) -> String {
    let t = line["time_s"].as_f64().unwrap_or_default();
    let time = if line["simulated"].as_bool().unwrap_or_default() {
        format!("{t:>10.3}s")
    } else {
        let day = t.rem_euclid(86_400.0);
        format!(
            "{:02}:{:02}:{:06.3}",
            (day / 3600.0) as u32,
            (day % 3600.0 / 60.0) as u32,
            day % 60.0
        )
    };
    let s = |k: &str| line[k].as_str().unwrap_or_default().to_owned();
    let re = line["re"]
        .as_str()
        .map(|r| format!(" re {r}"))
        .unwrap_or_default();
    format!(
        "{time}  {:<9} {:<14} {}  {}{re}  {}",
        s("class"),
        s("sender"),
        s("name"),
        s("id"),
        line["data"]
    )
}
