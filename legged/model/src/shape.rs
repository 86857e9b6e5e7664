//! Collision shapes: the primitive solids of a link that must not hit the terrain.

use nalgebra::{Isometry3, Vector3};
use serde::{Deserialize, Serialize};

/// A primitive solid, centred on the origin of its own frame, with URDF's conventions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    /// A ball of this radius, metres.
    Sphere {
        /// Radius, metres.
        radius: f64,
    },
    /// A box with these edge lengths along its frame's x, y and z, metres.
    Box {
        /// Edge lengths along x, y and z, metres.
        size: Vector3<f64>,
    },
    /// A cylinder whose axis is its frame's z.
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Length along z, metres.
        length: f64,
    },
    /// A cylinder along its frame's z with a half ball on each end (URDF 1.2).
    Capsule {
        /// Radius of the cylinder and of the end balls, metres.
        radius: f64,
        /// Length of the cylindrical part along z, metres (the ends add a radius each).
        length: f64,
    },
}

impl Shape {
    /// The radius of the smallest ball about the shape's centre that holds the whole shape:
    /// a cheap first test before an exact one.
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            Shape::Sphere { radius } => radius,
            Shape::Box { size } => size.norm() / 2.0,
            Shape::Cylinder { radius, length } => radius.hypot(length / 2.0),
            Shape::Capsule { radius, length } => radius + length / 2.0,
        }
    }

    /// The shape's kind as URDF writes it: `sphere`, `box`, `cylinder` or `capsule`.
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "sphere",
            Shape::Box { .. } => "box",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Capsule { .. } => "capsule",
        }
    }

    /// How far the shape reaches below its centre along the body frame's -z when its frame
    /// has the given pose: the lowest point is at `pose.translation.z - depth_below(pose)`.
    pub fn depth_below(&self, pose: &Isometry3<f64>) -> f64 {
        // The world down direction expressed in the shape's own frame.
        let down = pose.rotation.inverse() * -Vector3::z();
        match *self {
            Shape::Sphere { radius } => radius,
            Shape::Box { size } => {
                (size.x * down.x.abs() + size.y * down.y.abs() + size.z * down.z.abs()) / 2.0
            }
            Shape::Cylinder { radius, length } => {
                let across = (down.x * down.x + down.y * down.y).sqrt();
                length / 2.0 * down.z.abs() + radius * across
            }
            Shape::Capsule { radius, length } => length / 2.0 * down.z.abs() + radius,
        }
    }
}

/// One `<collision>` of a link: a shape and its pose in the link's frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Collision {
    /// The solid.
    pub shape: Shape,
    /// The shape's frame in the link's frame (the `<origin>` of the `<collision>`).
    pub origin: Isometry3<f64>,
}

/// A collision shape placed in the body frame for some joint positions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlacedShape<'a> {
    /// The link the shape belongs to.
    pub link: &'a str,
    /// The solid.
    pub shape: Shape,
    /// The shape's frame in the body frame.
    pub pose: Isometry3<f64>,
}

impl PlacedShape<'_> {
    /// Height of the shape's lowest point in the body frame.
    pub fn lowest_z(&self) -> f64 {
        self.pose.translation.vector.z - self.shape.depth_below(&self.pose)
    }
}
