//! Starting what a launch file names: central in this process, each module as a process of
//! its own (a built-in one as `EXE module NAME --connect ENDPOINT ARGS...`, any other by its
//! `command`, with `TCA_CONNECT=ENDPOINT`). ENDPOINT is a local socket unless the file says
//! `local_modules = false`: the first local endpoint central listens on, or `local/up-<pid>`,
//! added for the modules. A module whose process dies (a crash, `kill -9`)
//! is started again, after a pause that doubles from [`FIRST_PAUSE`] up to
//! [`LONGEST_PAUSE`] while it keeps dying within [`HEALTHY_RUN`] of starting.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use tca_central::{CentralConfig, Policy, RunningCentral, StartOptions, Stats};
use tokio::process::{Child, Command};
use tokio::sync::watch;
use tokio::task::JoinHandle;

use crate::{Launch, LaunchError, ModuleSection};

/// Set in the environment of every built-in module `tca up` starts: the launcher's process
/// id. Such a module ends when its parent is no longer that process (the launcher was killed
/// before it could stop its modules), rather than waiting for a central that will not return.
pub const LAUNCHER_PID_ENV: &str = "TCA_LAUNCHER_PID";

/// The first pause before a crashed module is started again.
pub const FIRST_PAUSE: Duration = Duration::from_millis(500);
/// The longest pause.
pub const LONGEST_PAUSE: Duration = Duration::from_secs(30);
/// A module that ran this long before dying starts again after the first pause.
pub const HEALTHY_RUN: Duration = Duration::from_secs(60);

/// A running launch file: central and the supervised module processes.
pub struct Up {
    central: RunningCentral,
    module_endpoint: String,
    stop: watch::Sender<bool>,
    supervisors: Vec<JoinHandle<()>>,
    kept_log: Option<PathBuf>,
}

impl Up {
    /// Every endpoint central listens on.
    pub fn endpoints(&self) -> Vec<String> {
        self.central.listening()
    }

    /// Where the modules started from the launch file reach central.
    pub fn module_endpoint(&self) -> &str {
        &self.module_endpoint
    }

    /// Where the previous traffic log was kept, if central's log file existed.
    pub fn kept_log(&self) -> Option<&Path> {
        self.kept_log.as_deref()
    }

    /// How many modules are supervised.
    pub fn modules(&self) -> usize {
        self.supervisors.len()
    }

    /// Stops every module process, then central; central's final statistics.
    pub async fn stop(self) -> Result<Stats, LaunchError> {
        let _ = self.stop.send(true);
        for s in self.supervisors {
            let _ = s.await;
        }
        Ok(self.central.shutdown().await?)
    }
}

/// Starts central and the modules of `launch` (in order, each started before the next);
/// built-in modules run as `exe module NAME`. An earlier traffic log at central's log path is
/// kept (see `tca_logs::set_aside`).
pub async fn up(launch: &Launch, exe: &Path) -> Result<Up, LaunchError> {
    let policy = match &launch.central.policy {
        Some(path) => Some(Arc::new(Policy::load(path)?)),
        None => None,
    };
    let mut listen = launch.central.listen.clone();
    let endpoint = if launch.central.local_modules {
        match listen.iter().find(|e| is_local(e)) {
            Some(e) => e.clone(),
            None => {
                let e = format!("local/up-{}", std::process::id());
                listen.push(e.clone());
                e
            }
        }
    } else {
        listen[0].clone()
    };
    let central = tca_central::start(StartOptions {
        log: launch.central.log.clone(),
        listen: listen.clone(),
        insecure: launch.central.insecure,
        config: CentralConfig {
            policy,
            simulated_time: launch.central.simulated_time,
            ..CentralConfig::default()
        },
        journal: launch.central.journal.clone(),
        keep_previous_log: true,
    })
    .await?;
    let kept_log = central.kept_log().map(Path::to_path_buf);
    tracing::info!(endpoints = ?listen, modules = %endpoint, "central listening");
    let (stop, stop_rx) = watch::channel(false);
    let mut supervisors = Vec::new();
    for m in &launch.modules {
        let command = ModuleCommand {
            section: m.clone(),
            exe: exe.to_owned(),
            endpoint: endpoint.clone(),
        };
        let child = command.spawn()?;
        supervisors.push(tokio::spawn(supervise(command, child, stop_rx.clone())));
    }
    Ok(Up {
        central,
        module_endpoint: endpoint,
        stop,
        supervisors,
        kept_log,
    })
}

/// Whether `endpoint` is a local socket's (`local`, `local/NAME`).
fn is_local(endpoint: &str) -> bool {
    endpoint == "local" || endpoint.starts_with("local/")
}

/// How one module of the launch file is started.
struct ModuleCommand {
    section: ModuleSection,
    exe: PathBuf,
    endpoint: String,
}

impl ModuleCommand {
    fn spawn(&self) -> Result<Child, LaunchError> {
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
        cmd.env("TCA_CONNECT", &self.endpoint)
            .env(LAUNCHER_PID_ENV, std::process::id().to_string())
            .kill_on_drop(true);
        let child = cmd.spawn().map_err(|source| LaunchError::Spawn {
            module: m.name.clone(),
            source,
        })?;
        tracing::info!(module = %m.name, pid = child.id().unwrap_or(0), "started module");
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
                tracing::warn!(module = %name, error = %e, "cannot kill the module's process");
            }
            return;
        };
        let status = match status {
            Ok(s) => s,
            Err(e) => {
                tracing::error!(module = %name, error = %e, "cannot watch the module's process");
                return;
            }
        };
        if status.success() || !command.section.restart {
            tracing::info!(module = %name, %status, "module ended");
            return;
        }
        if started.elapsed() >= HEALTHY_RUN {
            pause = FIRST_PAUSE;
        }
        tracing::warn!(module = %name, %status, ?pause, "module died; starting it again");
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
                tracing::error!(module = %name, error = %e, "cannot start the module again");
                return;
            }
        }
    }
}
