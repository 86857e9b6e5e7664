//! `tca up FILE`: central and a set of modules as processes, stopped together on Ctrl-C. A
//! module whose process dies (crash, `kill -9`) is started again, after a pause that doubles
//! from 0.5 s up to 30 s while it keeps dying within a minute of starting.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::Args;
use tca::launch::{Launch, ModuleSection};
use tca_central::CentralConfig;
use tca_central::runtime::StartOptions;
use tokio::process::{Child, Command};
use tokio::sync::watch;

#[derive(Debug, Args)]
pub(crate) struct UpArgs {
    /// The launch file.
    file: PathBuf,
}

/// The first pause before a crashed module is started again.
const FIRST_PAUSE: Duration = Duration::from_millis(500);
/// The longest pause.
const LONGEST_PAUSE: Duration = Duration::from_secs(30);
/// A module that ran this long before dying starts again after the first pause.
const HEALTHY_RUN: Duration = Duration::from_secs(60);

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
    let policy = match &launch.central.policy {
        Some(path) => Some(std::sync::Arc::new(
            tca_central::Policy::load(path).context("cannot load the policy")?,
        )),
        None => None,
    };
    let central = tca_central::start(StartOptions {
        log: launch.central.log.clone(),
        listen: launch.central.listen.clone(),
        config: CentralConfig {
            policy,
            ..CentralConfig::default()
        },
    })
    .await
    .context("cannot start central")?;
    let endpoint = launch.central.listen[0].clone();
    eprintln!("central listening on {}", launch.central.listen.join(", "));
    let exe = std::env::current_exe().context("cannot find the tca executable")?;
    let (stop_tx, stop_rx) = watch::channel(false);
    let mut supervisors = Vec::new();
    for m in &launch.modules {
        let command = ModuleCommand {
            section: m.clone(),
            exe: exe.clone(),
            endpoint: endpoint.clone(),
        };
        // Started in order, before the next one is.
        let child = command.spawn()?;
        supervisors.push(tokio::spawn(supervise(command, child, stop_rx.clone())));
    }
    tokio::signal::ctrl_c()
        .await
        .context("cannot wait for Ctrl-C")?;
    eprintln!("stopping {} modules and central", supervisors.len());
    let _ = stop_tx.send(true);
    for s in supervisors {
        let _ = s.await;
    }
    central.shutdown().await?;
    Ok(ExitCode::SUCCESS)
}

/// How one module of the launch file is started.
struct ModuleCommand {
    section: ModuleSection,
    exe: PathBuf,
    endpoint: String,
}

impl ModuleCommand {
    fn spawn(&self) -> anyhow::Result<Child> {
        let m = &self.section;
        let mut cmd = match &m.command {
            Some(argv) => {
                let mut c = Command::new(&argv[0]);
                c.args(&argv[1..]);
                c
            }
            None => {
                let mut c = Command::new(&self.exe);
                c.arg("module")
                    .arg(&m.name)
                    .arg("--connect")
                    .arg(&self.endpoint);
                c.args(&m.args);
                c
            }
        };
        cmd.env("TCA_CONNECT", &self.endpoint).kill_on_drop(true);
        let child = cmd
            .spawn()
            .with_context(|| format!("cannot start module {}", m.name))?;
        eprintln!(
            "started module {} (pid {})",
            m.name,
            child.id().unwrap_or(0)
        );
        Ok(child)
    }
}

/// Watches one module's process: starts it again when it dies (if its section says so) until
/// `stop`, then kills it.
async fn supervise(command: ModuleCommand, mut child: Child, mut stop: watch::Receiver<bool>) {
    let name = command.section.name.clone();
    let mut pause = FIRST_PAUSE;
    let mut started = Instant::now();
    loop {
        let ended = tokio::select! {
            _ = stop.wait_for(|s| *s) => None,
            status = child.wait() => Some(status),
        };
        let Some(status) = ended else {
            if let Err(e) = child.kill().await {
                eprintln!("module {name}: {e}");
            }
            return;
        };
        let status = match status {
            Ok(s) => s,
            Err(e) => {
                eprintln!("module {name}: cannot watch its process: {e}");
                return;
            }
        };
        if status.success() || !command.section.restart {
            eprintln!("module {name} ended ({status})");
            return;
        }
        if started.elapsed() >= HEALTHY_RUN {
            pause = FIRST_PAUSE;
        }
        eprintln!("module {name} died ({status}); starting it again in {pause:?}");
        tokio::select! {
            _ = stop.wait_for(|s| *s) => return,
            _ = tokio::time::sleep(pause) => {}
        }
        pause = (pause * 2).min(LONGEST_PAUSE);
        match command.spawn() {
            Ok(c) => {
                child = c;
                started = Instant::now();
            }
            Err(e) => {
                eprintln!("module {name}: {e:#}");
                return;
            }
        }
    }
}
