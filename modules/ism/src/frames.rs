//! The transform chain an image is tagged with (§5.2.1):
//! `locus <- scanner <- body <- global`, i.e. `L_T_G = L_T_S * S_T_B * B_T_G`.
//!
//! - **Global** G: the world frame (see `tca-robot`).
//! - **Body** B: the carriage frame; `B_T_G` is the inverse of the carriage pose the
//!   Controller reports at acquisition.
//! - **Scanner** S: +X along the boresight, +Y left, +Z up; `S_T_B` is the calibration
//!   (configurable, estimated by [`crate::calibration`]).
//! - **Locus** L: the frame the pixel rays are defined in ([`crate::spec`]); `L_T_S` is
//!   fixed (identity unless the mirrors' centre is offset from the scanner frame).
//!
//! On the wire a transform is a row-major 4 x 4 homogeneous matrix ([`Transform`]); `A_T_B`
//! maps coordinates in B to coordinates in A.

use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};
use tca_robot::CarriagePose;
use tca_robot::params::CarriageParams;
use tca_single_leg_messages::{BodyPose, RangeImage, Transform};

use crate::error::{IsmError, Result};

/// Largest deviation from orthonormality accepted in a wire rotation.
const ROTATION_TOLERANCE: f64 = 1e-6;

/// A rigid transform as a wire [`Transform`].
pub fn to_wire(t: &Isometry3<f64>) -> Transform {
    let m: Matrix4<f64> = t.to_homogeneous();
    let mut out = [0.0; 16];
    for (i, slot) in out.iter_mut().enumerate() {
        *slot = m[(i / 4, i % 4)];
    }
    Transform { m: out }
}

/// A wire [`Transform`] as a rigid transform; fails if it is not one (non-finite entries, a
/// bottom row other than `0 0 0 1`, or a rotation part that is not a proper rotation).
pub fn from_wire(which: &'static str, t: &Transform) -> Result<Isometry3<f64>> {
    let bad = |reason: String| IsmError::BadTransform { which, reason };
    if let Some(v) = t.m.iter().find(|v| !v.is_finite()) {
        return Err(bad(format!("it contains {v}")));
    }
    let bottom = [t.m[12], t.m[13], t.m[14], t.m[15]];
    if bottom != [0.0, 0.0, 0.0, 1.0] {
        return Err(bad(format!(
            "its bottom row is {bottom:?}, not [0, 0, 0, 1]"
        )));
    }
    let r = Matrix3::new(
        t.m[0], t.m[1], t.m[2], t.m[4], t.m[5], t.m[6], t.m[8], t.m[9], t.m[10],
    );
    let off = (r.transpose() * r - Matrix3::identity()).abs().max();
    if off > ROTATION_TOLERANCE || r.determinant() <= 0.0 {
        return Err(bad(format!(
            "its 3 x 3 part is not a rotation (|R^T R - I| = {off:.2e}, det = {:.6})",
            r.determinant()
        )));
    }
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    Ok(Isometry3::from_parts(
        Translation3::new(t.m[3], t.m[7], t.m[11]),
        rotation,
    ))
}

/// The carriage pose of a wire [`BodyPose`].
pub fn carriage_pose(pose: &BodyPose) -> CarriagePose {
    CarriagePose {
        y_m: pose.y_m,
        roll_rad: pose.roll_rad,
        pitch_rad: pose.pitch_rad,
    }
}

/// `B_T_G` for a carriage pose: maps world coordinates to carriage coordinates.
pub fn body_from_global(carriage: &CarriageParams, pose: &CarriagePose) -> Isometry3<f64> {
    pose.world_from_carriage(carriage).inverse()
}

/// The three transforms of an image, decoded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageFrames {
    /// `L_T_S`.
    pub locus_from_scanner: Isometry3<f64>,
    /// `S_T_B`.
    pub scanner_from_body: Isometry3<f64>,
    /// `B_T_G`.
    pub body_from_global: Isometry3<f64>,
}

impl ImageFrames {
    /// Decodes an image's transforms.
    pub fn of(image: &RangeImage) -> Result<Self> {
        Ok(Self {
            locus_from_scanner: from_wire("locus <- scanner", &image.locus_from_scanner)?,
            scanner_from_body: from_wire("scanner <- body", &image.scanner_from_body)?,
            body_from_global: from_wire("body <- global", &image.body_from_global)?,
        })
    }

    /// `L_T_G = L_T_S * S_T_B * B_T_G`.
    pub fn locus_from_global(&self) -> Isometry3<f64> {
        self.locus_from_scanner * self.scanner_from_body * self.body_from_global
    }

    /// `G_T_L`: maps a pixel's locus-frame point to the world.
    pub fn global_from_locus(&self) -> Isometry3<f64> {
        self.locus_from_global().inverse()
    }

    /// Where the carriage (body frame origin) was at acquisition, world frame.
    pub fn body_origin_world(&self) -> Vector3<f64> {
        self.body_from_global.inverse().translation.vector
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_robot::LegParams;

    #[test]
    fn wire_round_trip_is_exact_enough() {
        let t = Isometry3::from_parts(
            Translation3::new(1.0, -2.0, 3.5),
            UnitQuaternion::from_euler_angles(0.1, -0.4, 2.0),
        );
        let back = from_wire("t", &to_wire(&t)).unwrap();
        assert!((back.to_homogeneous() - t.to_homogeneous()).abs().max() < 1e-12);
    }

    #[test]
    fn non_rigid_transforms_are_refused_with_a_reason() {
        let mut w = to_wire(&Isometry3::identity());
        w.m[0] = 2.0;
        let e = from_wire("scanner <- body", &w).unwrap_err().to_string();
        assert!(
            e.contains("scanner <- body") && e.contains("not a rotation"),
            "{e}"
        );
        let mut w = to_wire(&Isometry3::identity());
        w.m[3] = f64::NAN;
        assert!(from_wire("x", &w).is_err());
        let mut w = to_wire(&Isometry3::identity());
        w.m[14] = 1.0;
        assert!(from_wire("x", &w).is_err());
    }

    #[test]
    fn chain_maps_the_scanner_origin_to_its_mount() {
        let p = LegParams::default();
        let pose = CarriagePose::level(2.0);
        let frames = ImageFrames {
            locus_from_scanner: Isometry3::identity(),
            scanner_from_body: p.scanner.carriage_from_scanner().inverse(),
            body_from_global: body_from_global(&p.carriage, &pose),
        };
        let origin = frames.global_from_locus() * nalgebra::Point3::origin();
        let expected =
            p.scanner.world_from_scanner(&p.carriage, &pose) * nalgebra::Point3::origin();
        assert!((origin - expected).norm() < 1e-12);
        assert!((frames.body_origin_world() - Vector3::new(3.0, 2.0, 4.0)).norm() < 1e-12);
    }
}
