//! Intersection of convex polygons.
//!
//! The intersection of two convex polygons is convex, and each of its corners is of one of
//! three kinds: a corner of the first polygon lying in the second, a corner of the second
//! lying in the first, or a point where an edge of one crosses an edge of the other. So the
//! intersection is the convex hull of those candidate points, and that is how it is computed
//! here: test every corner against the other polygon, cross every edge with every edge, and
//! take the hull of what is found. Degenerate polygons fit the same scheme: a segment has one
//! edge, a point none.
//!
//! Rounding is handled by counting a corner within a small tolerance (about 1e-12 of the
//! largest coordinate) of the other polygon as in it, so polygons that only touch along an
//! edge or at a corner meet in that segment or point instead of vanishing, and by keeping an
//! edge crossing only if it lies within that tolerance of both polygons. Every candidate is a
//! point already close to both polygons, so the result can only exceed the exact
//! intersection by the tolerance.
//!
//! Sutherland–Hodgman clipping (cutting one polygon by each edge line of the other) is not
//! used because it cannot take such a tolerance: widening the two half-planes at a thin
//! polygon's sharp corner moves the point where they meet far beyond the corner, and without
//! the widening, polygons that touch along an edge lose the contact to rounding.

use nalgebra::Point2;

use crate::hull;
use crate::polygon::{Polygon, cross};

impl Polygon {
    /// The intersection of two convex polygons: the points in both.
    ///
    /// Either may be degenerate; the result may be degenerate or empty (for instance two
    /// squares sharing an edge meet in that edge, a segment). The result lies within both
    /// polygons up to rounding (about 1e-12 of the largest coordinate).
    pub fn intersection(&self, other: &Polygon) -> Polygon {
        if self.is_empty() || other.is_empty() {
            return Polygon::empty();
        }
        let tol = hull::tolerance(self.vertices().iter().chain(other.vertices()));
        let near_self = |p: Point2<f64>| self.signed_distance(p) >= -tol;
        let near_other = |p: Point2<f64>| other.signed_distance(p) >= -tol;
        let mut candidates: Vec<Point2<f64>> = self
            .vertices()
            .iter()
            .copied()
            .filter(|&v| near_other(v))
            .chain(other.vertices().iter().copied().filter(|&v| near_self(v)))
            .collect();
        for (a0, a1) in sides(self) {
            for (b0, b1) in sides(other) {
                if let Some(x) = crossing(a0, a1, b0, b1)
                    && near_self(x)
                    && near_other(x)
                {
                    candidates.push(x);
                }
            }
        }
        Polygon::from_hull_vertices(hull::convex_hull_of_finite(&candidates))
    }
}

/// The sides of a polygon: its edges, or for a segment the segment once, or none for a
/// point.
fn sides(polygon: &Polygon) -> Vec<(Point2<f64>, Point2<f64>)> {
    match polygon.vertices() {
        [a, b] => vec![(*a, *b)],
        _ => polygon.edges().collect(),
    }
}

