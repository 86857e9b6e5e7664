//! Convex polygons in the horizontal (XY) plane.
//!
//! A [`Polygon`] is always convex, its vertices run counter-clockwise seen from above (+Z),
//! no two vertices coincide and no vertex lies on (or within rounding of) the straight line
//! through its neighbours.
//! It is made only as a convex hull ([`Polygon::convex_hull`]), as an intersection of two
//! polygons ([`Polygon::intersection`]) or empty ([`Polygon::empty`]), so these rules hold by
//! construction.
//!
//! # Degenerate polygons
//!
//! With fewer than three vertices a polygon has no interior: no vertices is the empty set,
//! one vertex is a single point, two are a line segment. Such a polygon
//! [`contains`](Polygon::contains) nothing, has zero [`area`](Polygon::area), and its
//! [`signed_distance`](Polygon::signed_distance) is never positive: it is minus the distance
//! to the point or segment (zero on it), and minus infinity for the empty polygon.
//!
//! # Signed distance
//!
//! For a point inside, the signed distance is the distance to the nearest edge (for a convex
//! polygon this equals the distance to the nearest edge's line), positive. For a point
//! outside it is minus the distance to the nearest point of the polygon. On the boundary it
//! is zero. `contains` is exactly "signed distance is zero or more" for a polygon with an
//! interior, so a positive distance always means inside and a negative one outside; points
//! within rounding of the boundary may fall either way. A point just beyond a very sharp
//! corner can be on the inner side of every edge's line by rounding; it is recognised as
//! outside by its distance to the edges themselves.
//!
//! Queries with a NaN or infinite coordinate return NaN distances and are not contained.

use nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};

use crate::error::StabilityError;
use crate::hull;

/// A convex polygon in the XY plane, vertices counter-clockwise seen from above.
///
/// See the [module documentation](self) for the invariants and for what degenerate
/// (fewer than three vertex) polygons mean. Serialised as its list of vertices; deserialising
/// takes the convex hull of the list, so it refuses non-finite coordinates and repairs any
/// list that is not already a valid polygon.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Vec<Point2<f64>>", into = "Vec<Point2<f64>>")]
pub struct Polygon {
    vertices: Vec<Point2<f64>>,
}

impl Polygon {
    /// The empty polygon: no vertices, contains nothing, signed distance minus infinity
    /// everywhere.
    pub fn empty() -> Self {
        Self {
            vertices: Vec::new(),
        }
    }

    /// The convex hull of `points`: the smallest convex polygon holding them all.
    ///
    /// Duplicate points and points on an edge are dropped, as are vertices within rounding
    /// (about 1e-12 of the largest coordinate) of the line through their neighbours. Fewer
    /// than three points not on one line give a degenerate polygon (a point or a segment);
    /// no points give the empty polygon.
    ///
    /// # Errors
    ///
    /// [`StabilityError::NonFinitePoint`] if any coordinate is NaN or infinite.
    pub fn convex_hull(points: &[Point2<f64>]) -> Result<Self, StabilityError> {
        hull::check_finite(points)?;
        Ok(Self::from_hull_vertices(hull::convex_hull_of_finite(
            points,
        )))
    }

    /// Wraps vertices that already satisfy the invariants (the output of
    /// [`hull::convex_hull_of_finite`]).
    pub(crate) fn from_hull_vertices(vertices: Vec<Point2<f64>>) -> Self {
        Self { vertices }
    }

