//! `tca stop`: the emergency stop of the report's User Interface. Central kills every task
//! tree at once (the running handlers are cancelled and nothing waiting is started), then the
//! halt is sent: every registered command or inform named `halt` or `*.halt` (or the ones
//! given with `--halt`), with no data.

use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use tca_messages::Class;
use tca_messages::control::{RegistryEntry, TaskOutcome};

use crate::cli::ConnectArgs;

/// How long a halt sent as a command may take to end.
const HALT_TIMEOUT: Duration = Duration::from_secs(5);

#[derive(Debug, Args)]
pub(crate) struct StopArgs {
    #[command(flatten)]
    connect: ConnectArgs,
    /// The halt message to send after the trees are killed (repeatable); default: every
    /// registered command or inform named `halt` or ending in `.halt`.
    #[arg(long, value_name = "NAME")]
    halt: Vec<String>,
}

/// Whether a registered message is a halt by its name.
fn is_halt(e: &RegistryEntry) -> bool {
    let name = e.name.as_str();
    matches!(e.class, Class::Command | Class::Inform) && (name == "halt" || name.ends_with(".halt"))
}

pub(crate) async fn run(args: StopArgs) -> anyhow::Result<ExitCode> {
    let me = super::connect(&args.connect, "stop").await?;
    let result = stop(&me, &args).await;
    me.close().await;
    result
}

async fn stop(me: &tca_module::Module, args: &StopArgs) -> anyhow::Result<ExitCode> {
    let killed = me.kill_all().await?;
    match killed {
        0 => println!("no task trees were live"),
        1 => println!("killed 1 task tree"),
        n => println!("killed {n} task trees"),
    }
    let registry = me.registry().await?;
    let halts: Vec<&RegistryEntry> = if args.halt.is_empty() {
        registry.entries.iter().filter(|e| is_halt(e)).collect()
    } else {
        args.halt
            .iter()
            .map(|n| super::find(&registry, n))
            .collect::<anyhow::Result<_>>()?
    };
    if halts.is_empty() {
        println!(
            "no halt message is registered: nothing more to send (a module that registers a \
             command or inform named `halt` gets it from `tca stop`)"
        );
        return Ok(ExitCode::SUCCESS);
    }
    let mut code = ExitCode::SUCCESS;
    for e in halts {
        let name = e.name.as_str();
        let data = super::encode(e, &serde_json::Value::Null)?;
        match e.class {
            Class::Inform => {
                me.send_raw(Class::Inform, name, data, [])?;
                println!("sent inform {name} to {}", e.handler);
            }
            Class::Command | Class::Goal => {
                let task = me.send_watched_raw(e.class, name, data, [])?;
                match tokio::time::timeout(HALT_TIMEOUT, task.outcome()).await {
                    Ok(Ok(TaskOutcome::Achieved)) => {
                        println!("{} {name} to {}: achieved", e.class, e.handler)
                    }
                    Ok(Ok(other)) => {
                        println!("{} {name} to {}: {other:?}", e.class, e.handler);
                        code = ExitCode::from(2);
                    }
                    Ok(Err(err)) => {
                        println!("{} {name} to {}: {err}", e.class, e.handler);
                        code = ExitCode::from(2);
                    }
                    Err(_) => {
                        println!(
                            "{} {name} to {}: not ended after {} s",
                            e.class,
                            e.handler,
                            HALT_TIMEOUT.as_secs()
                        );
                        code = ExitCode::from(2);
                    }
                }
            }
            other => anyhow::bail!("{name} is a {other}; a halt is a command or an inform"),
        }
    }
    Ok(code)
}
