//! Small conversions between nalgebra and Foxglove's geometry types.

use foxglove::messages::{Color, Point3, Pose, Quaternion, Timestamp, Vector3};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};

/// A Foxglove timestamp from nanoseconds since the UNIX epoch (saturating past 2106).
pub fn timestamp(at_ns: u64) -> Timestamp {
    let sec = u32::try_from(at_ns / 1_000_000_000).unwrap_or(u32::MAX);
    Timestamp::new(sec, (at_ns % 1_000_000_000) as u32)
}

/// A Foxglove vector.
pub fn vector(x: f64, y: f64, z: f64) -> Vector3 {
    Vector3 { x, y, z }
}

/// A Foxglove point.
pub fn point(x: f64, y: f64, z: f64) -> Point3 {
    Point3 { x, y, z }
}

/// A Foxglove quaternion from nalgebra's.
pub fn quaternion(q: &UnitQuaternion<f64>) -> Quaternion {
    Quaternion {
        x: q.i,
        y: q.j,
        z: q.k,
        w: q.w,
    }
}

/// A Foxglove pose from an isometry.
pub fn pose(iso: &Isometry3<f64>) -> Pose {
    let t = iso.translation.vector;
    Pose {
        position: Some(vector(t.x, t.y, t.z)),
        orientation: Some(quaternion(&iso.rotation)),
    }
}

/// A pose at a point with no rotation.
pub fn at(x: f64, y: f64, z: f64) -> Pose {
    pose(&Isometry3::translation(x, y, z))
}

/// A colour, components in 0..=1.
pub fn color(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

/// A rigid transform from a row-major homogeneous 4 x 4 matrix; the rotation part is
/// re-orthonormalised. `None` when an entry is not finite.
pub fn isometry_from_row_major(m: &[f64; 16]) -> Option<Isometry3<f64>> {
    if m.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
    let rotation = Rotation3::from_matrix(&r);
    Some(Isometry3::from_parts(
        Translation3::new(m[3], m[7], m[11]),
        UnitQuaternion::from_rotation_matrix(&rotation),
    ))
}

/// The body pose of roll, pitch and yaw (about X, Y, Z, applied in that order).
pub fn rpy_pose(x: f64, y: f64, z: f64, roll: f64, pitch: f64, yaw: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    )
}

/// The convex hull of points on the ground plane, counter-clockwise (Andrew's monotone
/// chain); fewer than three distinct points come back as they are.
pub fn convex_hull(points: &[(f64, f64, f64)]) -> Vec<(f64, f64, f64)> {
    let mut p: Vec<(f64, f64, f64)> = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup_by(|a, b| a.0 == b.0 && a.1 == b.1);
    if p.len() < 3 {
        return p;
    }
    let cross = |o: &(f64, f64, f64), a: &(f64, f64, f64), b: &(f64, f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64, f64)> = Vec::with_capacity(p.len() * 2);
    for q in &p {
        while hull.len() >= 2 && cross(&hull[hull.len() - 2], &hull[hull.len() - 1], q) <= 0.0 {
            hull.pop();
        }
        hull.push(*q);
    }
    let lower = hull.len() + 1;
    for q in p.iter().rev().skip(1) {
        while hull.len() >= lower && cross(&hull[hull.len() - 2], &hull[hull.len() - 1], q) <= 0.0 {
            hull.pop();
        }
        hull.push(*q);
    }
    hull.pop();
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hull_of_a_square_with_a_point_inside_is_the_square() {
        let pts = [
            (0.0, 0.0, 0.0),
            (1.0, 0.0, 0.0),
            (0.5, 0.5, 0.0),
            (1.0, 1.0, 0.0),
            (0.0, 1.0, 0.0),
        ];
        let hull = convex_hull(&pts);
        assert_eq!(hull.len(), 4);
        assert!(!hull.contains(&(0.5, 0.5, 0.0)));
    }

    #[test]
    fn a_row_major_matrix_becomes_its_rigid_transform() {
        // 90 degrees about Z, then a translation.
        let m = [
            0.0, -1.0, 0.0, 1.0, //
            1.0, 0.0, 0.0, 2.0, //
            0.0, 0.0, 1.0, 3.0, //
            0.0, 0.0, 0.0, 1.0,
        ];
        let iso = isometry_from_row_major(&m).unwrap();
        let p = iso * nalgebra::Point3::new(1.0, 0.0, 0.0);
        assert!((p - nalgebra::Point3::new(1.0, 3.0, 3.0)).norm() < 1e-12);
        let mut bad = m;
        bad[0] = f64::NAN;
        assert!(isometry_from_row_major(&bad).is_none());
    }

    #[test]
    fn timestamps_split_seconds_and_nanoseconds() {
        let t = timestamp(3_000_000_007);
        assert_eq!((t.sec(), t.nsec()), (3, 7));
    }
}
