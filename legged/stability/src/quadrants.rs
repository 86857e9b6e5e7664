//! The quadrant test on candidate footholds about the centre of gravity.
//!
//! This is the quadrant test of Eldershaw and Yim's planning in "CG-space": it divides the
//! ground plane about the projected centre of gravity (CG) into the four quadrants of the
//! body frame, a frame turned from the world axes by the heading, and reports which
//! quadrants hold at least one candidate foothold (a point some leg can reach and stand on).
//! A quadrant with no foothold means no foot can be placed on that side of the CG.
//!
//! # Frames
//!
//! The heading `theta` is measured counter-clockwise from world +X (east), as a yaw in ROS
//! REP 103. The body frame has +x forward along the heading and +y to the left, so a point
//! `p` has body coordinates `forward = (p - cg) . (cos theta, sin theta)` and
//! `left = (p - cg) . (-sin theta, cos theta)`.
//!
//! # Open quadrants
//!
//! The quadrants are open: a point exactly on either axis through the CG (or at the CG) is in
//! none of them and is listed separately. With open quadrants the test has a simple exact
//! meaning: if all four hold a point, the CG lies strictly inside the convex hull of the
//! points. (Otherwise some line through the CG would have every point on one side, and the
//! opposite quadrant would be empty.) The converse does not hold: three footholds round the
//! CG can enclose it while leaving a quadrant empty. So an empty quadrant warns of poor
//! footing on that side rather than proving the position cannot be supported.

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::error::StabilityError;
use crate::hull;

/// One of the four open quadrants about the CG, in the body frame (+x forward, +y left).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Quadrant {
    /// Forward and left: body x > 0, y > 0.
    FrontLeft,
    /// Behind and left: body x < 0, y > 0.
    RearLeft,
    /// Behind and right: body x < 0, y < 0.
    RearRight,
    /// Forward and right: body x > 0, y < 0.
    FrontRight,
}

impl Quadrant {
    /// All four, counter-clockwise from front-left (the order of the report's counts).
    pub const ALL: [Quadrant; 4] = [
        Quadrant::FrontLeft,
        Quadrant::RearLeft,
        Quadrant::RearRight,
        Quadrant::FrontRight,
    ];

    /// The quadrant about `cg` holding `point` in the body frame turned by `heading_rad`
    /// (counter-clockwise from world +X). `None` if the point is exactly on an axis (after
    /// rounding of the rotation) or any input is NaN or infinite.
    pub fn of(cg: Point2<f64>, heading_rad: f64, point: Point2<f64>) -> Option<Quadrant> {
        let (sin, cos) = heading_rad.sin_cos();
        let r = point - cg;
        let forward = r.x * cos + r.y * sin;
        let left = -r.x * sin + r.y * cos;
        match (forward > 0.0, forward < 0.0, left > 0.0, left < 0.0) {
            (true, _, true, _) => Some(Quadrant::FrontLeft),
            (_, true, true, _) => Some(Quadrant::RearLeft),
            (_, true, _, true) => Some(Quadrant::RearRight),
            (true, _, _, true) => Some(Quadrant::FrontRight),
            _ => None,
        }
    }

    /// Position in [`Quadrant::ALL`].
    fn index(self) -> usize {
        match self {
            Quadrant::FrontLeft => 0,
            Quadrant::RearLeft => 1,
            Quadrant::RearRight => 2,
            Quadrant::FrontRight => 3,
        }
    }
}

/// Which candidate footholds fall in which quadrant, by their index in the slice given to
/// [`quadrant_test`]; indices let callers map points back to the legs that can reach them.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct QuadrantReport {
    members: [Vec<usize>; 4],
    on_axes: Vec<usize>,
}

impl QuadrantReport {
    /// Indices of the points in `quadrant`, in input order.
    pub fn members(&self, quadrant: Quadrant) -> &[usize] {
        &self.members[quadrant.index()]
    }

    /// Number of points in `quadrant`.
    pub fn count(&self, quadrant: Quadrant) -> usize {
        self.members[quadrant.index()].len()
    }

    /// Whether `quadrant` holds at least one point.
    pub fn is_occupied(&self, quadrant: Quadrant) -> bool {
        !self.members[quadrant.index()].is_empty()
    }

    /// The quadrants holding no point, in the order of [`Quadrant::ALL`].
    pub fn empty_quadrants(&self) -> Vec<Quadrant> {
        Quadrant::ALL
            .into_iter()
            .filter(|&q| !self.is_occupied(q))
            .collect()
    }

    /// Whether every quadrant holds a point (then the CG is strictly inside the points'
    /// convex hull; see the [module documentation](self)).
    pub fn all_occupied(&self) -> bool {
        Quadrant::ALL.into_iter().all(|q| self.is_occupied(q))
    }

