//! Frames: the carriage pose on the rails and the transforms between the carriage frame,
//! the world frame and the scanner frame. See the crate docs for the frame definitions.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::params::{CarriageParams, ScannerMount};

/// Pose of the carriage: its position along the rails and its small rotations about the
/// world X (roll) and Y (pitch) axes, as the inclinometers read them. Its world X and height
/// are fixed ([`CarriageParams`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CarriagePose {
    /// Position along the rails (world Y), metres.
    pub y_m: f64,
    /// Rotation about world X, radians.
    pub roll_rad: f64,
    /// Rotation about world Y, radians.
    pub pitch_rad: f64,
}

impl CarriagePose {
    /// A level carriage at `y_m`.
    pub fn level(y_m: f64) -> Self {
        Self {
            y_m,
            roll_rad: 0.0,
            pitch_rad: 0.0,
        }
    }

    /// World origin of the carriage frame (the shoulder column at the links' height).
    pub fn origin_world(&self, carriage: &CarriageParams) -> Point3<f64> {
        Point3::new(carriage.x_m, self.y_m, carriage.link_plane_height_m)
    }

    /// The transform taking carriage-frame coordinates to world coordinates:
    /// `p_W = origin + Ry(pitch) Rx(roll) p_C`.
    pub fn world_from_carriage(&self, carriage: &CarriageParams) -> Isometry3<f64> {
        let rotation = UnitQuaternion::from_euler_angles(self.roll_rad, self.pitch_rad, 0.0);
        let origin = self.origin_world(carriage);
        Isometry3::from_parts(Translation3::new(origin.x, origin.y, origin.z), rotation)
    }

    /// Maps a carriage-frame point to the world frame.
    pub fn to_world(&self, carriage: &CarriageParams, p_carriage: &Point3<f64>) -> Point3<f64> {
        self.world_from_carriage(carriage) * p_carriage
    }

    /// Maps a world point to the carriage frame.
    pub fn to_carriage(&self, carriage: &CarriageParams, p_world: &Point3<f64>) -> Point3<f64> {
        self.world_from_carriage(carriage)
            .inverse_transform_point(p_world)
    }

    /// Maps a carriage-frame vector (a direction or a force) to the world frame.
    pub fn vector_to_world(&self, carriage: &CarriageParams, v: &Vector3<f64>) -> Vector3<f64> {
        self.world_from_carriage(carriage) * v
    }
}

impl ScannerMount {
    /// The transform taking scanner-frame coordinates to carriage coordinates:
    /// `Trans(position) Rz(pi/2 + yaw) Ry(pitch_down) Rx(roll)`. The scanner frame has +X
    /// along the boresight, +Y to the left, +Z up.
    pub fn carriage_from_scanner(&self) -> Isometry3<f64> {
        let rz = UnitQuaternion::from_axis_angle(
            &Vector3::z_axis(),
            std::f64::consts::FRAC_PI_2 + self.yaw_rad,
        );
        let ry = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), self.pitch_down_rad);
        let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), self.roll_rad);
        let [x, y, z] = self.position_m;
        Isometry3::from_parts(Translation3::new(x, y, z), rz * ry * rx)
    }

    /// The transform taking scanner-frame coordinates to world coordinates for a carriage pose.
    pub fn world_from_scanner(
        &self,
        carriage: &CarriageParams,
        pose: &CarriagePose,
    ) -> Isometry3<f64> {
        pose.world_from_carriage(carriage) * self.carriage_from_scanner()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LegParams;

    #[test]
    fn level_carriage_translates_only() {
        let p = LegParams::default();
        let pose = CarriagePose::level(2.0);
        let w = pose.to_world(&p.carriage, &Point3::new(1.0, 0.5, -3.5));
        assert!((w - Point3::new(4.0, 2.5, 0.5)).norm() < 1e-12);
        let back = pose.to_carriage(&p.carriage, &w);
        assert!((back - Point3::new(1.0, 0.5, -3.5)).norm() < 1e-12);
    }

    #[test]
    fn scanner_looks_forward_and_down() {
        let p = LegParams::default();
        let t = p
            .scanner
            .world_from_scanner(&p.carriage, &CarriagePose::level(1.0));
        let boresight = t * Vector3::x();
        assert!(boresight.y > 0.3, "looks forward: {boresight}");
        assert!(boresight.z < -0.3, "looks down: {boresight}");
        assert!(boresight.x.abs() < 1e-9);
        let left = t * Vector3::y();
        assert!(
            left.x < -0.99,
            "scanner +Y is world -X (left when facing +Y): {left}"
        );
        let origin = t * Point3::origin();
        assert!((origin - Point3::new(3.0, 1.5, 4.5)).norm() < 1e-12);
    }
}
