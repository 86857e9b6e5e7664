//! The Controller's state file: what lets a killed and restarted Controller process go on with
//! the leg where it was, as a real controller restarted would find its leg.
//!
//! After the simulator has computed a command (before its wall-clock play-out, before its
//! answer), the Controller writes its state and the command's outcome to the file (written to
//! a temporary file and renamed, so a kill never leaves half a file). A Controller started with
//! the file restores the leg, carriage, contact, clock and collision count from it.
//!
//! It also remembers the outcomes of the last [`REMEMBERED`] commands by message id. Central
//! delivers a command again when its Controller died before answering; if the dead Controller
//! had already carried it out, the new one answers with the recorded outcome instead of moving
//! the leg a second time. Goal and command ids thereby make redelivery idempotent.
//!
//! # Format
//!
//! The magic bytes `TCACTRL1`, then a postcard-encoded [`StateFile`].

use std::collections::VecDeque;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tca_messages::MessageId;

use crate::controller::{CommandFailure, SavedController};

/// Magic bytes at the start of a state file.
pub const MAGIC: &[u8; 8] = b"TCACTRL1";

/// How many command outcomes a state file remembers.
pub const REMEMBERED: usize = 64;

/// What a state file holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StateFile {
    /// The Controller.
    pub controller: SavedController,
    /// The latest commands carried out, oldest first: message id and outcome.
    pub done: VecDeque<(u64, Result<(), CommandFailure>)>,
}

/// Errors reading or writing a state file.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    /// The file could not be read or written.
    #[error("controller state file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a state file or is damaged.
    #[error(
        "controller state file {path} is not readable ({reason}); delete it to start the leg \
         from the terrain's start pose instead"
    )]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
}

/// A Controller's state file and the outcomes it remembers.
#[derive(Debug)]
pub struct Persistence {
    path: PathBuf,
    done: VecDeque<(u64, Result<(), CommandFailure>)>,
}

impl Persistence {
    /// Opens `path`: the saved Controller if the file exists, and the persistence that keeps it.
    pub fn open(path: &Path) -> Result<(Self, Option<SavedController>), StateError> {
        let bytes = match std::fs::read(path) {
            Ok(b) => Some(b),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(source) => {
                return Err(StateError::Io {
                    path: path.to_owned(),
                    source,
                });
            }
        };
        let mut persistence = Persistence {
            path: path.to_owned(),
            done: VecDeque::new(),
        };
        let Some(bytes) = bytes else {
            return Ok((persistence, None));
        };
        let corrupt = |reason: String| StateError::Corrupt {
            path: path.to_owned(),
            reason,
        };
        let body = bytes
            .strip_prefix(MAGIC.as_slice())
            .ok_or_else(|| corrupt("it does not start with TCACTRL1".into()))?;
        let file: StateFile =
            tca_messages::decode_data(body).map_err(|e| corrupt(e.to_string()))?;
        persistence.done = file.done;
        Ok((persistence, Some(file.controller)))
    }

    /// The outcome of command `id`, if this Controller (or the one before it) carried it out.
    pub fn outcome_of(&self, id: MessageId) -> Option<&Result<(), CommandFailure>> {
        self.done
            .iter()
            .rev()
            .find(|(done, _)| *done == id.0)
            .map(|(_, outcome)| outcome)
    }

    /// Records that command `id` was carried out with `outcome`, leaving the Controller as
    /// `controller`, and writes the file.
    pub fn record(
        &mut self,
        id: MessageId,
        outcome: &Result<(), CommandFailure>,
        controller: SavedController,
    ) -> Result<(), StateError> {
        self.done.push_back((id.0, outcome.clone()));
        while self.done.len() > REMEMBERED {
            self.done.pop_front();
        }
        self.write(controller)
    }

    /// Writes the file: the Controller and the remembered outcomes.
    pub fn write(&self, controller: SavedController) -> Result<(), StateError> {
        let file = StateFile {
            controller,
            done: self.done.clone(),
        };
        let mut bytes = MAGIC.to_vec();
        bytes.extend(
            tca_messages::encode_data(&file).map_err(|e| StateError::Corrupt {
                path: self.path.clone(),
                reason: e.to_string(),
            })?,
        );
        let io = |source| StateError::Io {
            path: self.path.clone(),
            source,
        };
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let tmp = self.path.with_extension("tmp");
        std::fs::write(&tmp, bytes).map_err(io)?;
        std::fs::rename(&tmp, &self.path).map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ControllerConfig;
    use crate::controller::Controller;
    use tokio::time::Instant;

    fn controller() -> Controller {
        Controller::new(&ControllerConfig::builtin().unwrap(), Instant::now()).unwrap()
    }

    #[test]
    fn a_restarted_controller_finds_the_leg_where_it_was_and_remembers_what_it_did() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("controller.state");
        let (mut p, saved) = Persistence::open(&path).unwrap();
        assert!(saved.is_none(), "no file yet");

        let mut c = controller();
        let y0 = c.simulator().body_position().y_m;
        let run = c.body_move(y0 + 0.3, Instant::now());
        assert!(run.outcome.is_ok(), "{:?}", run.outcome);
        p.record(MessageId::new(3, 7), &run.outcome, c.saved())
            .unwrap();

        let (p2, saved) = Persistence::open(&path).unwrap();
        let saved = saved.expect("saved state");
        let mut fresh = controller();
        assert!((fresh.simulator().body_position().y_m - y0).abs() < 1e-9);
        fresh.restore(&saved, Instant::now());
        assert_eq!(fresh.saved(), c.saved());
        assert!((fresh.simulator().body_position().y_m - (y0 + 0.3)).abs() < 0.01);
        assert_eq!(p2.outcome_of(MessageId::new(3, 7)), Some(&Ok(())));
        assert_eq!(p2.outcome_of(MessageId::new(3, 8)), None);
    }

    #[test]
    fn only_the_latest_outcomes_are_remembered() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.state");
        let (mut p, _) = Persistence::open(&path).unwrap();
        let c = controller();
        for seq in 0..(REMEMBERED as u32 + 10) {
            p.record(MessageId::new(1, seq), &Ok(()), c.saved())
                .unwrap();
        }
        assert_eq!(p.outcome_of(MessageId::new(1, 0)), None);
        assert!(
            p.outcome_of(MessageId::new(1, REMEMBERED as u32 + 9))
                .is_some()
        );
    }

    #[test]
    fn a_damaged_file_is_refused_with_what_to_do() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.state");
        std::fs::write(&path, b"TCACTRL1\xff\xff\xff").unwrap();
        let e = Persistence::open(&path).unwrap_err().to_string();
        assert!(e.contains("delete it"), "{e}");
        std::fs::write(&path, b"something else").unwrap();
        let e = Persistence::open(&path).unwrap_err().to_string();
        assert!(e.contains("TCACTRL1"), "{e}");
    }
}