/// Where the segment `a0 -> a1` crosses the segment `b0 -> b1`, if they cross at a single
/// point. Parallel segments give `None`; where they overlap, the overlap's ends are corners
/// found by the corner tests.
fn crossing(
    a0: Point2<f64>,
    a1: Point2<f64>,
    b0: Point2<f64>,
    b1: Point2<f64>,
) -> Option<Point2<f64>> {
    let (r, s, w) = (a1 - a0, b1 - b0, b0 - a0);
    let denom = cross(r, s);
    if denom == 0.0 {
        return None;
    }
    let t = cross(w, s) / denom;
    let u = cross(w, r) / denom;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then(|| a0 + r * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    fn hull(points: &[Point2<f64>]) -> Polygon {
        Polygon::convex_hull(points).unwrap()
    }

    fn square(x0: f64, y0: f64, side: f64) -> Polygon {
        hull(&[
            p(x0, y0),
            p(x0 + side, y0),
            p(x0 + side, y0 + side),
            p(x0, y0 + side),
        ])
    }

    #[test]
    fn overlapping_squares() {
        let a = square(0.0, 0.0, 2.0);
        let b = square(1.0, 1.0, 2.0);
        let i = a.intersection(&b);
        assert_eq!(
            i.vertices(),
            &[p(1.0, 1.0), p(2.0, 1.0), p(2.0, 2.0), p(1.0, 2.0)]
        );
        assert_eq!(b.intersection(&a), i);
    }

    #[test]
    fn nested_and_disjoint() {
        let big = square(0.0, 0.0, 4.0);
        let small = square(1.0, 1.0, 1.0);
        assert_eq!(big.intersection(&small), small);
        assert_eq!(small.intersection(&big), small);
        let far = square(10.0, 10.0, 1.0);
        assert!(big.intersection(&far).is_empty());
        assert!(big.intersection(&Polygon::empty()).is_empty());
    }

    #[test]
    fn squares_sharing_an_edge_or_a_corner() {
        let a = square(0.0, 0.0, 1.0);
        let edge = a.intersection(&square(1.0, 0.0, 1.0));
        assert_eq!(edge.vertices(), &[p(1.0, 0.0), p(1.0, 1.0)]);
        let corner = a.intersection(&square(1.0, 1.0, 1.0));
        assert_eq!(corner.vertices(), &[p(1.0, 1.0)]);
    }

    #[test]
    fn triangles_make_a_hexagon() {
        // Two opposite triangles round the origin (a star of David).
        let r = 1.0;
        let tri = |phase: f64| {
            let pts: Vec<_> = (0..3)
                .map(|k| {
                    let a = phase + k as f64 * std::f64::consts::TAU / 3.0;
                    p(r * a.cos(), r * a.sin())
                })
                .collect();
            hull(&pts)
        };
        let i = tri(0.0).intersection(&tri(std::f64::consts::PI));
        assert_eq!(i.len(), 6);
        // Hexagon of apothem r/2: area 2 sqrt(3) (r/2)^2.
        assert!((i.area() - 2.0 * 3f64.sqrt() * 0.25).abs() < 1e-12);
    }

    #[test]
    fn thin_polygon_is_not_stretched_beyond_its_sharp_corner() {
        // `sliver` is about 2.4e-12 m thick with a corner at (0.5, 0) only ~5e-12 rad wide;
        // widening its edges by the tolerance would move that corner about a metre away.
        let sliver = hull(&[p(0.0, -1.99999999999), p(0.5, 0.0), p(0.0, -2.0)]);
        assert_eq!(sliver.len(), 3);
        let big = hull(&[
            p(-1.499999999999999, 1e-15),
            p(2.431297730005863, -1.5),
            p(3.761582308897265, 0.999999999),
        ]);
        for i in [big.intersection(&sliver), sliver.intersection(&big)] {
            assert!(!i.is_empty());
            for &v in i.vertices() {
                assert!(sliver.signed_distance(v) >= -1e-11, "{v:?}");
                assert!(big.signed_distance(v) >= -1e-11, "{v:?}");
            }
        }
    }

    #[test]
    fn segment_and_polygon() {
        let sq = square(0.0, 0.0, 2.0);
        let seg = hull(&[p(-1.0, 1.0), p(3.0, 1.0)]);
        let i = sq.intersection(&seg);
        assert_eq!(i.vertices(), &[p(0.0, 1.0), p(2.0, 1.0)]);
        assert_eq!(seg.intersection(&sq), i);
        let short = hull(&[p(0.5, 1.0), p(1.0, 1.5)]);
        assert_eq!(sq.intersection(&short), short);
        let outside = hull(&[p(3.0, 0.0), p(3.0, 2.0)]);
        assert!(sq.intersection(&outside).is_empty());
    }

    #[test]
    fn segments_and_points() {
        let a = hull(&[p(0.0, 0.0), p(2.0, 2.0)]);
        let b = hull(&[p(0.0, 2.0), p(2.0, 0.0)]);
        assert_eq!(a.intersection(&b).vertices(), &[p(1.0, 1.0)]);
        let overlap = hull(&[p(1.0, 1.0), p(3.0, 3.0)]);
        assert_eq!(
            a.intersection(&overlap).vertices(),
            &[p(1.0, 1.0), p(2.0, 2.0)]
        );
        let point = hull(&[p(0.5, 0.5)]);
        assert_eq!(a.intersection(&point), point);
        assert_eq!(point.intersection(&a), point);
        assert!(hull(&[p(0.5, 0.6)]).intersection(&a).is_empty());
        let sq = square(0.0, 0.0, 1.0);
        assert_eq!(sq.intersection(&point), point);
        assert_eq!(point.intersection(&point), point);
    }
}
