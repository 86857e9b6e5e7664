//! Static stability margins.
//!
//! A walker moving slowly enough that inertia does not matter stays upright while the
//! vertical line through its centre of mass meets the ground inside the support polygon. The
//! *static stability margin* measures how far inside: the signed distance from the centre of
//! mass, projected straight down (along Z) onto the XY plane, to the polygon's boundary.
//! Positive means stable with that much room before the nearest edge; negative means the
//! centre of mass is that far outside and the walker would tip over the nearest edge. The
//! polygon may be the support polygon, or the conservative one for a margin that survives
//! lifting any one leg.
//!
//! # Along a straight move
//!
//! When the body shifts in a straight line, the projected centre of mass moves along a
//! straight segment, and the smallest margin along it is what matters. That minimum is always
//! at one of the two ends, for any convex polygon:
//!
//! - Inside, the margin is the smallest of the distances to the edges' lines. Each of those
//!   is an affine function of position, and the smallest of affine functions is concave.
//! - Outside, the margin is minus the distance to a convex set, and that distance is convex.
//! - The two pieces join into one concave function over the whole plane: the margin at `p`
//!   equals the smallest, over all unit directions `n`, of `max(n . x) - n . p`, the maximum
//!   taken over the polygon's points `x`. That is again a minimum of affine functions of `p`.
//!
//! A concave function on a segment is at least its smaller end value, so checking the two
//! ends is exact, not a sampling approximation. This also holds for degenerate polygons
//! (minus the distance to a point or segment) and trivially for the empty one (minus
//! infinity). A path of several straight moves has its minimum at one of its corners.

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};

use crate::polygon::Polygon;

/// Projects a centre of mass straight down onto the XY plane (drops Z).
pub fn ground_projection(com: Point3<f64>) -> Point2<f64> {
    Point2::new(com.x, com.y)
}

/// The static stability margin of `com` over `support`, metres: the signed distance of its
/// ground projection to the polygon's boundary, positive inside.
///
/// Never positive for a degenerate polygon; minus infinity for the empty one; NaN if `com`
/// has a NaN or infinite X or Y (Z is ignored).
pub fn stability_margin(support: &Polygon, com: Point3<f64>) -> f64 {
    support.signed_distance(ground_projection(com))
}

/// The smallest margin on a move and where it is reached.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MinimumMargin {
    /// The smallest static stability margin, metres (as [`stability_margin`]).
    pub margin_m: f64,
    /// The centre-of-mass position where it is reached: one of the given points.
    pub at: Point3<f64>,
}

/// The smallest stability margin while the centre of mass moves in a straight line from
/// `from` to `to` over the fixed polygon `support`.
///
/// Exact: the minimum is the smaller of the two end margins (see the
/// [module documentation](self)); on a tie, `from` is reported. If either end gives NaN (a
/// non-finite X or Y), the result is that NaN at that end.
pub fn margin_along(support: &Polygon, from: Point3<f64>, to: Point3<f64>) -> MinimumMargin {
    let start = MinimumMargin {
        margin_m: stability_margin(support, from),
        at: from,
    };
    let end = MinimumMargin {
        margin_m: stability_margin(support, to),
        at: to,
    };
    lower(start, end)
}

/// The smallest stability margin while the centre of mass follows the polyline `path`
/// (straight moves between consecutive points) over the fixed polygon `support`.
///
/// Exact, as for [`margin_along`]: the minimum is at a corner of the path; on a tie the
/// earliest is reported, and the first NaN margin wins. `None` for an empty path; a single
/// point is a path that stays put.
pub fn margin_along_path(support: &Polygon, path: &[Point3<f64>]) -> Option<MinimumMargin> {
    path.iter()
        .map(|&at| MinimumMargin {
            margin_m: stability_margin(support, at),
            at,
        })
        .reduce(lower)
}

/// The one with the smaller margin, `a` on a tie; a NaN margin counts as smallest.
fn lower(a: MinimumMargin, b: MinimumMargin) -> MinimumMargin {
    if a.margin_m.is_nan() || (!b.margin_m.is_nan() && a.margin_m <= b.margin_m) {
        a
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hull::support_polygon;

    fn q(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    fn square() -> Polygon {
        support_polygon(&[
            Point2::new(-1.0, -1.0),
            Point2::new(1.0, -1.0),
            Point2::new(1.0, 1.0),
            Point2::new(-1.0, 1.0),
        ])
    }

    #[test]
    fn margin_ignores_height() {
        let sq = square();
        assert_eq!(stability_margin(&sq, q(0.5, 0.0, 0.0)), 0.5);
        assert_eq!(stability_margin(&sq, q(0.5, 0.0, 3.0)), 0.5);
        assert_eq!(stability_margin(&sq, q(2.0, 0.0, 1.0)), -1.0);
        assert!(stability_margin(&sq, q(f64::NAN, 0.0, 1.0)).is_nan());
        assert_eq!(stability_margin(&sq, q(0.0, 0.0, f64::NAN)), 1.0);
    }

    #[test]
    fn segment_minimum_is_at_an_end() {
        let sq = square();
        let m = margin_along(&sq, q(0.0, 0.0, 1.0), q(0.8, 0.0, 1.0));
        assert!((m.margin_m - 0.2).abs() < 1e-15);
        assert_eq!(m.at, q(0.8, 0.0, 1.0));
        // Crossing the whole square: the middle is the most stable point, the ends the least.
        let m = margin_along(&sq, q(-3.0, 0.0, 0.0), q(2.0, 0.0, 0.0));
        assert_eq!(m.margin_m, -2.0);
        assert_eq!(m.at, q(-3.0, 0.0, 0.0));
        let tie = margin_along(&sq, q(0.5, 0.0, 0.0), q(-0.5, 0.0, 0.0));
        assert_eq!(tie.at, q(0.5, 0.0, 0.0));
    }

    #[test]
    fn nan_end_is_reported() {
        let sq = square();
        let m = margin_along(&sq, q(0.0, 0.0, 0.0), q(f64::NAN, 0.0, 0.0));
        assert!(m.margin_m.is_nan());
        assert!(m.at.x.is_nan());
        let m = margin_along(&sq, q(0.0, f64::INFINITY, 0.0), q(0.0, 0.0, 0.0));
        assert!(m.margin_m.is_nan());
        assert!(m.at.y.is_infinite());
    }

    #[test]
    fn path_minimum() {
        let sq = square();
        assert_eq!(margin_along_path(&sq, &[]), None);
        let path = [q(0.0, 0.0, 0.0), q(0.9, 0.0, 0.0), q(0.0, 0.5, 0.0)];
        let m = margin_along_path(&sq, &path).unwrap();
        assert_eq!(m.at, path[1]);
        assert!((m.margin_m - 0.1).abs() < 1e-15);
        let still = margin_along_path(&sq, &path[..1]).unwrap();
        assert_eq!(still.margin_m, 1.0);
    }

    #[test]
    fn empty_support_is_never_stable() {
        let m = margin_along(&Polygon::empty(), q(0.0, 0.0, 0.0), q(1.0, 0.0, 0.0));
        assert_eq!(m.margin_m, f64::NEG_INFINITY);
    }
}
