//! Body poses and postures: where the body is and where every foot stands.

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

/// The body's pose in the world: position of its origin and roll, pitch, yaw (extrinsic
/// X-Y-Z, as `UnitQuaternion::from_euler_angles`). Metres and radians.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyPose {
    /// World X, metres.
    pub x: f64,
    /// World Y, metres.
    pub y: f64,
    /// World Z, metres.
    pub z: f64,
    /// Roll about the body's x, radians.
    pub roll: f64,
    /// Pitch about the body's y, radians (positive tips the nose down).
    pub pitch: f64,
    /// Yaw about world Z, radians (0 faces +X).
    pub yaw: f64,
}

impl BodyPose {
    /// The pose as an isometry from the body frame to the world.
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.x, self.y, self.z),
            UnitQuaternion::from_euler_angles(self.roll, self.pitch, self.yaw),
        )
    }

    /// The pose of an isometry (angles from its rotation's Euler angles).
    pub fn from_isometry(iso: &Isometry3<f64>) -> BodyPose {
        let (roll, pitch, yaw) = iso.rotation.euler_angles();
        let t = iso.translation.vector;
        BodyPose {
            x: t.x,
            y: t.y,
            z: t.z,
            roll,
            pitch,
            yaw,
        }
    }

    /// Where the body is over the ground.
    pub fn xy(&self) -> Point2<f64> {
        Point2::new(self.x, self.y)
    }

    /// The pose a fraction `t` (0..=1) of the way from `self` to `to`: position along the
    /// straight line, each angle changed linearly (yaw the short way round).
    pub fn lerp(&self, to: &BodyPose, t: f64) -> BodyPose {
        let l = |a: f64, b: f64| a + (b - a) * t;
        BodyPose {
            x: l(self.x, to.x),
            y: l(self.y, to.y),
            z: l(self.z, to.z),
            roll: l(self.roll, to.roll),
            pitch: l(self.pitch, to.pitch),
            yaw: self.yaw + wrap(to.yaw - self.yaw) * t,
        }
    }
}

/// An angle brought into (-π, π].
pub fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut r = a.rem_euclid(t);
    if r > std::f64::consts::PI {
        r -= t;
    }
    r
}

/// A configuration of the robot: a body pose, a foothold for every leg and the joint
/// positions that put the feet there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Posture {
    /// The body's pose.
    pub body: BodyPose,
    /// Each foot's contact-sphere centre in the world, one per leg.
    pub feet: Vec<Point3<f64>>,
    /// Joint positions of every leg.
    pub joints: Vec<Vec<f64>>,
    /// The centre of mass (legs included) in the world.
    pub com: Point3<f64>,
    /// Distance of the centre of mass's ground projection inside the support polygon of
    /// all the feet, metres.
    pub margin_m: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn isometry_round_trips(x in -5.0..5.0f64, roll in -0.5..0.5f64, pitch in -0.5..0.5f64, yaw in -3.0..3.0f64) {
            let p = BodyPose { x, y: -x, z: 0.1, roll, pitch, yaw };
            let q = BodyPose::from_isometry(&p.isometry());
            prop_assert!((q.roll - roll).abs() < 1e-9);
            prop_assert!((q.pitch - pitch).abs() < 1e-9);
            prop_assert!(wrap(q.yaw - yaw).abs() < 1e-9);
        }

        #[test]
        fn lerp_ends_at_both_poses(a in -3.0..3.0f64, b in -3.0..3.0f64) {
            let p = BodyPose { x: 0.0, y: 0.0, z: 0.1, roll: 0.0, pitch: 0.1, yaw: a };
            let q = BodyPose { x: 1.0, y: 2.0, z: 0.2, roll: 0.1, pitch: 0.0, yaw: b };
            prop_assert_eq!(p.lerp(&q, 0.0), p);
            let end = p.lerp(&q, 1.0);
            prop_assert!(wrap(end.yaw - b).abs() < 1e-9);
            prop_assert!((end.x - 1.0).abs() < 1e-12);
            // Yaw takes the short way: never more than half a turn from either end.
            prop_assert!(wrap(p.lerp(&q, 0.5).yaw - a).abs() <= std::f64::consts::PI / 2.0 + 1e-9);
        }
    }
}
