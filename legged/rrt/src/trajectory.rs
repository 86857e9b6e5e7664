//! Foot trajectories: the terrain profile on the straight line from the foot's start to
//! its foothold, raised by the clearance, cut to its upper convex hull.

use nalgebra::{Point2, Point3};

use crate::terrain::Terrain;

/// The way-points of a swing from `start` to `end` (contact-sphere centres, world): the
/// profile of the highest ground within `foot_radius` of every point of the straight line
/// between them, sampled every `spacing`, lifted so that the sphere keeps `clearance` above
/// it, and reduced to its upper convex hull: from each way-point the line to the next is
/// the steepest to any later point of the profile. The ends are `start` and `end`
/// themselves, so the path rises from the start, runs straight over the highest points
/// and comes down on the foothold.
pub fn foot_trajectory(
    terrain: &Terrain,
    start: Point3<f64>,
    end: Point3<f64>,
    foot_radius: f64,
    clearance: f64,
    spacing: f64,
) -> Vec<Point3<f64>> {
    let (a, b) = (Point2::new(start.x, start.y), Point2::new(end.x, end.y));
    let length = (b - a).norm();
    let n = ((length / spacing.max(1e-3)).ceil() as usize).max(1);
    // (distance along, height of the sphere's centre)
    let mut profile = Vec::with_capacity(n + 1);
    profile.push((0.0, start.z));
    for i in 1..n {
        let s = i as f64 / n as f64;
        let p = a + (b - a) * s;
        let ground = terrain.max_in_disc(p, foot_radius);
        profile.push((length * s, ground + foot_radius + clearance));
    }
    // A short swing still lifts: the middle rises over both ends by the clearance.
    if n == 1 {
        let ground = terrain.max_in_disc(a + (b - a) * 0.5, foot_radius);
        profile.push((
            length * 0.5,
            ground.max(start.z.max(end.z) - foot_radius) + foot_radius + clearance,
        ));
    }
    profile.push((length, end.z));
    let hull = upper_hull(&profile);
    hull.iter()
        .map(|&(d, z)| {
            let s = if length > 0.0 { d / length } else { 0.5 };
            let p = a + (b - a) * s;
            Point3::new(p.x, p.y, z)
        })
        .collect()
}

/// The upper convex hull of points `(d, z)` sorted by `d`, from the first to the last:
/// from each vertex the next is the later point the line to which rises most steeply
/// (the farthest of equally steep ones).
pub fn upper_hull(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let Some(&first) = points.first() else {
        return out;
    };
    out.push(first);
    let mut i = 0;
    while i + 1 < points.len() {
        let (d0, z0) = points[i];
        let mut best = i + 1;
        let mut best_slope = f64::NEG_INFINITY;
        for (j, &(d, z)) in points.iter().enumerate().skip(i + 1) {
            let dd = d - d0;
            let slope = if dd > 1e-12 {
                (z - z0) / dd
            } else if z >= z0 {
                f64::INFINITY
            } else {
                f64::NEG_INFINITY
            };
            if slope >= best_slope - 1e-12 {
                best_slope = slope;
                best = j;
            }
        }
        out.push(points[best]);
        i = best;
    }
    out
}

/// The length of a polyline, metres.
pub fn path_length(points: &[Point3<f64>]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// The point a fraction `s` (0..=1) of the way along a polyline by length.
pub fn point_along(points: &[Point3<f64>], s: f64) -> Point3<f64> {
    let total = path_length(points);
    if points.len() < 2 || total <= 0.0 {
        return points.first().copied().unwrap_or_else(Point3::origin);
    }
    let mut left = s.clamp(0.0, 1.0) * total;
    for w in points.windows(2) {
        let l = (w[1] - w[0]).norm();
        if left <= l {
            return if l > 0.0 {
                w[0] + (w[1] - w[0]) * (left / l)
            } else {
                w[0]
            };
        }
        left -= l;
    }
    points[points.len() - 1]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::sync::Arc;
    use tca_robot::HeightField;

    fn step_terrain() -> Terrain {
        let (nx, ny, r) = (50, 20, 0.02);
        let mut h = Vec::new();
        for _ in 0..ny {
            for ix in 0..nx {
                let x = ix as f64 * r;
                h.push(if (0.4..0.5).contains(&x) { 0.08 } else { 0.0 });
            }
        }
        Terrain::new(
            Arc::new(HeightField::new(Point2::origin(), r, nx, ny, h).unwrap()),
            0.012,
        )
    }

    #[test]
    fn swing_clears_a_block_and_lands_on_the_foothold() {
        let t = step_terrain();
        let s = Point3::new(0.2, 0.2, 0.012);
        let f = Point3::new(0.7, 0.2, 0.012);
        let path = foot_trajectory(&t, s, f, 0.012, 0.03, 0.01);
        assert_eq!(path[0], s);
        assert_eq!(*path.last().unwrap(), f);
        // Everywhere along the path the sphere keeps at least the clearance above the block.
        for k in 0..=200 {
            let p = point_along(&path, f64::from(k) / 200.0);
            let ground = t.max_in_disc(Point2::new(p.x, p.y), 0.012);
            if (0.42..0.48).contains(&p.x) {
                assert!(p.z - 0.012 - ground >= 0.03 - 1e-9, "{p} over {ground}");
            }
            assert!(p.z - 0.012 >= ground - 1e-9, "{p} below {ground}");
        }
        // The hull is short: a few way-points, not the whole profile.
        assert!(path.len() <= 6, "{path:?}");
    }

    proptest! {
        #[test]
        fn upper_hull_lies_on_or_above_every_point(zs in prop::collection::vec(-1.0..1.0f64, 2..30)) {
            let pts: Vec<(f64, f64)> = zs.iter().enumerate().map(|(i, &z)| (i as f64, z)).collect();
            let hull = upper_hull(&pts);
            prop_assert_eq!(hull[0], pts[0]);
            prop_assert_eq!(*hull.last().unwrap(), *pts.last().unwrap());
            for &(d, z) in &pts {
                // Height of the hull at d.
                let k = hull.windows(2).find(|w| w[0].0 <= d && d <= w[1].0).unwrap();
                let (a, b) = (k[0], k[1]);
                let h = if b.0 > a.0 { a.1 + (b.1 - a.1) * (d - a.0) / (b.0 - a.0) } else { a.1.max(b.1) };
                prop_assert!(h >= z - 1e-9);
            }
            // Concave: slopes never increase.
            let slopes: Vec<f64> = hull.windows(2).map(|w| (w[1].1 - w[0].1) / (w[1].0 - w[0].0)).collect();
            for w in slopes.windows(2) {
                prop_assert!(w[1] <= w[0] + 1e-9);
            }
        }
    }
}
