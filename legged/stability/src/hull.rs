//! Convex hulls, and the support polygon of a standing walker.
//!
//! A walker standing still on rigid ground is held up only at its feet. Seen from above, the
//! region it can balance over is the convex hull of the standing feet's contact points: the
//! smallest convex region holding all of them. This is its *support polygon*. Feet that are
//! in the air (swinging) must be left out by the caller; every point passed counts as a
//! standing foot.
//!
//! The hull is computed with Andrew's monotone chain: sort the points by X then Y, build the
//! lower and the upper chain keeping only counter-clockwise turns, and join them. A final
//! pass drops vertices that are within rounding of the line through their neighbours, so a
//! nearly straight row of feet makes a segment, not a sliver of a triangle.

use nalgebra::Point2;

use crate::error::StabilityError;
use crate::polygon::{Polygon, cross};

/// Relative tolerance: vertices closer than this fraction of the largest coordinate to
/// another vertex, or to the line through their neighbours, are dropped.
const RELATIVE_TOLERANCE: f64 = 1e-12;

/// The support polygon of the standing feet: the convex hull of their contact points,
/// projected onto the XY plane.
///
/// Fewer than three feet not on one line give a degenerate polygon (empty, a point or a
/// segment), which contains nothing and has no positive margin anywhere.
///
/// This function never fails: if any coordinate is NaN or infinite it returns the **empty**
/// polygon, so that a robot with an unknown foot position counts as unsupported. Use
/// [`Polygon::convex_hull`] to get an error instead.
pub fn support_polygon(feet: &[Point2<f64>]) -> Polygon {
    Polygon::convex_hull(feet).unwrap_or_else(|_| Polygon::empty())
}

/// Refuses the first point with a NaN or infinite coordinate.
pub(crate) fn check_finite(points: &[Point2<f64>]) -> Result<(), StabilityError> {
    match points
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        Some(index) => Err(StabilityError::NonFinitePoint {
            index,
            x: points[index].x,
            y: points[index].y,
        }),
        None => Ok(()),
    }
}

/// The absolute tolerance for a set of points: [`RELATIVE_TOLERANCE`] times the largest
/// absolute coordinate.
pub(crate) fn tolerance<'a>(points: impl IntoIterator<Item = &'a Point2<f64>>) -> f64 {
    let scale = points
        .into_iter()
        .map(|p| p.x.abs().max(p.y.abs()))
        .fold(0.0, f64::max);
    RELATIVE_TOLERANCE * scale
}

/// The hull vertices of finite `points`, counter-clockwise from the lowest X (then Y),
/// cleaned as described in the module documentation.
pub(crate) fn convex_hull_of_finite(points: &[Point2<f64>]) -> Vec<Point2<f64>> {
    // Adding 0.0 turns -0.0 into 0.0, so the sort below agrees with `==`.
    let mut pts: Vec<Point2<f64>> = points
        .iter()
        .map(|p| Point2::new(p.x + 0.0, p.y + 0.0))
        .collect();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    let tol = tolerance(&pts);
    if pts.len() < 3 {
        return clean(pts, tol);
    }
    let mut lower: Vec<Point2<f64>> = Vec::with_capacity(pts.len());
    for &p in &pts {
        push_turning_left(&mut lower, p);
    }
    let mut upper: Vec<Point2<f64>> = Vec::with_capacity(pts.len());
    for &p in pts.iter().rev() {
        push_turning_left(&mut upper, p);
    }
    // Each chain ends where the other starts.
    lower.pop();
    upper.pop();
    lower.extend(upper);
    clean(lower, tol)
}

/// Appends `p` to a monotone chain after popping every vertex that would not make a strict
/// left turn.
fn push_turning_left(chain: &mut Vec<Point2<f64>>, p: Point2<f64>) {
    while let [.., a, b] = chain.as_slice() {
        if cross(b - a, p - b) > 0.0 {
            break;
        }
        chain.pop();
    }
    chain.push(p);
}

