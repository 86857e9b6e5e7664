//! `tca send NAME [JSON]`: send a goal, command or inform by hand, its data given as JSON and
//! encoded through the format its handler registered. A goal or command becomes a root task;
//! `tca send` waits for its end and prints it (exit status 0 achieved, 2 failed, 3 killed),
//! unless `--no-wait`.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_messages::Class;
use tca_messages::control::TaskOutcome;
use tca_module::Module;

use crate::cli::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct SendArgs {
    /// The message's name, e.g. bodyMove.
    name: String,
    /// Its data as JSON, e.g. '{"target_y_m": 2.0}' (default: null, for messages without data).
    #[arg(value_name = "JSON")]
    data: Option<String>,
    #[command(flatten)]
    connect: ConnectArgs,
    /// Do not wait for a goal's or command's end: print its message id and return (kill it
    /// later with `tca kill ID`).
    #[arg(long)]
    no_wait: bool,
    /// Print one line of JSON: name, class, id, outcome ("achieved", "failed", "killed" or
    /// "sent") and the reason of a failure.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(args: SendArgs) -> anyhow::Result<ExitCode> {
    let json = super::parse_json(&args.name, args.data.as_deref())?;
    let me = super::connect(&args.connect, "send").await?;
    let result = send(&me, &args, &json).await;
    me.close().await;
    let (class, id, outcome) = result?;
    let (word, reason, code) = match &outcome {
        None => ("sent", None, ExitCode::SUCCESS),
        Some(TaskOutcome::Achieved) => ("achieved", None, ExitCode::SUCCESS),
        Some(TaskOutcome::Failed(r)) => ("failed", Some(r.as_str()), ExitCode::from(2)),
        Some(TaskOutcome::Killed) => ("killed", None, ExitCode::from(3)),
    };
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "name": args.name, "class": class.as_str(), "id": id.to_string(),
                "outcome": word, "reason": reason,
            })
        );
    } else {
        match reason {
            Some(r) => println!("{class} {} ({id}): {word}: {r}", args.name),
            None => println!("{class} {} ({id}): {word}", args.name),
        }
    }
    Ok(code)
}

/// Sends; for a goal or command (unless `--no-wait`) waits for its end.
async fn send(
    me: &Module,
    args: &SendArgs,
    json: &serde_json::Value,
) -> anyhow::Result<(Class, tca_messages::MessageId, Option<TaskOutcome>)> {
    let name = args.name.as_str();
    let registry = me.registry().await?;
    let entry = super::find(&registry, name)?;
    match entry.class {
        Class::Goal | Class::Command | Class::Inform => {}
        Class::Query => anyhow::bail!(
            "{name} is a query: ask it with `tca call {name} JSON`, which prints the reply"
        ),
        Class::Exception => anyhow::bail!(
            "{name} is an exception: handlers raise exceptions in the context of their task; \
             `tca send` sends goals, commands and informs"
        ),
        other => anyhow::bail!("{name} is registered as a {other}, which cannot be sent"),
    }
    let data = super::encode(entry, json)?;
    let class = entry.class;
    if class == Class::Inform || args.no_wait {
        let id = me
            .send_raw(class, name, data, [])
            .with_context(|| format!("cannot send {name}"))?;
        return Ok((class, id, None));
    }
    let task = me
        .send_watched_raw(class, name, data, [])
        .with_context(|| format!("cannot send {name}"))?;
    let id = task.id();
    eprintln!(
        "sent {class} {name} as {id}; waiting for its end (Ctrl-C stops waiting, not the task)"
    );
    let outcome = tokio::select! {
        o = task.outcome() => o.with_context(|| format!("{name} ({id}) did not end"))?,
        r = tokio::signal::ctrl_c() => {
            r.context("cannot wait for Ctrl-C")?;
            anyhow::bail!("stopped waiting; {name} ({id}) goes on: `tca kill {id}` stops it");
        }
    };
    Ok((class, id, Some(outcome)))
}
