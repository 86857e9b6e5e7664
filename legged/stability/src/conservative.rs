//! The conservative support polygon.
//!
//! A walker whose centre of mass is inside its support polygon is stable now, but may not be
//! stable once it lifts a leg to step. The *conservative* support polygon is the region that
//! stays supported whichever single standing leg is lifted next: for each standing foot in
//! turn, take the support polygon of all the *other* feet, and intersect these polygons.
//! Keeping the centre of mass inside it means any one leg may be picked up (or found to have
//! lost its footing) without the walker tipping. The idea comes from the FootFall planner of
//! SunSpiral et al.
//!
//! It lies inside the ordinary support polygon, since each leave-one-out polygon does. Only
//! feet at corners of the support polygon change it when lifted, so the others are skipped.
//!
//! With fewer than four standing feet it is empty: lifting one of three leaves a segment, and
//! the three edges of a triangle share no common point. With four feet it never has an area:
//! at the corners of a convex quadrilateral it shrinks to the point where the diagonals
//! cross, and with one foot inside the triangle of the others, to that foot. Only from five
//! feet on can it have an interior, and so a positive margin.

use nalgebra::Point2;

use crate::error::StabilityError;
use crate::hull;
use crate::polygon::Polygon;

/// The conservative support polygon of the standing feet: the intersection of the support
/// polygons left when any one of them is lifted.
///
/// Fewer than four feet give the empty polygon. See the [module documentation](self).
///
/// This function never fails: if any coordinate is NaN or infinite it returns the **empty**
/// polygon, so that an unknown foot position counts as no support. Use
/// [`try_conservative_support_polygon`] to get an error instead.
pub fn conservative_support_polygon(feet: &[Point2<f64>]) -> Polygon {
    try_conservative_support_polygon(feet).unwrap_or_else(|_| Polygon::empty())
}

/// The conservative support polygon, as [`conservative_support_polygon`], refusing bad input.
///
/// # Errors
///
/// [`StabilityError::NonFinitePoint`] if any coordinate is NaN or infinite.
pub fn try_conservative_support_polygon(feet: &[Point2<f64>]) -> Result<Polygon, StabilityError> {
    hull::check_finite(feet)?;
    if feet.len() < 4 {
        return Ok(Polygon::empty());
    }
    // Hull vertices are input points exactly (the hull only drops points), so a foot that is
    // not exactly a corner of the full support polygon leaves it unchanged when lifted, and
    // that full polygon holds every other leave-one-out polygon: it cannot change the result.
    let full = hull::convex_hull_of_finite(feet);
    let is_corner = |p: &Point2<f64>| full.iter().any(|v| v == p);
    let mut result: Option<Polygon> = None;
    let mut others = Vec::with_capacity(feet.len() - 1);
    for (lifted, foot) in feet.iter().enumerate() {
        if !is_corner(foot) {
            continue;
        }
        others.clear();
        others.extend_from_slice(&feet[..lifted]);
        others.extend_from_slice(&feet[lifted + 1..]);
        let remaining = Polygon::from_hull_vertices(hull::convex_hull_of_finite(&others));
        let next = match result {
            None => remaining,
            Some(so_far) => so_far.intersection(&remaining),
        };
        if next.is_empty() {
            return Ok(next);
        }
        result = Some(next);
    }
    Ok(result.unwrap_or_else(|| Polygon::from_hull_vertices(full)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    fn regular(n: usize, radius: f64, phase: f64) -> Vec<Point2<f64>> {
        (0..n)
            .map(|k| {
                let a = phase + k as f64 * TAU / n as f64;
                p(radius * a.cos(), radius * a.sin())
            })
            .collect()
    }

    #[test]
    fn fewer_than_four_feet_is_empty() {
        assert!(conservative_support_polygon(&[]).is_empty());
        assert!(conservative_support_polygon(&regular(3, 1.0, 0.0)).is_empty());
    }

    #[test]
    fn rectangle_shrinks_to_its_centre() {
        let feet = [p(0.0, 0.0), p(4.0, 0.0), p(4.0, 2.0), p(0.0, 2.0)];
        let c = conservative_support_polygon(&feet);
        assert_eq!(c.len(), 1);
        assert!((c.vertices()[0] - p(2.0, 1.0)).norm() < 1e-12);
        assert!(!c.contains(p(2.0, 1.0)));
    }

    #[test]
    fn regular_hexagon_gives_a_smaller_rotated_hexagon() {
        let feet = regular(6, 1.0, 0.0);
        let c = conservative_support_polygon(&feet);
        assert_eq!(c.len(), 6);
        // Lifting a foot cuts the chord between its neighbours, half a radius from the
        // centre: a regular hexagon of apothem 1/2, corners at 30 + 60k degrees.
        assert!((c.area() - 2.0 * 3f64.sqrt() * 0.25).abs() < 1e-12);
        for v in c.vertices() {
            assert!((v.coords.norm() - 0.5 / (TAU / 12.0).cos()).abs() < 1e-12);
            let angle = v.y.atan2(v.x).rem_euclid(TAU / 6.0);
            assert!((angle - TAU / 12.0).abs() < 1e-9);
        }
        assert!((c.signed_distance(p(0.0, 0.0)) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn inner_foot_does_not_matter_when_lifted() {
        let mut feet = regular(6, 1.0, 0.0);
        let without = conservative_support_polygon(&feet);
        feet.push(p(0.1, 0.0));
        let with = conservative_support_polygon(&feet);
        assert!((with.area() - without.area()).abs() < 1e-12);
    }

    #[test]
    fn doubled_corner_pins_the_polygon_to_it() {
        // Lifting either copy of (0, 0) leaves the triangle; lifting another corner leaves
        // the segment through (0, 0) and the remaining corner. They meet only at (0, 0).
        let feet = [p(0.0, 0.0), p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)];
        assert_eq!(
            conservative_support_polygon(&feet).vertices(),
            &[p(0.0, 0.0)]
        );
    }

    #[test]
    fn nearly_doubled_feet_stay_within_every_leave_one_out_polygon() {
        // Two pairs of feet 1e-11 and 1e-7 apart make thin slivers while intersecting.
        let feet = [
            p(1e-11, -2.09863382340068),
            p(-1.0, 2.0),
            p(-0.9999999, 2.000000000000001),
            p(-1.999999999999999, 0.0),
            p(-1.99999999999, 0.0),
        ];
        let c = conservative_support_polygon(&feet);
        assert!(!c.is_empty());
        for lifted in 0..feet.len() {
            let mut others = feet.to_vec();
            others.remove(lifted);
            let remaining = crate::hull::support_polygon(&others);
            for &v in c.vertices() {
                assert!(
                    remaining.signed_distance(v) >= -1e-11,
                    "{v:?} lifting {lifted}"
                );
            }
        }
    }

    #[test]
    fn non_finite_foot() {
        let mut feet = regular(6, 1.0, 0.0);
        feet[3].y = f64::NAN;
        assert!(conservative_support_polygon(&feet).is_empty());
        assert!(matches!(
            try_conservative_support_polygon(&feet),
            Err(StabilityError::NonFinitePoint { index: 3, .. })
        ));
    }
}
