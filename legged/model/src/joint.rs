//! The moving joints of a leg: how each moves, where it sits and how far it may go.

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// How a leg joint moves, about or along an axis given in the joint's own frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum JointKind {
    /// Turns about the axis (right-handed); its position is an angle in radians.
    Revolute {
        /// The unit axis in the joint frame.
        axis: Unit<Vector3<f64>>,
    },
    /// Slides along the axis; its position is a distance in metres.
    Prismatic {
        /// The unit axis in the joint frame.
        axis: Unit<Vector3<f64>>,
    },
}

impl JointKind {
    /// The unit axis in the joint frame.
    pub fn axis(&self) -> Unit<Vector3<f64>> {
        match *self {
            JointKind::Revolute { axis } | JointKind::Prismatic { axis } => axis,
        }
    }

    /// The unit of the joint's position: `rad` or `m`.
    pub fn unit(&self) -> &'static str {
        match self {
            JointKind::Revolute { .. } => "rad",
            JointKind::Prismatic { .. } => "m",
        }
    }

    /// The URDF name of the joint type: `revolute` or `prismatic`.
    pub fn urdf_name(&self) -> &'static str {
        match self {
            JointKind::Revolute { .. } => "revolute",
            JointKind::Prismatic { .. } => "prismatic",
        }
    }

    /// The motion of the child frame in the joint frame at this joint position.
    pub fn motion(&self, position: f64) -> Isometry3<f64> {
        match *self {
            JointKind::Revolute { axis } => Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_axis_angle(&axis, position),
            ),
            JointKind::Prismatic { axis } => Isometry3::from_parts(
                Translation3::from(axis.into_inner() * position),
                UnitQuaternion::identity(),
            ),
        }
    }
}

/// The `<limit>` of a moving joint, in the joint's unit (radians or metres).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JointLimits {
    /// Lowest position.
    pub lower: f64,
    /// Highest position, not below `lower`.
    pub upper: f64,
    /// Top speed, per second, above 0.
    pub velocity: f64,
    /// Top torque (N m) or force (N), as the file gives it; 0 when the file gives none.
    pub effort: f64,
}

impl JointLimits {
    /// Whether a position lies within `[lower, upper]`.
    pub fn contains(&self, position: f64) -> bool {
        (self.lower..=self.upper).contains(&position)
    }

    /// The nearest position within `[lower, upper]`.
    pub fn clamp(&self, position: f64) -> f64 {
        position.clamp(self.lower, self.upper)
    }

    /// The width of the range, `upper - lower`.
    pub fn span(&self) -> f64 {
        self.upper - self.lower
    }

    /// The middle of the range.
    pub fn middle(&self) -> f64 {
        (self.lower + self.upper) / 2.0
    }
}

/// A moving joint of a leg.
///
/// Fixed joints of the file do not appear: their transforms are folded into [`origin`]
/// (those before the joint) or into the leg's foot offset (those after the last one).
///
/// [`origin`]: LegJoint::origin
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LegJoint {
    pub(crate) name: String,
    pub(crate) kind: JointKind,
    pub(crate) origin: Isometry3<f64>,
    pub(crate) limits: JointLimits,
    pub(crate) child_link: String,
}

impl LegJoint {
    /// The joint's name in the file.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// How it moves, and about or along which axis.
    pub fn kind(&self) -> JointKind {
        self.kind
    }

    /// The joint frame in the frame of the leg's previous moving joint's child (the body
    /// frame for the first joint), with any fixed joints in between folded in. For a joint
    /// right after another one this is the joint's own URDF `<origin>`.
    pub fn origin(&self) -> &Isometry3<f64> {
        &self.origin
    }

    /// Its limits.
    pub fn limits(&self) -> JointLimits {
        self.limits
    }

    /// The link it moves (its URDF child).
    pub fn child_link(&self) -> &str {
        &self.child_link
    }
}
