//! Turning the URDF reader's elements into checked values: poses, joint motions and limits,
//! masses and collision shapes. Each check refuses with the element's name and the reason.

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use urdf_rs::{Geometry, JointType};

use crate::error::{JointProblem, LinkProblem, ModelError};
use crate::joint::{JointKind, JointLimits};
use crate::shape::{Collision, Shape};

/// A URDF `<origin>` as a rigid transform, or `None` when a value is not finite.
///
/// `rpy` is roll about x, then pitch about y, then yaw about z, all about the fixed axes,
/// which is `Rz(yaw) Ry(pitch) Rx(roll)`.
pub(crate) fn pose(origin: &urdf_rs::Pose) -> Option<Isometry3<f64>> {
    let [x, y, z] = *origin.xyz;
    let [roll, pitch, yaw] = *origin.rpy;
    if ![x, y, z, roll, pitch, yaw].iter().all(|v| v.is_finite()) {
        return None;
    }
    Some(Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    ))
}

/// A joint as this crate sees it: its origin and, for a moving joint, its motion and limits.
#[derive(Debug, Clone)]
pub(crate) struct JointSpec {
    pub(crate) name: String,
    pub(crate) parent: String,
    pub(crate) child: String,
    pub(crate) origin: Isometry3<f64>,
    /// `None` for a fixed joint.
    pub(crate) motion: Option<(JointKind, JointLimits)>,
}

fn joint_error(joint: &urdf_rs::Joint, problem: JointProblem) -> ModelError {
    ModelError::Joint {
        joint: joint.name.clone(),
        problem,
    }
}

/// Checks one joint on its own: its type, axis, limits and numbers.
pub(crate) fn joint(joint: &urdf_rs::Joint) -> Result<JointSpec, ModelError> {
    let fail = |problem| joint_error(joint, problem);
    let moving = match joint.joint_type {
        JointType::Fixed => None,
        JointType::Revolute => Some("revolute"),
        JointType::Prismatic => Some("prismatic"),
        JointType::Continuous => return Err(fail(JointProblem::Continuous)),
        JointType::Floating => return Err(fail(JointProblem::Unsupported { kind: "floating" })),
        JointType::Planar => return Err(fail(JointProblem::Unsupported { kind: "planar" })),
        JointType::Spherical => {
            return Err(fail(JointProblem::Unsupported { kind: "spherical" }));
        }
    };
    let origin = pose(&joint.origin).ok_or_else(|| {
        fail(JointProblem::NotFinite {
            what: "origin (xyz or rpy)",
        })
    })?;
    let motion = match moving {
        None => None,
        Some(kind_name) => {
            if let Some(mimic) = &joint.mimic {
                return Err(fail(JointProblem::Mimic {
                    of: mimic.joint.clone(),
                }));
            }
            let [x, y, z] = *joint.axis.xyz;
            let axis = Vector3::new(x, y, z);
            let norm = axis.norm();
            if !norm.is_finite() || norm < 1e-9 {
                return Err(fail(JointProblem::BadAxis { x, y, z }));
            }
            let axis = Unit::new_normalize(axis);
            let kind = if kind_name == "revolute" {
                JointKind::Revolute { axis }
            } else {
                JointKind::Prismatic { axis }
            };
            let limits = limits(&joint.limit, kind_name).map_err(fail)?;
            Some((kind, limits))
        }
    };
    Ok(JointSpec {
        name: joint.name.clone(),
        parent: joint.parent.link.clone(),
        child: joint.child.link.clone(),
        origin,
        motion,
    })
}

fn limits(limit: &urdf_rs::JointLimit, kind: &'static str) -> Result<JointLimits, JointProblem> {
    let urdf_rs::JointLimit {
        lower,
        upper,
        effort,
        velocity,
        ..
    } = *limit;
    // Without <limit>, the reader gives every value as 0: a joint that cannot move.
    if lower == 0.0 && upper == 0.0 && velocity == 0.0 && effort == 0.0 {
        return Err(JointProblem::MissingLimits { kind });
    }
    if !lower.is_finite() || !upper.is_finite() {
        return Err(JointProblem::UnboundedLimits { lower, upper });
    }
    if lower > upper {
        return Err(JointProblem::LowerAboveUpper { lower, upper });
    }
    if velocity == 0.0 {
        return Err(JointProblem::ZeroVelocity);
    }
    if !(velocity.is_finite() && velocity > 0.0) {
        return Err(JointProblem::BadVelocity { velocity });
    }
    if effort.is_nan() || effort < 0.0 {
        return Err(JointProblem::BadEffort { effort });
    }
    Ok(JointLimits {
        lower,
        upper,
        velocity,
        effort,
    })
}

/// A link as this crate sees it, before it is placed on the body or a leg.
#[derive(Debug, Clone)]
pub(crate) struct LinkSpec {
    pub(crate) name: String,
    pub(crate) mass: f64,
    pub(crate) centre_of_mass: Point3<f64>,
    pub(crate) collisions: Vec<Collision>,
}

/// Checks one link on its own: its mass and its collision shapes (meshes are refused).
pub(crate) fn link(link: &urdf_rs::Link) -> Result<LinkSpec, ModelError> {
    let fail = |problem| ModelError::Link {
        link: link.name.clone(),
        problem,
    };
    let mass = link.inertial.mass.value;
    if !mass.is_finite() || mass < 0.0 {
        return Err(fail(LinkProblem::BadMass { mass }));
    }
    let [x, y, z] = *link.inertial.origin.xyz;
    if ![x, y, z].iter().all(|v| v.is_finite()) {
        return Err(fail(LinkProblem::NotFinite {
            what: "inertial origin",
        }));
    }
    let mut collisions = Vec::with_capacity(link.collision.len());
    for collision in &link.collision {
        let shape = shape(&collision.geometry).map_err(fail)?;
        let origin = pose(&collision.origin).ok_or_else(|| {
            fail(LinkProblem::NotFinite {
                what: "collision origin",
            })
        })?;
        collisions.push(Collision { shape, origin });
    }
    Ok(LinkSpec {
        name: link.name.clone(),
        mass,
        centre_of_mass: Point3::new(x, y, z),
        collisions,
    })
}

fn positive(shape: &'static str, what: &'static str, value: f64) -> Result<f64, LinkProblem> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(LinkProblem::BadShape { shape, what, value })
    }
}

fn shape(geometry: &Geometry) -> Result<Shape, LinkProblem> {
    Ok(match geometry {
        Geometry::Sphere { radius } => Shape::Sphere {
            radius: positive("sphere", "radius", *radius)?,
        },
        Geometry::Box { size } => {
            let [x, y, z] = **size;
            Shape::Box {
                size: Vector3::new(
                    positive("box", "size x", x)?,
                    positive("box", "size y", y)?,
                    positive("box", "size z", z)?,
                ),
            }
        }
        Geometry::Cylinder { radius, length } => Shape::Cylinder {
            radius: positive("cylinder", "radius", *radius)?,
            length: positive("cylinder", "length", *length)?,
        },
        Geometry::Capsule { radius, length } => Shape::Capsule {
            radius: positive("capsule", "radius", *radius)?,
            length: positive("capsule", "length", *length)?,
        },
        Geometry::Mesh { filename, .. } => {
            return Err(LinkProblem::MeshCollision {
                filename: filename.clone(),
            });
        }
    })
}