    /// Indices of the points exactly on an axis through the CG, which count in no quadrant.
    pub fn on_axes(&self) -> &[usize] {
        &self.on_axes
    }
}

/// Sorts candidate footholds `points` into the four quadrants about `cg` in the body frame
/// turned by `heading_rad` (counter-clockwise from world +X), reporting which are empty.
///
/// # Errors
///
/// [`StabilityError::NonFiniteCentre`], [`StabilityError::NonFiniteHeading`] or
/// [`StabilityError::NonFinitePoint`] for NaN or infinite input.
pub fn quadrant_test(
    cg: Point2<f64>,
    heading_rad: f64,
    points: &[Point2<f64>],
) -> Result<QuadrantReport, StabilityError> {
    if !(cg.x.is_finite() && cg.y.is_finite()) {
        return Err(StabilityError::NonFiniteCentre { x: cg.x, y: cg.y });
    }
    if !heading_rad.is_finite() {
        return Err(StabilityError::NonFiniteHeading(heading_rad));
    }
    hull::check_finite(points)?;
    let mut report = QuadrantReport::default();
    for (i, &p) in points.iter().enumerate() {
        match Quadrant::of(cg, heading_rad, p) {
            Some(q) => report.members[q.index()].push(i),
            None => report.on_axes.push(i),
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    #[test]
    fn heading_east_uses_world_axes() {
        let cg = p(1.0, 1.0);
        assert_eq!(
            Quadrant::of(cg, 0.0, p(2.0, 2.0)),
            Some(Quadrant::FrontLeft)
        );
        assert_eq!(Quadrant::of(cg, 0.0, p(0.0, 2.0)), Some(Quadrant::RearLeft));
        assert_eq!(
            Quadrant::of(cg, 0.0, p(0.0, 0.0)),
            Some(Quadrant::RearRight)
        );
        assert_eq!(
            Quadrant::of(cg, 0.0, p(2.0, 0.0)),
            Some(Quadrant::FrontRight)
        );
        assert_eq!(Quadrant::of(cg, 0.0, p(2.0, 1.0)), None);
        assert_eq!(Quadrant::of(cg, 0.0, cg), None);
        assert_eq!(Quadrant::of(cg, f64::NAN, p(2.0, 2.0)), None);
    }

    #[test]
    fn heading_north_turns_the_quadrants() {
        // Facing north, forward is +Y and left is -X.
        let cg = p(0.0, 0.0);
        assert_eq!(
            Quadrant::of(cg, FRAC_PI_2, p(-1.0, 1.0)),
            Some(Quadrant::FrontLeft)
        );
        assert_eq!(
            Quadrant::of(cg, FRAC_PI_2, p(1.0, 1.0)),
            Some(Quadrant::FrontRight)
        );
        assert_eq!(
            Quadrant::of(cg, FRAC_PI_2, p(1.0, -1.0)),
            Some(Quadrant::RearRight)
        );
    }

    #[test]
    fn report_lists_empty_quadrants() {
        let points = [p(1.0, 1.0), p(-1.0, 1.0), p(2.0, 0.5), p(0.0, -1.0)];
        let r = quadrant_test(p(0.0, 0.0), 0.0, &points).unwrap();
        assert_eq!(r.members(Quadrant::FrontLeft), &[0, 2]);
        assert_eq!(r.count(Quadrant::RearLeft), 1);
        assert_eq!(
            r.empty_quadrants(),
            vec![Quadrant::RearRight, Quadrant::FrontRight]
        );
        assert_eq!(r.on_axes(), &[3]);
        assert!(!r.all_occupied());
    }

    #[test]
    fn enclosing_triangle_can_leave_a_quadrant_empty() {
        let points = [p(1.0, 1.0), p(-1.0, 1.0), p(0.5, -2.0)];
        let r = quadrant_test(p(0.0, 0.0), 0.0, &points).unwrap();
        assert_eq!(r.empty_quadrants(), vec![Quadrant::RearRight]);
        assert!(crate::hull::support_polygon(&points).contains(p(0.0, 0.0)));
    }

    #[test]
    fn refuses_non_finite_input() {
        let pts = [p(1.0, 1.0)];
        assert!(matches!(
            quadrant_test(p(f64::NAN, 0.0), 0.0, &pts),
            Err(StabilityError::NonFiniteCentre { .. })
        ));
        assert_eq!(
            quadrant_test(p(0.0, 0.0), f64::INFINITY, &pts),
            Err(StabilityError::NonFiniteHeading(f64::INFINITY))
        );
        assert!(matches!(
            quadrant_test(p(0.0, 0.0), 0.0, &[p(1.0, 1.0), p(0.0, f64::NAN)]),
            Err(StabilityError::NonFinitePoint { index: 1, .. })
        ));
        assert!(
            quadrant_test(p(0.0, 0.0), 0.0, &[])
                .unwrap()
                .empty_quadrants()
                .len()
                == 4
        );
    }
}
