//! The checks every posture and every posture along a move must pass: static stability
//! by the triangle-area test over a support polygon shrunk toward its centre, no leg
//! touching another leg or the body, no link in the terrain.

use nalgebra::{Isometry3, Point2, Point3};
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

/// The closest distance between segments `a0 a1` and `b0 b1`.
pub fn segment_distance(a0: Point3<f64>, a1: Point3<f64>, b0: Point3<f64>, b1: Point3<f64>) -> f64 {
    let (d1, d2, r) = (a1 - a0, b1 - b0, a0 - b0);
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let eps = 1e-12;
    let (s, t);
    if a <= eps && e <= eps {
        return r.norm();
    }
    if a <= eps {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= eps {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > eps {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    ((a0 + d1 * s) - (b0 + d2 * t)).norm()
}

/// A leg (or the body), a segment's two ends and a radius.
type Capsule = (Option<usize>, Point3<f64>, Point3<f64>, f64);

/// The first collision between parts of the robot in a posture: two legs' links closer
/// than their capsules allow, or a leg's link inside the body's box (the first joint's
/// link, which is fixed to the body, excepted). `None` when there is none.
pub fn self_collision(robot: &Robot, poses: &[Isometry3<f64>], clearance: f64) -> Option<String> {
    let capsules: Vec<Capsule> = robot
        .probes
        .iter()
        .zip(poses)
        .map(|(p, pose)| (p.leg, pose * p.capsule.0, pose * p.capsule.1, p.capsule.2))
        .collect();
    for (i, a) in capsules.iter().enumerate() {
        let Some(la) = a.0 else { continue };
        for (j, b) in capsules.iter().enumerate().skip(i + 1) {
            let Some(lb) = b.0 else { continue };
            if la == lb {
                continue;
            }
            let d = segment_distance(a.1, a.2, b.1, b.2);
            if d < a.3 + b.3 + clearance {
                return Some(format!(
                    "links `{}` and `{}` come {:.3} m apart",
                    robot.probes[i].link, robot.probes[j].link, d
                ));
            }
        }
    }
    // Leg links against the body's box, in the body frame.
    let body_pose = robot
        .probes
        .iter()
        .zip(poses)
        .find(|(p, _)| p.leg.is_none())
        .map(|(p, pose)| (pose, p));
    let (body_world, _) = body_pose?;
    let body_inv = body_world.inverse();
    for (probe, pose) in robot.probes.iter().zip(poses) {
        let Some(leg) = probe.leg else { continue };
        if robot.model().link(&probe.link).map(|l| l.stage()) == Some(1) {
            continue;
        }
        for (pt, r) in &probe.points {
            let local = body_inv * (pose * pt) - robot.body_centre;
            let h = robot.body_half;
            if local.x.abs() < h.x + r && local.y.abs() < h.y + r && local.z.abs() < h.z + r {
                return Some(format!(
                    "link `{}` of leg {leg} enters the body",
                    probe.link
                ));
            }
        }
    }
    None
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

        #[test]
        fn segment_distance_is_symmetric_and_bounded(a in prop::array::uniform3(-1.0..1.0f64), b in prop::array::uniform3(-1.0..1.0f64), c in prop::array::uniform3(-1.0..1.0f64), d in prop::array::uniform3(-1.0..1.0f64)) {
            let (a, b, c, d) = (Point3::from(a), Point3::from(b), Point3::from(c), Point3::from(d));
            let s = segment_distance(a, b, c, d);
            prop_assert!((s - segment_distance(c, d, a, b)).abs() < 1e-9);
            // Never more than the distance between any two end points nor less than zero.
            prop_assert!(s <= (a - c).norm() + 1e-9 && s <= (b - d).norm() + 1e-9);
            // No sampled pair of points is closer.
            for i in 0..=10 {
                for j in 0..=10 {
                    let p = a + (b - a) * (f64::from(i) / 10.0);
                    let q = c + (d - c) * (f64::from(j) / 10.0);
                    prop_assert!(s <= (p - q).norm() + 1e-9);
                }
            }
        }
    }

    #[test]
    fn crossing_segments_are_at_zero() {
        let d = segment_distance(
            Point3::new(-1.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, -1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        );
        assert!(d.abs() < 1e-12);
    }
}
