//! Whole-robot queries for a posture (joint positions of every leg): link poses, collision
//! shapes, feet and the centre of mass, all in the body frame.

use nalgebra::{Isometry3, Point3};
use serde::Serialize;

use crate::error::KinematicsError;
use crate::model::RobotModel;
use crate::shape::PlacedShape;

/// A link's frame in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinkPose<'a> {
    /// The link's name.
    pub link: &'a str,
    /// Its frame in the body frame.
    pub pose: Isometry3<f64>,
}

/// The mass of the robot and where its centre is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MassProperties {
    /// Total mass, kilograms.
    pub mass: f64,
    /// Centre of mass in the body frame.
    pub centre: Point3<f64>,
}

impl RobotModel {
    /// Refuses a posture with the wrong number of legs or of joint positions, or with a
    /// value that is not finite.
    pub fn check_posture<Q: AsRef<[f64]>>(&self, posture: &[Q]) -> Result<(), KinematicsError> {
        if posture.len() != self.legs.len() {
            return Err(KinematicsError::LegCount {
                given: posture.len(),
                expected: self.legs.len(),
            });
        }
        for (leg, q) in self.legs.iter().zip(posture) {
            leg.check(q.as_ref())?;
        }
        Ok(())
    }

    /// The foot link's frame of one leg in the body frame (see
    /// [`Leg::forward_kinematics`](crate::Leg::forward_kinematics)).
    pub fn forward_kinematics(
        &self,
        leg: usize,
        q: &[f64],
    ) -> Result<Isometry3<f64>, KinematicsError> {
        self.leg_at(leg)?.forward_kinematics(q)
    }

    /// The frame of every link in the body frame, in file order.
    pub fn link_poses<Q: AsRef<[f64]>>(
        &self,
        posture: &[Q],
    ) -> Result<Vec<LinkPose<'_>>, KinematicsError> {
        let stages = self.stages(posture)?;
        Ok(self
            .links
            .iter()
            .map(|link| LinkPose {
                link: link.name(),
                pose: Self::place(&stages, link),
            })
            .collect())
    }

    /// Every collision shape placed in the body frame: the solids that must not hit the
    /// terrain. Feet's contact spheres are not among them (see
    /// [`foot_positions`](Self::foot_positions)).
    pub fn collision_shapes<Q: AsRef<[f64]>>(
        &self,
        posture: &[Q],
    ) -> Result<Vec<PlacedShape<'_>>, KinematicsError> {
        let stages = self.stages(posture)?;
        let mut shapes = Vec::new();
        for link in &self.links {
            if link.collisions.is_empty() {
                continue;
            }
            let pose = Self::place(&stages, link);
            shapes.extend(link.collisions.iter().map(|c| PlacedShape {
                link: link.name(),
                shape: c.shape,
                pose: pose * c.origin,
            }));
        }
        Ok(shapes)
    }

    /// The collision shapes of one leg's links placed in the body frame for that leg's
    /// joint positions `q` (the other legs and the body do not move with them): what a
    /// planner moving one leg tests at every sample, without placing the whole robot.
    pub fn leg_collision_shapes(
        &self,
        leg: usize,
        q: &[f64],
    ) -> Result<Vec<PlacedShape<'_>>, KinematicsError> {
        let l = self.leg_at(leg)?;
        l.check(q)?;
        let stages = l.stage_frames(q);
        let mut shapes = Vec::new();
        for link in &self.links {
            if link.placement.leg != Some(leg) || link.collisions.is_empty() {
                continue;
            }
            let pose = stages[link.placement.stage] * link.placement.offset;
            shapes.extend(link.collisions.iter().map(|c| PlacedShape {
                link: link.name(),
                shape: c.shape,
                pose: pose * c.origin,
            }));
        }
        Ok(shapes)
    }

    /// The centre of every foot's contact sphere in the body frame, one per leg.
    pub fn foot_positions<Q: AsRef<[f64]>>(
        &self,
        posture: &[Q],
    ) -> Result<Vec<Point3<f64>>, KinematicsError> {
        self.check_posture(posture)?;
        Ok(self
            .legs
            .iter()
            .zip(posture)
            .map(|(leg, q)| leg.foot_position_unchecked(q.as_ref()))
            .collect())
    }

    /// The total mass and the centre of mass in the body frame, legs included.
    pub fn centre_of_mass<Q: AsRef<[f64]>>(
        &self,
        posture: &[Q],
    ) -> Result<MassProperties, KinematicsError> {
        let stages = self.stages(posture)?;
        let mut moment = Point3::origin().coords;
        for link in &self.links {
            if link.mass > 0.0 {
                let centre = Self::place(&stages, link) * link.centre_of_mass;
                moment += centre.coords * link.mass;
            }
        }
        Ok(MassProperties {
            mass: self.total_mass,
            centre: Point3::from(moment / self.total_mass),
        })
    }

    /// The frames after each moving joint of every leg, for a checked posture.
    fn stages<Q: AsRef<[f64]>>(
        &self,
        posture: &[Q],
    ) -> Result<Vec<Vec<Isometry3<f64>>>, KinematicsError> {
        self.check_posture(posture)?;
        Ok(self
            .legs
            .iter()
            .zip(posture)
            .map(|(leg, q)| leg.stage_frames(q.as_ref()))
            .collect())
    }

    fn place(stages: &[Vec<Isometry3<f64>>], link: &crate::link::Link) -> Isometry3<f64> {
        let p = link.placement;
        match p.leg {
            None => p.offset,
            Some(leg) => stages[leg][p.stage] * p.offset,
        }
    }
}
