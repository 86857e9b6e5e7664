//! A leg: its moving joints from the body to the foot, and its forward kinematics.

use nalgebra::{Isometry3, Matrix3xX, Point3};
use serde::Serialize;

use crate::error::KinematicsError;
use crate::joint::{JointKind, LegJoint};

/// One leg: the chain of moving joints from the body to a link named `<leg>_foot`.
///
/// Joint positions for the leg are a slice with one value per moving joint, in chain order
/// (from the body outwards), in radians for revolute and metres for prismatic joints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Leg {
    pub(crate) name: String,
    pub(crate) joints: Vec<LegJoint>,
    pub(crate) foot_link: String,
    pub(crate) foot_offset: Isometry3<f64>,
    pub(crate) contact_centre: Point3<f64>,
    pub(crate) foot_radius: f64,
}

impl Leg {
    /// The leg's name: its foot link's name without `_foot`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The moving joints, from the body outwards.
    pub fn joints(&self) -> &[LegJoint] {
        &self.joints
    }

    /// The number of moving joints (the length of a joint-position slice).
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The foot link's name (`<leg>_foot`).
    pub fn foot_link(&self) -> &str {
        &self.foot_link
    }

    /// The radius of the foot's contact sphere, metres; 0 for a point foot (a foot link
    /// without `<collision>`).
    pub fn foot_radius(&self) -> f64 {
        self.foot_radius
    }

    /// The foot link's frame in the child frame of the last moving joint (fixed joints in
    /// between folded in).
    pub fn foot_offset(&self) -> &Isometry3<f64> {
        &self.foot_offset
    }

    /// The centre of the contact sphere in the foot link's frame (the origin of its
    /// `<collision>`, or the link's origin for a point foot).
    pub fn contact_centre(&self) -> Point3<f64> {
        self.contact_centre
    }

