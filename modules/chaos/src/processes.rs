//! The walking modules (and, when it is the one killed, central) as child processes that can be
//! killed and started again.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use anyhow::Context as _;
use tokio::process::{Child, Command};

/// How each walking module process is started.
#[derive(Clone, Debug)]
pub struct ProcessSetup {
    /// The `tca` executable.
    pub exe: PathBuf,
    /// Central's zenoh endpoint.
    pub endpoint: String,
    /// `--course` (or a terrain file with `--terrain`): the arguments naming the terrain.
    pub terrain_args: Vec<String>,
    /// Scanner noise seed.
    pub seed: u64,
    /// The Controller's speed factor, if not as fast as possible.
    pub speed: Option<f64>,
    /// `--compute` of the planners.
    pub compute: &'static str,
}

/// One walking module's process, or central's.
#[derive(Debug)]
pub struct ModuleProcess {
    /// The module's name (`controller`, `ism`, ...), or `central`.
    pub name: String,
    args: Vec<String>,
    exe: PathBuf,
    child: Option<Child>,
    /// Where its standard error goes (appended), if anywhere.
    stderr: Option<PathBuf>,
}

impl ModuleProcess {
    /// Starts module `name`, keeping its state in `state` (Controller and LTM Manager).
    pub fn start(setup: &ProcessSetup, name: &str, state: &Path) -> anyhow::Result<Self> {
        let mut args: Vec<String> = vec![
            "module".into(),
            name.into(),
            "--connect".into(),
            setup.endpoint.clone(),
            "--seed".into(),
            setup.seed.to_string(),
            "--compute".into(),
            setup.compute.into(),
            "--state".into(),
            state.display().to_string(),
        ];
        args.extend(setup.terrain_args.iter().cloned());
        if let (Some(speed), "controller") = (setup.speed, name) {
            args.extend(["--speed".into(), speed.to_string()]);
        }
        let mut process = ModuleProcess {
            name: name.into(),
            args,
            exe: setup.exe.clone(),
            child: None,
            stderr: None,
        };
        process.spawn()?;
        Ok(process)
    }

    /// Starts central as its own process on `endpoint`, on the simulated clock, logging to
    /// `log` and keeping its journal in `journal` (so that it can be killed and started again);
    /// what it says goes to `stderr` (appended).
    pub fn central(
        exe: &Path,
        endpoint: &str,
        log: &Path,
        journal: &Path,
        stderr: &Path,
    ) -> anyhow::Result<Self> {
        let mut process = ModuleProcess {
            name: "central".into(),
            args: vec![
                "central".into(),
                "--listen".into(),
                endpoint.into(),
                "--log".into(),
                log.display().to_string(),
                "--journal".into(),
                journal.display().to_string(),
                "--simulated-time".into(),
            ],
            exe: exe.to_owned(),
            child: None,
            stderr: Some(stderr.to_owned()),
        };
        process.spawn()?;
        Ok(process)
    }

    fn spawn(&mut self) -> anyhow::Result<()> {
        let stderr = match &self.stderr {
            Some(path) => Stdio::from(
                std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(path)
                    .with_context(|| format!("cannot open {}", path.display()))?,
            ),
            None => Stdio::null(),
        };
        let child = Command::new(&self.exe)
            .args(&self.args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(stderr)
            .kill_on_drop(true)
            .spawn()
            .with_context(|| format!("cannot start module {}", self.name))?;
        self.child = Some(child);
        Ok(())
    }

    /// Kills the process with SIGKILL, as a crash, and waits until it is gone.
    pub async fn kill(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.start_kill();
            let _ = child.wait().await;
        }
    }

    /// Starts the process again with the same arguments (and so the same state directory).
    pub fn restart(&mut self) -> anyhow::Result<()> {
        self.spawn()
    }

    /// Asks the process to stop (SIGINT: the module says goodbye to central), killing it if it
    /// has not stopped within 2 s.
    pub async fn stop(&mut self) {
        let Some(mut child) = self.child.take() else {
            return;
        };
        if let Some(pid) = child.id() {
            let _ = Command::new("kill")
                .args(["-INT", &pid.to_string()])
                .status()
                .await;
        }
        if tokio::time::timeout(Duration::from_secs(2), child.wait())
            .await
            .is_err()
        {
            let _ = child.start_kill();
            let _ = child.wait().await;
        }
    }
}
