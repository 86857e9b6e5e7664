//! Parts of the robot touching each other: every collision shape filled by capsules, the
//! links of different legs tested pairwise, and points over every leg link beyond its
//! first joint (a box's surface, a cylinder's or capsule's axis with its radius) tested
//! against the body's own shapes.

use nalgebra::Point3;

use crate::error::KinematicsError;
use crate::model::RobotModel;
use crate::shape::PlacedShape;

/// Two parts of the robot that touch.
#[derive(Debug, Clone, PartialEq)]
pub struct SelfContact {
    /// One link.
    pub first: String,
    /// The other link (the body's for a leg link inside the body).
    pub second: String,
    /// How far apart the axes of their nearest capsules are, metres (less than the sum of
    /// the radii).
    pub distance_m: f64,
}

impl std::fmt::Display for SelfContact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "links `{}` and `{}` touch", self.first, self.second)
    }
}

/// Spacing of the points over a leg link's shape tested against the body's box, metres.
const BODY_TEST_SPACING_M: f64 = 0.01;

impl RobotModel {
    /// The first pair of parts touching in `posture` (joint positions per leg, model order):
    /// two links of different legs whose capsules overlap, or a leg's link beyond
    /// its first joint reaching into one of the body's shapes. `None` when no
    /// parts touch.
    pub fn self_contact<Q: AsRef<[f64]>>(
        &self,
        posture: &[Q],
    ) -> Result<Option<SelfContact>, KinematicsError> {
        let shapes = self.collision_shapes(posture)?;
        let (legs, body) = self.split_capsules(&shapes);
        if let Some(contact) = legs_touching(&legs, None, 0.0) {
            return Ok(Some(contact));
        }
        let mut seen = std::collections::HashSet::new();
        for &(_, s, ..) in &legs {
            if self.link(s.link).is_none_or(|l| l.stage() <= 1) || !seen.insert(s.link) {
                continue;
            }
            // Only the body's shapes whose bounding balls meet this one's can hold its points.
            let near: Vec<&PlacedShape<'_>> = body
                .iter()
                .copied()
                .filter(|b| {
                    (b.pose.translation.vector - s.pose.translation.vector).norm()
                        <= b.shape.bounding_radius() + s.shape.bounding_radius()
                })
                .collect();
            if near.is_empty() {
                continue;
            }
            for (point, r) in s.shape.surface_points(BODY_TEST_SPACING_M) {
                let world = s.pose * point;
                for b in &near {
                    if b.shape.holds_ball(&(b.pose.inverse() * world), r) {
                        return Ok(Some(SelfContact {
                            first: s.link.to_owned(),
                            second: b.link.to_owned(),
                            distance_m: 0.0,
                        }));
                    }
                }
            }
        }
        Ok(None)
    }

    /// The first pair of links of different legs whose capsules, each widened by
    /// `margin_m`, overlap in `posture`; with `leg` given, only pairs with one link on that
    /// leg. The body's shapes are not tested: this is the cheap check a planner makes at
    /// every sample of a move (a few microseconds for six legs).
    pub fn legs_touching<Q: AsRef<[f64]>>(
        &self,
        posture: &[Q],
        leg: Option<usize>,
        margin_m: f64,
    ) -> Result<Option<SelfContact>, KinematicsError> {
        let shapes = self.collision_shapes(posture)?;
        let (legs, _) = self.split_capsules(&shapes);
        Ok(legs_touching(&legs, leg, margin_m))
    }

    /// The capsules of the legs' shapes (with the leg each belongs to) and the body's
    /// shapes.
    fn split_capsules<'a>(
        &self,
        shapes: &'a [PlacedShape<'a>],
    ) -> (Vec<LegCapsule<'a>>, Vec<&'a PlacedShape<'a>>) {
        let mut legs = Vec::new();
        let mut body = Vec::new();
        for s in shapes {
            match self.link(s.link).and_then(|l| l.leg()) {
                Some(leg) => {
                    let ball = (
                        Point3::from(s.pose.translation.vector),
                        s.shape.bounding_radius(),
                    );
                    for (a, b, r) in s.shape.capsules() {
                        legs.push((leg, s, s.pose * a, s.pose * b, r, ball));
                    }
                }
                None => body.push(s),
            }
        }
        (legs, body)
    }
}

/// A capsule of a leg's shape: the leg, the shape, the axis's ends, the radius, and the
/// ball that holds the whole shape (centre, radius).
type LegCapsule<'a> = (
    usize,
    &'a PlacedShape<'a>,
    Point3<f64>,
    Point3<f64>,
    f64,
    (Point3<f64>, f64),
);

