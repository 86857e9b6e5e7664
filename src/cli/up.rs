//! `tca up FILE`: central and a set of modules as processes, stopped together on Ctrl-C.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca::launch::Launch;
use tca_central::runtime::StartOptions;
use tokio::process::{Child, Command};

#[derive(Debug, Args)]
pub(crate) struct UpArgs {
    /// The launch file.
    file: PathBuf,
}

pub(crate) async fn run(args: UpArgs) -> anyhow::Result<ExitCode> {
    let launch = Launch::load(&args.file)?;
    if let Some(log) = &launch.central.log
        && let Some(kept) = tca_logs::set_aside(log).context("cannot keep the previous log")?
    {
        eprintln!(
            "the previous log {} is kept as {}",
            log.display(),
            kept.display()
        );
    }
    let central = tca_central::start(StartOptions {
        log: launch.central.log.clone(),
        listen: launch.central.listen.clone(),
        ..StartOptions::default()
    })
    .await
    .context("cannot start central")?;
    let endpoint = launch.central.listen[0].clone();
    eprintln!("central listening on {}", launch.central.listen.join(", "));
    let exe = std::env::current_exe().context("cannot find the tca executable")?;
    let mut children: Vec<(String, Child)> = Vec::new();
    for m in &launch.modules {
        let mut cmd = match &m.command {
            Some(argv) => {
                let mut c = Command::new(&argv[0]);
                c.args(&argv[1..]);
                c
            }
            None => {
                let mut c = Command::new(&exe);
                c.arg("module").arg(&m.name).arg("--connect").arg(&endpoint);
                c.args(&m.args);
                c
            }
        };
        cmd.env("TCA_CONNECT", &endpoint).kill_on_drop(true);
        let child = cmd
            .spawn()
            .with_context(|| format!("cannot start module {}", m.name))?;
        eprintln!(
            "started module {} (pid {})",
            m.name,
            child.id().unwrap_or(0)
        );
        children.push((m.name.clone(), child));
    }
    tokio::signal::ctrl_c()
        .await
        .context("cannot wait for Ctrl-C")?;
    eprintln!("stopping {} modules and central", children.len());
    for (name, child) in children.iter_mut() {
        if let Err(e) = child.kill().await {
            eprintln!("module {name}: {e}");
        }
    }
    central.shutdown().await?;
    Ok(ExitCode::SUCCESS)
}
