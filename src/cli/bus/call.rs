//! `tca call NAME [JSON]`: ask a query by hand; its reply, decoded through the registered
//! reply format, is printed as one line of JSON.

use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::Args;
use tca_messages::Class;

use crate::cli::ConnectArgs;

#[derive(Debug, Args)]
pub(crate) struct CallArgs {
    /// The query's name, e.g. bodyPosition.
    name: String,
    /// Its data as JSON, e.g. '{}' (default: null, for queries without data).
    #[arg(value_name = "JSON")]
    data: Option<String>,
    #[command(flatten)]
    connect: ConnectArgs,
    /// Seconds to wait for the reply.
    #[arg(long, default_value_t = 30.0)]
    timeout: f64,
}

pub(crate) async fn run(args: CallArgs) -> anyhow::Result<ExitCode> {
    let json = super::parse_json(&args.name, args.data.as_deref())?;
    let timeout = Duration::try_from_secs_f64(args.timeout)
        .ok()
        .filter(|t| !t.is_zero())
        .context("--timeout must be a positive number of seconds")?;
    let me = super::connect(&args.connect, "call").await?;
    let result = call(&me, &args.name, &json, timeout).await;
    me.close().await;
    println!("{}", result?);
    Ok(ExitCode::SUCCESS)
}

async fn call(
    me: &tca_module::Module,
    name: &str,
    json: &serde_json::Value,
    timeout: Duration,
) -> anyhow::Result<serde_json::Value> {
    let registry = me.registry().await?;
    let entry = super::find(&registry, name)?;
    if entry.class != Class::Query {
        anyhow::bail!(
            "{name} is a {}, not a query: send it with `tca send {name} JSON`",
            entry.class
        );
    }
    let data = super::encode(entry, json)?;
    let reply = me
        .query_raw(name, data, Some(timeout))
        .await
        .with_context(|| format!("query {name} was not answered"))?;
    Ok(match &entry.reply {
        Some(format) => super::decode(format, &reply),
        None => serde_json::Value::Null,
    })
}
