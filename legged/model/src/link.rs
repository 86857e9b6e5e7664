//! Links: the rigid parts of the robot, with their masses, collision shapes and where they
//! ride (on the body, or after some joint of a leg).

use nalgebra::{Isometry3, Point3};
use serde::Serialize;

use crate::shape::Collision;

/// Where a link rides: on the body, or after the first `stage` moving joints of a leg.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Placement {
    /// The leg whose joints move the link; `None` for links rigid with the body.
    pub(crate) leg: Option<usize>,
    /// How many of that leg's moving joints lie between the body and the link.
    pub(crate) stage: usize,
    /// The link's frame in the child frame of that joint (in the body frame for stage 0).
    pub(crate) offset: Isometry3<f64>,
}

/// A link of the robot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Link {
    pub(crate) name: String,
    pub(crate) mass: f64,
    pub(crate) centre_of_mass: Point3<f64>,
    pub(crate) collisions: Vec<Collision>,
    pub(crate) placement: Placement,
}

impl Link {
    /// The link's name in the file.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its mass, kilograms (0 when the file gives no `<inertial>`).
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// Its centre of mass in its own frame (the origin of its `<inertial>`).
    pub fn centre_of_mass(&self) -> Point3<f64> {
        self.centre_of_mass
    }

    /// The shapes that must not hit the terrain, in the link's frame. A foot's contact
    /// sphere is not among them: it is the leg's
    /// [`foot_radius`](crate::Leg::foot_radius).
    pub fn collisions(&self) -> &[Collision] {
        &self.collisions
    }

    /// The index of the leg whose joints move this link, or `None` for a part of the body
    /// (the root link and whatever is fixed to it).
    pub fn leg(&self) -> Option<usize> {
        self.placement.leg
    }

    /// How many of its leg's moving joints lie between the body and the link (0 for body
    /// parts).
    pub fn stage(&self) -> usize {
        self.placement.stage
    }
}