/// The first pair of capsules of different legs (one of them on `only`, when given) closer
/// than their radii plus twice `margin_m`.
fn legs_touching(
    legs: &[LegCapsule<'_>],
    only: Option<usize>,
    margin_m: f64,
) -> Option<SelfContact> {
    for (i, a) in legs.iter().enumerate() {
        for b in legs.iter().skip(i + 1) {
            if a.0 == b.0 || only.is_some_and(|l| a.0 != l && b.0 != l) {
                continue;
            }
            // Shapes whose bounding balls are apart cannot touch.
            let reach = a.5.1 + b.5.1 + 2.0 * margin_m;
            if (a.5.0 - b.5.0).norm_squared() > reach * reach {
                continue;
            }
            let d = segment_distance(a.2, a.3, b.2, b.3);
            if d < a.4 + b.4 + 2.0 * margin_m {
                return Some(SelfContact {
                    first: a.1.link.to_owned(),
                    second: b.1.link.to_owned(),
                    distance_m: d,
                });
            }
        }
    }
    None
}

/// The closest distance between the segments `a0 a1` and `b0 b1`, metres.
pub fn segment_distance(a0: Point3<f64>, a1: Point3<f64>, b0: Point3<f64>, b1: Point3<f64>) -> f64 {
    let (d1, d2, r) = (a1 - a0, b1 - b0, a0 - b0);
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let eps = 1e-12;
    if a <= eps && e <= eps {
        return r.norm();
    }
    let (s, t) = if a <= eps {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= eps {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let s0 = if denom > eps {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t0 > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s0, t0)
            }
        }
    };
    ((a0 + d1 * s) - (b0 + d2 * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn segment_distance_is_symmetric_and_no_sampled_pair_is_closer(
            a in prop::array::uniform3(-1.0..1.0f64),
            b in prop::array::uniform3(-1.0..1.0f64),
            c in prop::array::uniform3(-1.0..1.0f64),
            d in prop::array::uniform3(-1.0..1.0f64),
        ) {
            let (a, b, c, d) = (Point3::from(a), Point3::from(b), Point3::from(c), Point3::from(d));
            let s = segment_distance(a, b, c, d);
            prop_assert!((s - segment_distance(c, d, a, b)).abs() < 1e-9);
            prop_assert!(s >= 0.0);
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
    fn a_boxs_capsules_stay_inside_it_and_fill_its_middle() {
        let size = nalgebra::Vector3::new(1.5, 0.25, 0.2);
        let shape = crate::Shape::Box { size };
        let capsules = shape.capsules();
        assert_eq!(capsules.len(), 2);
        for (a, b, r) in &capsules {
            for p in [a, b] {
                for k in 0..3 {
                    assert!(p[k].abs() + r <= size[k] / 2.0 + 1e-12, "{p:?} {r}");
                }
            }
        }
        // Two such boxes stacked 0.3 m apart (0.1 m of air between them) do not touch.
        let lift = nalgebra::Vector3::new(0.0, 0.0, 0.3);
        for (a, b, r) in &capsules {
            for (c, d, q) in &capsules {
                assert!(segment_distance(*a, *b, c + lift, d + lift) > r + q);
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

    #[test]
    fn the_shipped_robots_standing_neutral_touch_nowhere() {
        for r in crate::BUILTIN_ROBOTS {
            let model = RobotModel::builtin(r.name).unwrap();
            let contact = model.self_contact(&model.neutral_posture()).unwrap();
            assert!(contact.is_none(), "{}: {contact:?}", r.name);
        }
    }

    #[test]
    fn legs_swung_into_each_other_touch() {
        let model = RobotModel::builtin("hexapod").unwrap();
        let front = model.leg_index("left_front").unwrap();
        let middle = model.leg_index("left_middle").unwrap();
        let range = |leg: usize| model.legs()[leg].joints()[0].limits();
        let (f, m) = (range(front), range(middle));
        let mut touched = 0;
        for i in 0..=10 {
            for j in 0..=10 {
                let mut p = model.neutral_posture();
                p[front][0] = f.lower + (f.upper - f.lower) * f64::from(i) / 10.0;
                p[middle][0] = m.lower + (m.upper - m.lower) * f64::from(j) / 10.0;
                if let Some(c) = model.self_contact(&p).unwrap() {
                    assert!(
                        c.first.starts_with("left_") && c.second.starts_with("left_"),
                        "{c:?}"
                    );
                    touched += 1;
                }
            }
        }
        assert!(
            touched > 0,
            "the front and middle legs meet when their hips turn toward each other"
        );
        assert!(touched < 121, "but not everywhere");
    }

    #[test]
    fn the_legs_only_check_finds_what_the_full_check_finds_between_legs() {
        let model = RobotModel::builtin("hexapod").unwrap();
        let front = model.leg_index("left_front").unwrap();
        let middle = model.leg_index("left_middle").unwrap();
        let rear = model.leg_index("right_rear").unwrap();
        let range = |leg: usize| model.legs()[leg].joints()[0].limits();
        let (f, m) = (range(front), range(middle));
        let (mut both, mut widened) = (0, 0);
        for i in 0..=10 {
            for j in 0..=10 {
                let mut p = model.neutral_posture();
                p[front][0] = f.lower + (f.upper - f.lower) * f64::from(i) / 10.0;
                p[middle][0] = m.lower + (m.upper - m.lower) * f64::from(j) / 10.0;
                let full = model.self_contact(&p).unwrap();
                let legs = model.legs_touching(&p, None, 0.0).unwrap();
                assert_eq!(full.is_some(), legs.is_some(), "{full:?} {legs:?}");
                // Asked about one of the two legs, the same; about a leg far away, nothing.
                assert_eq!(
                    model.legs_touching(&p, Some(front), 0.0).unwrap().is_some(),
                    legs.is_some()
                );
                assert!(model.legs_touching(&p, Some(rear), 0.0).unwrap().is_none());
                both += usize::from(legs.is_some());
                widened += usize::from(model.legs_touching(&p, None, 0.01).unwrap().is_some());
            }
        }
        assert!(both > 0);
        assert!(
            widened > both,
            "a margin finds more near misses: {widened} vs {both}"
        );
    }
}
