//! The checks every posture and every posture along a move must pass: static stability
//! by the triangle-area test over a support polygon shrunk toward its centre, no leg
//! touching another leg or the body, no link in the terrain.

use nalgebra::{Isometry3, Point2};
use tca_stability::Polygon;

use crate::robot::Robot;
use crate::terrain::Terrain;

/// Relative tolerance of the triangle-area test.
const AREA_TOLERANCE: f64 = 1e-9;

/// Whether `p` lies inside the convex polygon of the stance feet `feet` after each vertex
/// is moved `margin` toward the polygon's centroid: the triangles from `p` to every edge
/// add up to the polygon's area exactly when `p` is inside (the McGhee-Iswandhi test as
/// the paper uses it).
pub fn statically_stable(feet: &[Point2<f64>], p: Point2<f64>, margin: f64) -> bool {
    let Ok(hull) = Polygon::convex_hull(feet) else {
        return false;
    };
    if hull.is_degenerate() {
        return false;
    }
    let Some(c) = hull.centroid() else {
        return false;
    };
    let shrunk: Vec<Point2<f64>> = hull
        .vertices()
        .iter()
        .map(|v| {
            let d = c - v;
            let n = d.norm();
            if n <= margin { c } else { v + d * (margin / n) }
        })
        .collect();
    let area = polygon_area(&shrunk);
    if area <= 0.0 {
        return false;
    }
    let mut sum = 0.0;
    for k in 0..shrunk.len() {
        let (a, b) = (shrunk[k], shrunk[(k + 1) % shrunk.len()]);
        sum += triangle_area(a, b, p);
    }
    sum <= area * (1.0 + AREA_TOLERANCE)
}

fn triangle_area(a: Point2<f64>, b: Point2<f64>, c: Point2<f64>) -> f64 {
    ((b - a).perp(&(c - a)) / 2.0).abs()
}

fn polygon_area(v: &[Point2<f64>]) -> f64 {
    let mut s = 0.0;
    for k in 0..v.len() {
        let (a, b) = (v[k], v[(k + 1) % v.len()]);
        s += a.x * b.y - b.x * a.y;
    }
    (s / 2.0).abs()
}

/// The distance of `p` inside the support polygon of `feet` (negative outside), metres.
pub fn margin(feet: &[Point2<f64>], p: Point2<f64>) -> f64 {
    Polygon::convex_hull(feet).map_or(f64::NEG_INFINITY, |h| h.signed_distance(p))
}

/// The first collision between parts of the robot in a posture (joint positions per leg):
/// two legs' links whose bounding capsules overlap, or a leg's link beyond its first joint
/// inside the body's box (`tca_legged_model::RobotModel::self_contact`). `None` when there
/// is none.
pub fn self_collision(robot: &Robot, joints: &[Vec<f64>]) -> Option<String> {
    match robot.model().self_contact(joints) {
        Ok(contact) => contact.map(|c| c.to_string()),
        Err(e) => Some(e.to_string()),
    }
}

/// The first link of the robot below the ground in a posture (every collision shape's
/// points against the highest ground within their radius), `None` when every link is
/// clear. `poses` are the shapes' world poses (see [`Robot::shape_poses`]).
pub fn terrain_collision(
    robot: &Robot,
    terrain: &Terrain,
    poses: &[Isometry3<f64>],
    clearance: f64,
) -> Option<String> {
    for (probe, pose) in robot.probes.iter().zip(poses) {
        // The whole shape well above the highest ground under it needs no closer look.
        let c = pose.translation.vector;
        let reach = probe.bounding_radius;
        if c.z - reach - clearance > terrain.max_in_disc(Point2::new(c.x, c.y), reach) {
            continue;
        }
        for (pt, r) in &probe.points {
            let w = pose * pt;
            let ground = terrain.max_in_disc(Point2::new(w.x, w.y), *r);
            let gap = w.z - r - ground;
            if gap < clearance {
                return Some(format!(
                    "link `{}` comes {gap:.3} m from the ground",
                    probe.link
                ));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn square() -> Vec<Point2<f64>> {
        vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
        ]
    }

    #[test]
    fn stability_shrinks_the_polygon() {
        let f = square();
        assert!(statically_stable(&f, Point2::new(0.5, 0.5), 0.1));
        assert!(statically_stable(&f, Point2::new(0.05, 0.5), 0.0));
        assert!(!statically_stable(&f, Point2::new(0.05, 0.05), 0.1));
        assert!(!statically_stable(&f, Point2::new(1.5, 0.5), 0.0));
        // Two feet give no support.
        assert!(!statically_stable(&f[..2], Point2::new(0.5, 0.0), 0.0));
    }

    proptest! {
        #[test]
        fn area_test_agrees_with_the_distance_test(x in -0.5..1.5f64, y in -0.5..1.5f64) {
            let f = square();
            let p = Point2::new(x, y);
            let d = margin(&f, p);
            // Shrinking a square's corners toward its centre by m moves its edges in by
            // m / sqrt(2).
            let m = 0.1;
            let inner = d - m / std::f64::consts::SQRT_2;
            if inner.abs() > 1e-6 {
                prop_assert_eq!(statically_stable(&f, p, m), inner > 0.0);
            }
        }

    }
}
