//! Conversions between nalgebra's types and the bus's poses and points.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use tca_legged_messages::{Pose, WorldPoint};

/// The isometry of a pose: translation, then roll, pitch and yaw about X, Y and Z (the yaw
/// applied last).
pub fn pose_to_isometry(pose: &Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(pose.x_m, pose.y_m, pose.z_m),
        UnitQuaternion::from_euler_angles(pose.roll_rad, pose.pitch_rad, pose.yaw_rad),
    )
}

/// The pose of an isometry (roll, pitch, yaw as [`pose_to_isometry`] takes them).
pub fn isometry_to_pose(iso: &Isometry3<f64>) -> Pose {
    let (roll, pitch, yaw) = iso.rotation.euler_angles();
    let t = iso.translation.vector;
    Pose {
        x_m: t.x,
        y_m: t.y,
        z_m: t.z,
        roll_rad: roll,
        pitch_rad: pitch,
        yaw_rad: yaw,
    }
}

/// A world point as the bus writes it.
pub fn world_point(p: &Point3<f64>) -> WorldPoint {
    WorldPoint {
        x_m: p.x,
        y_m: p.y,
        z_m: p.z,
    }
}

/// Whether every number of an isometry is finite.
pub(crate) fn is_finite(iso: &Isometry3<f64>) -> bool {
    iso.translation.vector.iter().all(|v| v.is_finite())
        && iso.rotation.coords.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_round_trips() {
        let p = Pose {
            x_m: 1.0,
            y_m: -2.0,
            z_m: 3.0,
            roll_rad: 0.1,
            pitch_rad: -0.2,
            yaw_rad: 2.5,
        };
        let back = isometry_to_pose(&pose_to_isometry(&p));
        for (a, b) in p.to_array().iter().zip(back.to_array()) {
            assert!((a - b).abs() < 1e-12, "{p:?} {back:?}");
        }
        // Yaw last: body x of a pure yaw of 90 degrees points north.
        let iso = pose_to_isometry(&Pose {
            yaw_rad: std::f64::consts::FRAC_PI_2,
            ..p
        });
        let x = iso.rotation * nalgebra::Vector3::x();
        assert!(x.y > 0.9);
    }
}
