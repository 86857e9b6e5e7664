//! What a worker is set up with when it starts: the robot, the terrain, CG-space's
//! parameters and its region cap. The planner builds its own space from the same set-up;
//! the two must agree, which every batch checks ([`tca_cg_space::fingerprint`]).
//!
//! Nothing large travels on the bus: a worker on another machine reads the robot (a shipped
//! name or a URDF file) and the terrain (a built-in course and seed, or an `.asc` file) itself.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use tca_cg_space::{CgError, CgParams, CgRobot, CgSpace};
use tca_legged_courses::Course;
use tca_legged_model::RobotModel;
use tca_robot::HeightField;
use tca_robot::terrain::asc::{NoData, read_height_field};
use thiserror::Error;

/// Why a worker (or the planner) could not be set up.
#[derive(Debug, Error)]
pub enum SetupError {
    /// The robot is unknown or its description unreadable.
    #[error("robot {robot:?}: {reason}")]
    Robot {
        /// What was given.
        robot: String,
        /// Why it cannot be used.
        reason: String,
    },
    /// The terrain is unknown or unreadable.
    #[error("terrain {terrain:?}: {reason}")]
    Terrain {
        /// What was given.
        terrain: String,
        /// Why it cannot be used.
        reason: String,
    },
    /// CG-space cannot be built for them.
    #[error("CG-space cannot be built: {0}")]
    Space(#[from] CgError),
}

/// Where the terrain comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TerrainSource {
    /// A built-in course of `tca-legged-courses`, built from a seed.
    Course {
        /// Its name (one of `tca_legged_courses::NAMES`).
        name: String,
        /// The seed it is built from.
        seed: u64,
    },
    /// An ESRI ASCII grid (`.asc`) file.
    File(PathBuf),
}

impl TerrainSource {
    /// A built-in course's name (built from `seed`), else a file's path.
    pub fn parse(text: &str, seed: u64) -> Self {
        if tca_legged_courses::NAMES.contains(&text) {
            TerrainSource::Course {
                name: text.to_owned(),
                seed,
            }
        } else {
            TerrainSource::File(PathBuf::from(text))
        }
    }

    /// The terrain.
    pub fn load(&self) -> Result<HeightField, SetupError> {
        match self {
            TerrainSource::Course { name, seed } => Course::builtin(name, *seed)
                .map(|c| c.terrain)
                .map_err(|e| SetupError::Terrain {
                    terrain: name.clone(),
                    reason: e.to_string(),
                }),
            TerrainSource::File(path) => {
                let shown = path.display().to_string();
                if !Path::new(path).exists() {
                    return Err(SetupError::Terrain {
                        terrain: shown,
                        reason: format!(
                            "neither a built-in course ({}) nor an existing .asc file",
                            tca_legged_courses::NAMES.join(", ")
                        ),
                    });
                }
                read_height_field(path, NoData::Refuse).map_err(|e| SetupError::Terrain {
                    terrain: shown,
                    reason: e.to_string(),
                })
            }
        }
    }
}

/// A worker's set-up.
#[derive(Debug, Clone)]
pub struct WorkerSetup {
    /// A shipped robot's name or a URDF file.
    pub robot: String,
    /// The terrain.
    pub terrain: TerrainSource,
    /// CG-space's parameters (the planner's must be the same).
    pub params: CgParams,
    /// Most regions the worker holds at once (`None`: no cap).
    pub region_cap: Option<usize>,
}

impl WorkerSetup {
    /// The robot's model.
    pub fn model(&self) -> Result<RobotModel, SetupError> {
        RobotModel::load(&self.robot).map_err(|e| SetupError::Robot {
            robot: self.robot.clone(),
            reason: e.to_string(),
        })
    }

    /// The worker's CG-space: the robot tabulated for the terrain, built lazily, capped.
    pub fn space(&self) -> Result<CgSpace, SetupError> {
        let model = self.model()?;
        let terrain = self.terrain.load()?;
        let robot = CgRobot::new(&model, terrain.grid().resolution_m(), self.params.clone())?;
        Ok(CgSpace::new(Arc::new(robot), &terrain)?.with_region_cap(self.region_cap))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_robots_and_terrains_are_refused_clearly() {
        let setup = WorkerSetup {
            robot: "no-such-robot".into(),
            terrain: TerrainSource::parse("cliff", 1),
            params: CgParams::default(),
            region_cap: None,
        };
        let e = setup.space().unwrap_err().to_string();
        assert!(e.contains("no-such-robot"), "{e}");
        let t = TerrainSource::parse("/no/such/field.asc", 1);
        assert!(matches!(t, TerrainSource::File(_)));
        let e = t.load().unwrap_err().to_string();
        assert!(e.contains("cliff") && e.contains("field.asc"), "{e}");
        assert_eq!(
            TerrainSource::parse("cliff", 4),
            TerrainSource::Course {
                name: "cliff".into(),
                seed: 4
            }
        );
    }
}
