//! Where the tools' terrain and robot come from: a built-in course (with its seed) or an
//! ESRI ASCII grid file, and a shipped robot or a URDF file.

use std::path::PathBuf;
use std::sync::Arc;

use tca_footfall::{FootfallError, Scene};
use tca_legged_model::{BUILTIN_ROBOTS, RobotModel};
use tca_legged_sim::StartPose;
use tca_robot::HeightField;
use tca_robot::terrain::asc::{NoData, read_height_field};

/// The terrain: a built-in course or a file.
#[derive(Clone, Debug, PartialEq)]
pub enum TerrainSource {
    /// A built-in course by name, with its seed.
    Course {
        /// Its name (`tca course list`).
        name: String,
        /// Its seed.
        seed: u64,
    },
    /// An ESRI ASCII grid (`.asc`).
    File(PathBuf),
}

impl TerrainSource {
    /// A course's name, or a path when it names no course (ends in `.asc`, or exists).
    pub fn parse(text: &str, seed: u64) -> TerrainSource {
        let is_course = tca_legged_courses::NAMES.contains(&text);
        if is_course {
            TerrainSource::Course {
                name: text.to_owned(),
                seed,
            }
        } else {
            TerrainSource::File(PathBuf::from(text))
        }
    }

    /// The height field, and the course's start when it is one.
    pub fn load(&self) -> Result<(HeightField, Option<StartPose>), FootfallError> {
        match self {
            TerrainSource::Course { name, seed } => {
                let c = tca_legged_courses::Course::builtin(name, *seed)
                    .map_err(|e| FootfallError::Scene(e.to_string()))?;
                let start = StartPose {
                    x_m: c.start.x_m,
                    y_m: c.start.y_m,
                    yaw_rad: c.start.yaw_rad,
                };
                Ok((c.terrain, Some(start)))
            }
            TerrainSource::File(path) => {
                let field = read_height_field(path, NoData::Refuse).map_err(|e| {
                    FootfallError::Scene(format!(
                        "cannot read the terrain {}: {e} (give a built-in course's name, \
                         `tca course list`, or an .asc file)",
                        path.display()
                    ))
                })?;
                Ok((field, None))
            }
        }
    }

    /// A short description.
    pub fn describe(&self) -> String {
        match self {
            TerrainSource::Course { name, seed } => format!("{name} (seed {seed})"),
            TerrainSource::File(p) => p.display().to_string(),
        }
    }
}

/// A robot and its URDF text: a shipped one by name, or a file.
pub fn load_robot(name_or_path: &str) -> Result<(RobotModel, String), FootfallError> {
    if let Some(b) = BUILTIN_ROBOTS.iter().find(|r| r.name == name_or_path) {
        let model =
            RobotModel::from_urdf_str(b.urdf).map_err(|e| FootfallError::Scene(e.to_string()))?;
        return Ok((model, b.urdf.to_owned()));
    }
    let text = std::fs::read_to_string(name_or_path).map_err(|e| {
        FootfallError::Scene(format!(
            "no shipped robot is called {name_or_path:?} and it cannot be read as a URDF file \
             ({e}); shipped robots: {}",
            BUILTIN_ROBOTS
                .iter()
                .map(|r| r.name)
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })?;
    let model =
        RobotModel::from_urdf_str(&text).map_err(|e| FootfallError::Scene(e.to_string()))?;
    Ok((model, text))
}

/// Everything the FootFall tools and modules are set up with.
#[derive(Clone, Debug, PartialEq)]
pub struct FootfallSetup {
    /// The robot (a shipped one's name or a URDF file).
    pub robot: String,
    /// The terrain (the ground side's digital elevation model; the simulator's truth).
    pub terrain: TerrainSource,
    /// Where the robot stands; the course's start when `None`.
    pub start: Option<StartPose>,
}

impl Default for FootfallSetup {
    /// The shipped `athlete` at the start of the rock field of seed 1.
    fn default() -> Self {
        Self {
            robot: "athlete".into(),
            terrain: TerrainSource::Course {
                name: "rock-field".into(),
                seed: 1,
            },
            start: None,
        }
    }
}

impl FootfallSetup {
    /// The robot, its URDF, the terrain and the start.
    pub fn load(
        &self,
    ) -> Result<(Arc<RobotModel>, String, Arc<HeightField>, StartPose), FootfallError> {
        let (model, urdf) = load_robot(&self.robot)?;
        let (terrain, course_start) = self.terrain.load()?;
        let start = self.start.or(course_start).ok_or_else(|| {
            FootfallError::Scene(format!(
                "the terrain {} is a file: say where the robot stands with --start X,Y[,YAW]",
                self.terrain.describe()
            ))
        })?;
        Ok((Arc::new(model), urdf, Arc::new(terrain), start))
    }

    /// The robot standing at the start, as the simulator stands it.
    pub fn scene(&self) -> Result<Scene, FootfallError> {
        let (model, _, terrain, start) = self.load()?;
        Scene::standing(model, terrain, start)
    }
}
