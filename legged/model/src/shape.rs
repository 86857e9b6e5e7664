//! Collision shapes: the primitive solids of a link that must not hit the terrain.

use nalgebra::{Isometry3, Point3, Vector3};
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
    /// Points over a shape every `spacing` or closer, each with the radius of the ball about
    /// it that the checks keep clear of the ground: for a box, a lattice over its surface
    /// (radius 0); for a cylinder or capsule, points along its axis (its radius); for a
    /// sphere, its centre (its radius).
    pub fn surface_points(&self, spacing: f64) -> Vec<(Point3<f64>, f64)> {
        let steps = |len: f64| ((len / spacing).ceil() as usize).clamp(1, 40);
        match *self {
            Shape::Sphere { radius } => vec![(Point3::origin(), radius)],
            Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
                let n = steps(length);
                (0..=n)
                    .map(|i| {
                        let z = -length / 2.0 + length * i as f64 / n as f64;
                        (Point3::new(0.0, 0.0, z), radius)
                    })
                    .collect()
            }
            Shape::Box { size } => {
                let (nx, ny, nz) = (steps(size.x), steps(size.y), steps(size.z));
                let mut out = Vec::new();
                for i in 0..=nx {
                    for j in 0..=ny {
                        for k in 0..=nz {
                            let on_face =
                                i == 0 || i == nx || j == 0 || j == ny || k == 0 || k == nz;
                            if on_face {
                                out.push((
                                    Point3::new(
                                        -size.x / 2.0 + size.x * i as f64 / nx as f64,
                                        -size.y / 2.0 + size.y * j as f64 / ny as f64,
                                        -size.z / 2.0 + size.z * k as f64 / nz as f64,
                                    ),
                                    0.0,
                                ));
                            }
                        }
                    }
                }
                out
            }
        }
    }

    /// Whether a ball of radius `r` about `p` (shape frame) reaches into the shape.
    pub fn holds_ball(&self, p: &Point3<f64>, r: f64) -> bool {
        match *self {
            Shape::Sphere { radius } => p.coords.norm() < radius + r,
            Shape::Box { size } => {
                let h = size / 2.0;
                p.x.abs() < h.x + r && p.y.abs() < h.y + r && p.z.abs() < h.z + r
            }
            Shape::Cylinder { radius, length } => {
                p.x.hypot(p.y) < radius + r && p.z.abs() < length / 2.0 + r
            }
            Shape::Capsule { radius, length } => {
                let h = length / 2.0;
                let z = p.z.clamp(-h, h);
                (p.coords - Vector3::new(0.0, 0.0, z)).norm() < radius + r
            }
        }
    }

    /// Capsules (segment ends in the shape frame, radius) that together fill the shape
    /// closely: a sphere's or capsule's own; a cylinder's with its ends rounded inside it;
    /// for a box, capsules along its
    /// longest axis with the radius of half its thinnest side, side by side across the
    /// remaining side, ends rounded inside the box.
    pub fn capsules(&self) -> Vec<(Point3<f64>, Point3<f64>, f64)> {
        if let Shape::Cylinder { radius, length } = *self {
            // Ends rounded inside the cylinder (its flat ends' rims are cut).
            let h = (length / 2.0 - radius).max(0.0);
            return vec![(Point3::new(0.0, 0.0, -h), Point3::new(0.0, 0.0, h), radius)];
        }
        let Shape::Box { size } = *self else {
            return vec![self.capsule()];
        };
        let mut axes = [0usize, 1, 2];
        axes.sort_by(|&a, &b| size[b].total_cmp(&size[a]));
        let [long, wide, thin] = axes;
        let r = size[thin] / 2.0;
        let n = ((size[wide] / size[thin].max(1e-9)).ceil() as usize).max(1);
        let half_run = (size[long] / 2.0 - r).max(0.0);
        let spread = (size[wide] / 2.0 - r).max(0.0);
        (0..n)
            .map(|k| {
                let offset = if n == 1 {
                    0.0
                } else {
                    -spread + 2.0 * spread * k as f64 / (n - 1) as f64
                };
                let (mut a, mut b) = (Point3::origin(), Point3::origin());
                a[long] = -half_run;
                b[long] = half_run;
                a[wide] = offset;
                b[wide] = offset;
                (a, b, r)
            })
            .collect()
    }

    /// The capsule along the shape's longest axis that holds it: the segment's ends (shape
    /// frame) and its radius. A box's capsule has the radius of its cross-section's
    /// half-diagonal, its ends pulled in by as much.
    pub fn capsule(&self) -> (Point3<f64>, Point3<f64>, f64) {
        match *self {
            Shape::Sphere { radius } => (Point3::origin(), Point3::origin(), radius),
            Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
                let h = length / 2.0;
                (Point3::new(0.0, 0.0, -h), Point3::new(0.0, 0.0, h), radius)
            }
            Shape::Box { size } => {
                let axis = if size.x >= size.y && size.x >= size.z {
                    0
                } else if size.y >= size.z {
                    1
                } else {
                    2
                };
                let (mut a, mut b) = (Point3::origin(), Point3::origin());
                let mut across = 0.0_f64;
                for k in 0..3 {
                    if k == axis {
                        a[k] = -size[k] / 2.0;
                        b[k] = size[k] / 2.0;
                    } else {
                        across += (size[k] / 2.0).powi(2);
                    }
                }
                let r = across.sqrt();
                let shrink = r.min(size[axis] / 2.0);
                a[axis] += shrink;
                b[axis] -= shrink;
                (a, b, r)
            }
        }
    }

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