/// Removes vertices of a counter-clockwise convex loop that are within `tol` of their
/// predecessor, then vertices within `tol` of the chord joining their neighbours (and lying
/// over that chord), until none is left to remove; then turns the loop to start at its
/// lowest X (then Y) vertex.
fn clean(mut v: Vec<Point2<f64>>, tol: f64) -> Vec<Point2<f64>> {
    loop {
        let n = v.len();
        if n <= 1 {
            return v;
        }
        if n == 2 {
            if (v[1] - v[0]).norm() <= tol {
                v.truncate(1);
            }
            return start_at_lowest(v);
        }
        let near_duplicate = (0..n).find(|&i| (v[i] - v[(i + n - 1) % n]).norm() <= tol);
        let removable = near_duplicate.or_else(|| {
            (0..n).find(|&i| {
                let (prev, cur, next) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
                let chord = next - prev;
                let len = chord.norm();
                if len <= tol {
                    return false;
                }
                // Height of `cur` outside the chord (positive for a convex corner) and where
                // it falls along the chord.
                let height = cross(cur - prev, chord) / len;
                let along = (cur - prev).dot(&chord) / len;
                height <= tol && along >= -tol && along <= len + tol
            })
        });
        match removable {
            Some(i) => {
                v.remove(i);
            }
            None => return start_at_lowest(v),
        }
    }
}

/// Rotates a loop so that it starts at its lowest X (then Y) vertex.
fn start_at_lowest(mut v: Vec<Point2<f64>>) -> Vec<Point2<f64>> {
    let lowest = (0..v.len())
        .min_by(|&i, &j| v[i].x.total_cmp(&v[j].x).then(v[i].y.total_cmp(&v[j].y)))
        .unwrap_or(0);
    v.rotate_left(lowest);
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    #[test]
    fn square_with_interior_edge_and_duplicate_points() {
        let feet = [
            p(1.0, 1.0),
            p(0.0, 0.0),
            p(0.5, 0.5),
            p(1.0, 0.0),
            p(0.5, 0.0),
            p(0.0, 1.0),
            p(1.0, 1.0),
            p(0.0, 0.5),
        ];
        let hull = support_polygon(&feet);
        assert_eq!(
            hull.vertices(),
            &[p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]
        );
    }

    #[test]
    fn collinear_feet_give_a_segment() {
        let feet = [p(0.0, 0.0), p(3.0, 3.0), p(1.0, 1.0), p(2.0, 2.0)];
        let hull = support_polygon(&feet);
        assert_eq!(hull.vertices(), &[p(0.0, 0.0), p(3.0, 3.0)]);
        assert!(hull.is_degenerate());
        assert!(!hull.contains(p(1.5, 1.5)));
    }

    #[test]
    fn nearly_collinear_feet_give_a_segment() {
        let feet = [p(0.0, 0.0), p(1.0, 1e-15), p(2.0, 0.0)];
        assert_eq!(
            support_polygon(&feet).vertices(),
            &[p(0.0, 0.0), p(2.0, 0.0)]
        );
    }

    #[test]
    fn thin_but_real_triangle_is_kept() {
        let feet = [p(0.0, 0.0), p(1.0, 1e-6), p(2.0, 0.0)];
        assert_eq!(support_polygon(&feet).len(), 3);
    }

    #[test]
    fn few_feet() {
        assert!(support_polygon(&[]).is_empty());
        assert_eq!(support_polygon(&[p(1.0, 2.0)]).vertices(), &[p(1.0, 2.0)]);
        assert_eq!(
            support_polygon(&[p(1.0, 2.0), p(1.0, 2.0)]).vertices(),
            &[p(1.0, 2.0)]
        );
        assert_eq!(
            support_polygon(&[p(0.0, 0.0), p(-0.0, -0.0)]).vertices(),
            &[p(0.0, 0.0)]
        );
    }

    #[test]
    fn triangle_is_counter_clockwise_whatever_the_input_order() {
        let hull = support_polygon(&[p(0.0, 1.0), p(1.0, 0.0), p(0.0, 0.0)]);
        assert_eq!(hull.vertices(), &[p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)]);
        assert!(hull.area() > 0.0);
    }

    #[test]
    fn non_finite_foot_gives_empty_support() {
        let feet = [p(0.0, 0.0), p(1.0, 0.0), p(f64::INFINITY, 1.0), p(0.0, 1.0)];
        assert!(support_polygon(&feet).is_empty());
        let err = Polygon::convex_hull(&feet).unwrap_err();
        assert_eq!(
            err,
            StabilityError::NonFinitePoint {
                index: 2,
                x: f64::INFINITY,
                y: 1.0
            }
        );
    }
}
