//! The robot model: loading it and looking at its legs and links.

use std::path::Path;

use serde::Serialize;

use crate::builtin;
use crate::error::{KinematicsError, ModelError};
use crate::leg::Leg;
use crate::link::Link;

/// A multi-legged robot read from URDF and checked against the crate's conventions.
///
/// The root link is the body and its frame is the body frame (x forward, y left, z up).
/// Legs keep the order of their foot links in the file. A whole-robot set of joint
/// positions (a *posture*) is one slice per leg, in that order, each as
/// [`Leg`] describes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobotModel {
    pub(crate) name: String,
    pub(crate) body_link: String,
    pub(crate) legs: Vec<Leg>,
    pub(crate) links: Vec<Link>,
    pub(crate) total_mass: f64,
}

impl RobotModel {
    /// Reads a robot from URDF text.
    pub fn from_urdf_str(urdf: &str) -> Result<Self, ModelError> {
        crate::build::build(&crate::read::parse(urdf)?)
    }

    /// Reads a robot from a URDF file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self, ModelError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ModelError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::from_urdf_str(&text)
    }

    /// One of the shipped robots by name (see [`BUILTIN_ROBOTS`](crate::BUILTIN_ROBOTS)).
    pub fn builtin(name: &str) -> Result<Self, ModelError> {
        let robot = builtin::find(name).ok_or_else(|| ModelError::UnknownRobot {
            name: name.to_owned(),
            known: builtin::names(),
        })?;
        Self::from_urdf_str(robot.urdf)
    }

    /// A shipped robot if `name_or_path` is one's name, otherwise the URDF file at that
    /// path (write `./ambler` for a file that has a shipped robot's name).
    pub fn load(name_or_path: &str) -> Result<Self, ModelError> {
        if builtin::find(name_or_path).is_some() {
            return Self::builtin(name_or_path);
        }
        let path = Path::new(name_or_path);
        if path.exists() {
            return Self::from_file(path);
        }
        Err(ModelError::UnknownRobot {
            name: name_or_path.to_owned(),
            known: builtin::names(),
        })
    }

    /// The `name` of the `<robot>` element.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The root link's name: the body.
    pub fn body_link(&self) -> &str {
        &self.body_link
    }

    /// The legs, in the order of their foot links in the file.
    pub fn legs(&self) -> &[Leg] {
        &self.legs
    }

    /// The leg with this name.
    pub fn leg(&self, name: &str) -> Option<&Leg> {
        self.legs.iter().find(|l| l.name() == name)
    }

    /// The index of the leg with this name.
    pub fn leg_index(&self, name: &str) -> Option<usize> {
        self.legs.iter().position(|l| l.name() == name)
    }

    /// The leg with this index, or an error naming the index.
    pub fn leg_at(&self, index: usize) -> Result<&Leg, KinematicsError> {
        self.legs
            .get(index)
            .ok_or_else(|| KinematicsError::UnknownLeg {
                leg: index.to_string(),
                count: self.legs.len(),
            })
    }

    /// Every link, in file order.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// The link with this name.
    pub fn link(&self, name: &str) -> Option<&Link> {
        self.links.iter().find(|l| l.name() == name)
    }

    /// The mass of the whole robot, legs included, kilograms.
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// The number of moving joints over all legs.
    pub fn dof(&self) -> usize {
        self.legs.iter().map(Leg::dof).sum()
    }

    /// Every leg in its [`neutral`](Leg::neutral) joint positions.
    pub fn neutral_posture(&self) -> Vec<Vec<f64>> {
        self.legs.iter().map(Leg::neutral).collect()
    }
}