    /// The vertices, counter-clockwise seen from above (+Z), starting at the one with the
    /// smallest X (and, among those, the smallest Y).
    pub fn vertices(&self) -> &[Point2<f64>] {
        &self.vertices
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Whether the polygon has no vertices at all (the empty set).
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Whether the polygon has no interior: fewer than three vertices (empty, a point or a
    /// segment).
    pub fn is_degenerate(&self) -> bool {
        self.vertices.len() < 3
    }

    /// The edges as `(start, end)` pairs, counter-clockwise, the interior on the left. A
    /// segment gives its two directions; a point or the empty polygon gives none.
    pub fn edges(&self) -> impl Iterator<Item = (Point2<f64>, Point2<f64>)> + '_ {
        let n = self.vertices.len();
        let count = if n >= 2 { n } else { 0 };
        (0..count).map(move |i| (self.vertices[i], self.vertices[(i + 1) % n]))
    }

    /// Area in square metres; zero for a degenerate polygon.
    pub fn area(&self) -> f64 {
        if self.is_degenerate() {
            return 0.0;
        }
        let o = self.vertices[0];
        let twice: f64 = self
            .vertices
            .windows(2)
            .skip(1)
            .map(|w| cross(w[0] - o, w[1] - o))
            .sum();
        0.5 * twice
    }

    /// The centroid (centre of area). For a point or a segment, the mean of its vertices;
    /// `None` for the empty polygon.
    pub fn centroid(&self) -> Option<Point2<f64>> {
        let n = self.vertices.len();
        if n == 0 {
            return None;
        }
        let o = self.vertices[0];
        if n < 3 {
            let sum: Vector2<f64> = self.vertices.iter().map(|v| v - o).sum();
            return Some(o + sum / n as f64);
        }
        let mut twice_area = 0.0;
        let mut moment = Vector2::zeros();
        for w in self.vertices.windows(2).skip(1) {
            let (a, b) = (w[0] - o, w[1] - o);
            let c = cross(a, b);
            twice_area += c;
            moment += (a + b) * c;
        }
        Some(o + moment / (3.0 * twice_area))
    }

    /// Whether `p` lies in the polygon, boundary included. A degenerate polygon contains
    /// nothing; a NaN or infinite `p` is never contained.
    pub fn contains(&self, p: Point2<f64>) -> bool {
        !self.is_degenerate() && self.signed_distance(p) >= 0.0
    }

    /// Signed distance from `p` to the polygon's boundary, metres: positive inside, negative
    /// outside, zero on the boundary. See the [module documentation](self) for degenerate
    /// polygons (never positive; minus infinity when empty). NaN if `p` is not finite.
    pub fn signed_distance(&self, p: Point2<f64>) -> f64 {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return f64::NAN;
        }
        match self.vertices.as_slice() {
            [] => f64::NEG_INFINITY,
            [a] => -(p - a).norm(),
            [a, b] => -segment_distance(p, *a, *b),
            _ => {
                let nearest_line = self
                    .edges()
                    .map(|(a, b)| line_distance(p, a, b))
                    .fold(f64::INFINITY, f64::min);
                let nearest_edge = self
                    .edges()
                    .map(|(a, b)| segment_distance(p, a, b))
                    .fold(f64::INFINITY, f64::min);
                // Inside, the nearest edge's line and the nearest edge are equally far. A
                // point just beyond a very sharp corner can be on the inner side of every
                // edge line by rounding; it is then told apart by being much farther from
                // the edges themselves than from their lines.
                let slack = hull::tolerance(&self.vertices);
                if nearest_line >= 0.0 && nearest_edge <= nearest_line + slack {
                    return nearest_line;
                }
                // Outside: minus the distance to the nearest edge, which is also at least the
                // violation of any edge's half-plane; this keeps the result strictly negative
                // whenever `contains` is false.
                -nearest_edge.max(-nearest_line)
            }
        }
    }
}

impl TryFrom<Vec<Point2<f64>>> for Polygon {
    type Error = StabilityError;

    /// The convex hull of the points, as [`Polygon::convex_hull`].
    fn try_from(points: Vec<Point2<f64>>) -> Result<Self, StabilityError> {
        Self::convex_hull(&points)
    }
}

impl From<Polygon> for Vec<Point2<f64>> {
    /// The vertices, counter-clockwise.
    fn from(polygon: Polygon) -> Self {
        polygon.vertices
    }
}

/// The z component of the cross product of two plane vectors: positive when `v` turns
/// counter-clockwise from `u`.
pub(crate) fn cross(u: Vector2<f64>, v: Vector2<f64>) -> f64 {
    u.x * v.y - u.y * v.x
}

/// Signed distance from `p` to the line through `a` and `b`, positive on the left of the
/// direction `a -> b`. `a` and `b` must differ.
pub(crate) fn line_distance(p: Point2<f64>, a: Point2<f64>, b: Point2<f64>) -> f64 {
    let e = b - a;
    cross(e, p - a) / e.norm()
}

