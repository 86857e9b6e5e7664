//! The `tca` binary as a child process. A test names the binary of its package
//! (`Tca::at(env!("CARGO_BIN_EXE_tca"))`, which only the package's own tests can write).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::Duration;

use crate::retry;

/// The `tca` binary under test.
#[derive(Clone, Debug)]
pub struct Tca {
    exe: PathBuf,
}

/// How a run of `tca` ended: its status and what it printed.
#[derive(Debug)]
pub struct Output {
    /// The exit status.
    pub status: ExitStatus,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl Tca {
    /// The binary at `exe`.
    pub fn at(exe: impl Into<PathBuf>) -> Self {
        Tca { exe: exe.into() }
    }

    /// The binary's path.
    pub fn path(&self) -> &Path {
        &self.exe
    }

    /// A command running the binary with `args`, stdin closed.
    pub fn command(&self, args: &[&str]) -> Command {
        let mut c = Command::new(&self.exe);
        c.args(args).stdin(Stdio::null());
        c
    }

    /// Runs `tca ARGS` to its end, failing the test after `limit`.
    pub async fn run(&self, what: &str, args: &[&str], limit: Duration) -> Output {
        let mut command = self.command(args);
        let run = tokio::task::spawn_blocking(move || command.output());
        let out = match tokio::time::timeout(limit, run).await {
            Ok(out) => out.expect("joins").expect("tca runs"),
            Err(_) => panic!("timed out after {limit:?}: {what}"),
        };
        Output {
            status: out.status,
            stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        }
    }

    /// Starts `tca ARGS` in the background (stdout discarded, stderr shown).
    pub fn spawn(&self, args: &[&str]) -> ChildProcess {
        let child = self
            .command(args)
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("tca starts");
        ChildProcess(child)
    }

    /// The modules registered with the central at `endpoint` (`tca registry --json`).
    pub async fn registered_modules(&self, endpoint: &str) -> Result<Vec<String>, String> {
        let mut command = self.command(&["registry", "--connect", endpoint, "--json"]);
        let out = tokio::task::spawn_blocking(move || command.output())
            .await
            .map_err(|e| e.to_string())?
            .map_err(|e| e.to_string())?;
        let v: serde_json::Value =
            serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())?;
        Ok(v["modules"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|m| m.as_str().map(str::to_owned))
                    .collect()
            })
            .unwrap_or_default())
    }

    /// Waits until every module in `names` is registered with the central at `endpoint`.
    pub async fn wait_for_modules(&self, endpoint: &str, names: &[&str]) {
        retry("the modules registered", || async {
            let modules = self.registered_modules(endpoint).await?;
            let missing: Vec<_> = names
                .iter()
                .filter(|n| !modules.iter().any(|m| m == *n))
                .collect();
            if missing.is_empty() {
                Ok(())
            } else {
                Err(format!("still missing {missing:?}"))
            }
        })
        .await
    }
}

/// A child process, killed (`SIGKILL`, as a crash) when dropped.
pub struct ChildProcess(pub Child);

impl ChildProcess {
    /// Kills it and waits for it.
    pub fn kill(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }

    /// Interrupts it (`SIGINT`, as Ctrl-C) and waits until it has exited; the test fails
    /// if that takes longer than [`crate::within`] allows.
    pub async fn interrupt_and_wait(&mut self, what: &str) {
        let _ = Command::new("kill")
            .args(["-INT", &self.0.id().to_string()])
            .status();
        crate::within(what, async {
            while self.0.try_wait().ok().flatten().is_none() {
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        })
        .await;
    }
}

impl Drop for ChildProcess {
    fn drop(&mut self) {
        self.kill();
    }
}

/// The JSON report on the last line of `tca walk --json`'s stdout (the test fails, showing
/// both streams, if there is none).
pub fn walk_report(stdout: &str, stderr: &str) -> serde_json::Value {
    let last = stdout.trim().lines().last().unwrap_or_default();
    serde_json::from_str(last)
        .unwrap_or_else(|e| panic!("no walk report ({e}): {stdout}\n{stderr}"))
}