    /// The joint positions the leg takes when nothing else is known: every joint at 0, or
    /// at the nearest limit when 0 is outside its range. The shipped robots stand in it.
    pub fn neutral(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.limits.clamp(0.0)).collect()
    }

    /// The middle of every joint's range.
    pub fn middle(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.limits.middle()).collect()
    }

    /// Whether every position lies within its joint's limits (false for a wrong length).
    pub fn within_limits(&self, q: &[f64]) -> bool {
        q.len() == self.dof()
            && self
                .joints
                .iter()
                .zip(q)
                .all(|(j, &v)| j.limits.contains(v))
    }

    /// The positions moved into the joints' limits (missing values taken as 0, extra ones
    /// dropped).
    pub fn clamp(&self, q: &[f64]) -> Vec<f64> {
        self.joints
            .iter()
            .enumerate()
            .map(|(i, j)| j.limits.clamp(q.get(i).copied().unwrap_or(0.0)))
            .collect()
    }

    /// Refuses a slice of the wrong length or with a value that is not finite.
    pub fn check(&self, q: &[f64]) -> Result<(), KinematicsError> {
        if q.len() != self.dof() {
            return Err(KinematicsError::JointCount {
                leg: self.name.clone(),
                given: q.len(),
                expected: self.dof(),
            });
        }
        if let Some((j, v)) = self.joints.iter().zip(q).find(|(_, v)| !v.is_finite()) {
            return Err(KinematicsError::NotFinite {
                leg: self.name.clone(),
                what: format!("the position {v} of joint `{}`", j.name),
            });
        }
        Ok(())
    }

    /// The position of the first moving joint in the body frame: where the leg meets the
    /// body (its hip or shoulder), which does not depend on the joint positions.
    pub fn base_position(&self) -> Point3<f64> {
        self.joints
            .first()
            .map(|j| Point3::from(j.origin.translation.vector))
            .unwrap_or_else(Point3::origin)
    }

    /// The child frame of every moving joint in the body frame, from the body outwards.
    pub fn joint_frames(&self, q: &[f64]) -> Result<Vec<Isometry3<f64>>, KinematicsError> {
        self.check(q)?;
        Ok(self.stage_frames(q)[1..].to_vec())
    }

    /// The foot link's frame in the body frame.
    pub fn forward_kinematics(&self, q: &[f64]) -> Result<Isometry3<f64>, KinematicsError> {
        self.check(q)?;
        Ok(self.foot_pose_unchecked(q))
    }

    /// The centre of the foot's contact sphere in the body frame: the point that
    /// [`inverse_kinematics`](Self::inverse_kinematics) places. On level ground the foot
    /// touches when this point is [`foot_radius`](Self::foot_radius) above the ground.
    pub fn foot_position(&self, q: &[f64]) -> Result<Point3<f64>, KinematicsError> {
        self.check(q)?;
        Ok(self.foot_position_unchecked(q))
    }

    /// The 3 x [`dof`](Self::dof) Jacobian of [`foot_position`](Self::foot_position) with
    /// respect to the joint positions, in the body frame.
    pub fn jacobian(&self, q: &[f64]) -> Result<Matrix3xX<f64>, KinematicsError> {
        self.check(q)?;
        Ok(self.jacobian_unchecked(q))
    }

    /// The frame after each moving joint: index 0 is the body frame (identity), index k the
    /// child frame of joint k. `q` must have the right length.
    pub(crate) fn stage_frames(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        let mut frames = Vec::with_capacity(self.joints.len() + 1);
        let mut frame = Isometry3::identity();
        frames.push(frame);
        for (joint, &value) in self.joints.iter().zip(q) {
            frame = frame * joint.origin * joint.kind.motion(value);
            frames.push(frame);
        }
        frames
    }

    pub(crate) fn foot_pose_unchecked(&self, q: &[f64]) -> Isometry3<f64> {
        let frames = self.stage_frames(q);
        frames[frames.len() - 1] * self.foot_offset
    }

    pub(crate) fn foot_position_unchecked(&self, q: &[f64]) -> Point3<f64> {
        self.foot_pose_unchecked(q) * self.contact_centre
    }

    pub(crate) fn jacobian_unchecked(&self, q: &[f64]) -> Matrix3xX<f64> {
        let frames = self.stage_frames(q);
        let foot = frames[frames.len() - 1] * self.foot_offset * self.contact_centre;
        let mut jacobian = Matrix3xX::zeros(self.joints.len());
        for (i, joint) in self.joints.iter().enumerate() {
            let joint_frame = frames[i] * joint.origin;
            let axis = joint_frame.rotation * joint.kind.axis().into_inner();
            let column = match joint.kind {
                JointKind::Revolute { .. } => {
                    let at = Point3::from(joint_frame.translation.vector);
                    axis.cross(&(foot - at))
                }
                JointKind::Prismatic { .. } => axis,
            };
            jacobian.set_column(i, &column);
        }
        jacobian
    }

    /// An upper bound of the distance from [`base_position`](Self::base_position) to the
    /// foot position over all joint positions within the limits, metres: the sum of the
    /// joint offsets after the first joint, the longest prismatic extensions and the foot's
    /// offset. No target farther than this from the base can be reached.
    pub fn reach_bound(&self) -> f64 {
        let extensions: f64 = self
            .joints
            .iter()
            .filter(|j| matches!(j.kind, JointKind::Prismatic { .. }))
            .map(|j| j.limits.lower.abs().max(j.limits.upper.abs()))
            .sum();
        self.joint_offsets_m() + extensions + self.foot_offset_m()
    }

    /// The lengths of the offsets between successive joints (after the first), summed.
    fn joint_offsets_m(&self) -> f64 {
        self.joints
            .iter()
            .skip(1)
            .map(|j| j.origin.translation.vector.norm())
            .sum()
    }

    /// How far the contact-sphere centre is from the last joint's frame.
    fn foot_offset_m(&self) -> f64 {
        (self.foot_offset * self.contact_centre).coords.norm()
    }

    /// A length scale of the leg, metres: the sum of its joint offsets and prismatic
    /// travels, at least 1 mm. Sets the damping of the inverse kinematics.
    pub(crate) fn length_scale(&self) -> f64 {
        let travel: f64 = self
            .joints
            .iter()
            .filter(|j| matches!(j.kind, JointKind::Prismatic { .. }))
            .map(|j| j.limits.span())
            .sum();
        (self.joint_offsets_m() + travel + self.foot_offset_m()).max(1e-3)
    }
}
