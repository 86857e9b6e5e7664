//! The launch file: central's options and the modules to start as processes.
//!
//! ```toml
//! [central]
//! listen = ["tcp/127.0.0.1:7447"]   # endpoints: zenoh ones, local or local/NAME (default
//!                                   # tcp/127.0.0.1:7447)
//! local_modules = true              # the modules started here connect over a local socket
//!                                   # (the first local endpoint of listen, else a private
//!                                   # local/up-<pid> added for them); false: listen[0]
//! log = "out/traffic.mcap"          # optional traffic log
//! journal = "out/central.journal"   # optional: after a crash, central comes back with its
//!                                   # task trees and queues (see tca central --journal)
//! policy = "policy.toml"            # optional: who may connect and what they may do
//! simulated_time = true             # optional: central keeps the simulated clock
//! insecure = true                   # optional: allow a network endpoint with no policy
//!
//! [[module]]
//! name = "echo"                     # a built-in module: runs `tca module echo --connect ...`
//! restart = true                    # started again if it crashes (the default)
//!
//! [[module]]
//! name = "my-planner"               # or any program; it gets TCA_CONNECT=<endpoint>
//! command = ["./target/release/my-planner", "--fast"]
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::LaunchError;

/// A launch file.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Launch {
    /// Central's options.
    #[serde(default)]
    pub central: CentralSection,
    /// Modules to start, in order.
    #[serde(default, rename = "module")]
    pub modules: Vec<ModuleSection>,
}

/// `[central]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CentralSection {
    /// Endpoints to listen on: zenoh ones (`tcp/HOST:PORT`) and local ones (`local`,
    /// `local/NAME`).
    #[serde(default = "default_listen")]
    pub listen: Vec<String>,
    /// The modules this file starts connect over a local socket (default): the first local
    /// endpoint of `listen`, or one added for them. False: they connect to `listen[0]`.
    #[serde(default = "yes")]
    pub local_modules: bool,
    /// Traffic log file.
    pub log: Option<PathBuf>,
    /// Journal file, as `tca central --journal`: a central restarted after a crash comes back
    /// with its task trees and queues.
    pub journal: Option<PathBuf>,
    /// Policy file (authentication, authorisation, limits), as `tca central --policy`.
    pub policy: Option<PathBuf>,
    /// Keep the system's simulated clock, as `tca central --simulated-time`.
    #[serde(default)]
    pub simulated_time: bool,
    /// Listen on endpoints other machines can reach with no policy (or one that
    /// authenticates no zenoh client), as `tca central --insecure`; refused otherwise.
    #[serde(default)]
    pub insecure: bool,
}

impl Default for CentralSection {
    fn default() -> Self {
        CentralSection {
            listen: default_listen(),
            local_modules: true,
            log: None,
            journal: None,
            policy: None,
            simulated_time: false,
            insecure: false,
        }
    }
}

fn default_listen() -> Vec<String> {
    vec![tca_central::DEFAULT_ENDPOINT.to_owned()]
}

/// `[[module]]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModuleSection {
    /// The module's name (a built-in module unless `command` is given).
    pub name: String,
    /// A program to run instead of the built-in module.
    pub command: Option<Vec<String>>,
    /// Extra arguments for the built-in module.
    #[serde(default)]
    pub args: Vec<String>,
    /// Start the module again when its process dies other than by exiting cleanly (with a
    /// growing pause between attempts). Default true.
    #[serde(default = "yes")]
    pub restart: bool,
}

fn yes() -> bool {
    true
}

impl Launch {
    /// Reads and checks a launch file. `builtins` are the module names that run without a
    /// `command` (the `tca` command's built-in modules).
    pub fn load(path: &Path, builtins: &[&str]) -> Result<Self, LaunchError> {
        let text = std::fs::read_to_string(path).map_err(|source| LaunchError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, builtins).map_err(|reason| LaunchError::Invalid {
            path: path.to_owned(),
            reason,
        })
    }

    /// Parses and checks launch-file text; the error says what is wrong.
    pub fn parse(text: &str, builtins: &[&str]) -> Result<Self, String> {
        let launch: Launch = toml::from_str(text).map_err(|e| e.to_string())?;
        if launch.central.listen.is_empty() {
            return Err(
                "[central] listen is empty; give at least one endpoint such as tcp/127.0.0.1:7447"
                    .into(),
            );
        }
        for m in &launch.modules {
            if let Some(cmd) = &m.command {
                if cmd.is_empty() {
                    return Err(format!("module {}: command is empty", m.name));
                }
            } else if !builtins.contains(&m.name.as_str()) {
                return Err(format!(
                    "module {}: not a built-in module ({}); give a command to run it",
                    m.name,
                    builtins.join(", ")
                ));
            }
        }
        Ok(launch)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BUILTINS: &[&str] = &["echo"];

    #[test]
    fn a_launch_file_parses() {
        let l = Launch::parse(
            "[central]\nlisten=[\"tcp/127.0.0.1:7500\"]\n[[module]]\nname=\"echo\"\n",
            BUILTINS,
        )
        .unwrap();
        assert_eq!(l.modules.len(), 1);
        assert_eq!(l.central.listen, vec!["tcp/127.0.0.1:7500"]);
        assert!(l.modules[0].restart, "modules restart by default");
        assert!(
            l.central.local_modules,
            "modules connect locally by default"
        );
        assert_eq!(l.central.policy, None);
        let l = Launch::parse(
            "[central]\npolicy=\"p.toml\"\n[[module]]\nname=\"echo\"\nrestart=false\n",
            BUILTINS,
        )
        .unwrap();
        assert!(!l.modules[0].restart);
        assert_eq!(l.central.policy, Some(PathBuf::from("p.toml")));
    }

    #[test]
    fn mistakes_are_named() {
        let err = Launch::parse("[[module]]\nname=\"nope\"\n", BUILTINS).unwrap_err();
        assert!(err.contains("not a built-in module (echo)"), "{err}");
        let err = Launch::parse("[central]\nlissen=[]\n", BUILTINS).unwrap_err();
        assert!(err.contains("lissen"), "{err}");
        let err = Launch::load(Path::new("/nonexistent/launch.toml"), BUILTINS).unwrap_err();
        assert!(err.to_string().contains("cannot read launch file"), "{err}");
    }
}
