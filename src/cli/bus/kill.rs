//! `tca kill NODE|MESSAGE-ID`: kill a task and its subtree, named by its task-tree node (as
//! `tca tree` shows it, `n5` or `5`) or by the id of the message that created it (as
//! `tca send` and `tca echo` print it, `m3.7`).

use std::process::ExitCode;

use clap::Args;
use tca_messages::{MessageId, NodeId};

use crate::cli::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct KillArgs {
    /// The task: a node (n5 or 5) or a message id (m3.7).
    target: String,
    #[command(flatten)]
    connect: ConnectArgs,
}

/// What to kill.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Node(NodeId),
    Task(MessageId),
}

fn parse(text: &str) -> anyhow::Result<Target> {
    let bad = || {
        anyhow::anyhow!(
            "{text:?} names no task: give a task-tree node (n5 or 5, as `tca tree` shows) or \
             the id of the message that created it (m3.7, as `tca send` and `tca echo` print)"
        )
    };
    let t = text.trim();
    if let Some(id) = t.strip_prefix('m') {
        let (link, seq) = id.split_once('.').ok_or_else(bad)?;
        let link: u32 = link.parse().map_err(|_| bad())?;
        let seq: u32 = seq.parse().map_err(|_| bad())?;
        return Ok(Target::Task(MessageId::new(link, seq)));
    }
    let n = t.strip_prefix('n').unwrap_or(t);
    n.parse()
        .map(|n| Target::Node(NodeId(n)))
        .map_err(|_| bad())
}

pub(crate) async fn run(args: KillArgs) -> anyhow::Result<ExitCode> {
    let target = parse(&args.target)?;
    let me = super::connect(&args.connect, "kill").await?;
    let result = match target {
        Target::Node(n) => me.kill(n).await,
        Target::Task(id) => me.kill_task(id).await,
    };
    me.close().await;
    result.map_err(|e| anyhow::anyhow!("cannot kill {}: {e}", args.target))?;
    match target {
        Target::Node(n) => println!("killed node {n} and its subtree"),
        Target::Task(id) => println!("killed the task of {id} and its subtree"),
    }
    Ok(ExitCode::SUCCESS)
}