/// Distance from `p` to the closed segment from `a` to `b` (which may coincide).
pub(crate) fn segment_distance(p: Point2<f64>, a: Point2<f64>, b: Point2<f64>) -> f64 {
    let e = b - a;
    let len2 = e.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&e) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + e * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    fn unit_square() -> Polygon {
        Polygon::convex_hull(&[p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]).unwrap()
    }

    #[test]
    fn square_area_centroid_and_order() {
        let sq = unit_square();
        assert_eq!(sq.len(), 4);
        assert_eq!(sq.vertices()[0], p(0.0, 0.0));
        assert_eq!(sq.vertices()[1], p(1.0, 0.0));
        assert!((sq.area() - 1.0).abs() < 1e-15);
        let c = sq.centroid().unwrap();
        assert!((c - p(0.5, 0.5)).norm() < 1e-15);
    }

    #[test]
    fn signed_distance_inside_outside_boundary() {
        let sq = unit_square();
        assert!((sq.signed_distance(p(0.5, 0.5)) - 0.5).abs() < 1e-15);
        assert!((sq.signed_distance(p(0.5, 0.1)) - 0.1).abs() < 1e-15);
        assert!((sq.signed_distance(p(2.0, 0.5)) + 1.0).abs() < 1e-15);
        // Nearest point is a corner.
        assert!((sq.signed_distance(p(2.0, 2.0)) + 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(sq.signed_distance(p(1.0, 0.5)), 0.0);
        assert!(sq.contains(p(1.0, 0.5)));
        assert!(sq.contains(p(0.5, 0.5)));
        assert!(!sq.contains(p(1.5, 0.5)));
    }

    #[test]
    fn point_beyond_a_sharp_corner_is_outside() {
        // A sliver whose corner at the top is about 1e-11 rad wide (met while intersecting
        // leave-one-out polygons). The point, 1.4e-7 beyond that corner, is on the inner side
        // of both long edges' lines by rounding.
        let sliver = Polygon::convex_hull(&[
            p(-1.9999999999999991, 0.0),
            p(-1.99999999999, 0.0),
            p(-0.9999999672057723, 1.9999998655884699),
        ])
        .unwrap();
        assert_eq!(sliver.len(), 3);
        let beyond = p(-0.9999999, 2.000000000000001);
        let corner = sliver.vertices()[2];
        let sd = sliver.signed_distance(beyond);
        assert!((sd + (beyond - corner).norm()).abs() < 1e-12, "{sd}");
        assert!(!sliver.contains(beyond));
        assert!(sliver.contains(p(-1.999999999995, 1e-12)));
    }

    #[test]
    fn non_finite_queries() {
        let sq = unit_square();
        assert!(sq.signed_distance(p(f64::NAN, 0.5)).is_nan());
        assert!(sq.signed_distance(p(f64::INFINITY, 0.5)).is_nan());
        assert!(!sq.contains(p(f64::NAN, 0.5)));
    }

    #[test]
    fn degenerate_polygons() {
        let empty = Polygon::empty();
        assert!(empty.is_empty() && empty.is_degenerate());
        assert_eq!(empty.signed_distance(p(0.0, 0.0)), f64::NEG_INFINITY);
        assert!(!empty.contains(p(0.0, 0.0)));
        assert_eq!(empty.area(), 0.0);
        assert_eq!(empty.centroid(), None);
        assert_eq!(empty.edges().count(), 0);

        let point = Polygon::convex_hull(&[p(1.0, 1.0), p(1.0, 1.0)]).unwrap();
        assert_eq!(point.vertices(), &[p(1.0, 1.0)]);
        assert!(!point.contains(p(1.0, 1.0)));
        assert_eq!(point.signed_distance(p(1.0, 1.0)), 0.0);
        assert!((point.signed_distance(p(4.0, 5.0)) + 5.0).abs() < 1e-15);

        let seg = Polygon::convex_hull(&[p(0.0, 0.0), p(2.0, 0.0), p(1.0, 0.0)]).unwrap();
        assert_eq!(seg.vertices(), &[p(0.0, 0.0), p(2.0, 0.0)]);
        assert!(!seg.contains(p(1.0, 0.0)));
        assert!((seg.signed_distance(p(1.0, 3.0)) + 3.0).abs() < 1e-15);
        assert!((seg.signed_distance(p(3.0, 0.0)) + 1.0).abs() < 1e-15);
        assert_eq!(seg.area(), 0.0);
        assert_eq!(seg.centroid(), Some(p(1.0, 0.0)));
        assert_eq!(seg.edges().count(), 2);
    }

    #[test]
    fn convex_hull_refuses_non_finite() {
        let err = Polygon::convex_hull(&[p(0.0, 0.0), p(f64::NAN, 1.0)]).unwrap_err();
        assert!(matches!(
            err,
            StabilityError::NonFinitePoint { index: 1, .. }
        ));
        assert!(err.to_string().contains("point 1"));
    }

    #[test]
    fn serde_round_trip_and_repair() {
        let sq = unit_square();
        let json = serde_json::to_string(&sq).unwrap();
        assert_eq!(json, "[[0.0,0.0],[1.0,0.0],[1.0,1.0],[0.0,1.0]]");
        let back: Polygon = serde_json::from_str(&json).unwrap();
        assert_eq!(back, sq);
        // A clockwise list with an interior point comes back as the hull.
        let repaired: Polygon =
            serde_json::from_str("[[0,1],[1,1],[0.5,0.5],[1,0],[0,0]]").unwrap();
        assert_eq!(repaired, sq);
    }
}
