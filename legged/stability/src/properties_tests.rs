//! Property tests of the stability geometry against brute-force definitions.
//!
//! Coordinates are drawn from a continuous range, from a coarse half-metre grid, and from that
//! grid nudged by 1e-15 to 1e-7 m, so that duplicate, nearly duplicate, collinear and nearly
//! collinear feet, and feet on or just off edges, turn up often.

use crate::{
    Polygon, Quadrant, centre_of_mass, conservative_support_polygon, margin_along,
    margin_along_path, quadrant_test, stability_margin, support_polygon,
};
use nalgebra::{Point2, Point3};
use proptest::prelude::*;

/// Absolute tolerance for comparisons, metres (coordinates are within 5 m of the origin).
const EPS: f64 = 1e-9;

fn coordinate() -> impl Strategy<Value = f64> {
    let grid = (-4i32..=4).prop_map(|k| f64::from(k) * 0.5);
    let jitter = prop::sample::select(vec![1e-15, -1e-13, 1e-11, -1e-9, 1e-7]);
    prop_oneof![
        -5.0..5.0f64,
        grid.clone(),
        (grid, jitter).prop_map(|(g, j)| g + j),
    ]
}

fn point() -> impl Strategy<Value = Point2<f64>> {
    (coordinate(), coordinate()).prop_map(|(x, y)| Point2::new(x, y))
}

fn points(max: usize) -> impl Strategy<Value = Vec<Point2<f64>>> {
    prop::collection::vec(point(), 0..=max)
}

fn query() -> impl Strategy<Value = Point2<f64>> {
    (-7.0..7.0f64, -7.0..7.0f64).prop_map(|(x, y)| Point2::new(x, y))
}

fn cross(o: Point2<f64>, a: Point2<f64>, b: Point2<f64>) -> f64 {
    let (u, v) = (a - o, b - o);
    u.x * v.y - u.y * v.x
}

fn segment_distance(p: Point2<f64>, a: Point2<f64>, b: Point2<f64>) -> f64 {
    let e = b - a;
    let t = ((p - a).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
    (p - (a + e * t)).norm()
}

/// Distance to the polygon's boundary by brute force over its edges (or its point).
fn boundary_distance(poly: &Polygon, p: Point2<f64>) -> f64 {
    match poly.vertices() {
        [] => f64::INFINITY,
        [a] => (p - a).norm(),
        vs => (0..vs.len())
            .map(|i| segment_distance(p, vs[i], vs[(i + 1) % vs.len()]))
            .fold(f64::INFINITY, f64::min),
    }
}

/// The support polygons left by lifting each foot in turn.
fn leave_one_out(feet: &[Point2<f64>]) -> Vec<Polygon> {
    (0..feet.len())
        .map(|i| {
            let mut others = feet.to_vec();
            others.remove(i);
            support_polygon(&others)
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn hull_contains_every_input_point(feet in points(10)) {
        let hull = support_polygon(&feet);
        for &f in &feet {
            prop_assert!(hull.signed_distance(f) >= -EPS, "{f:?} outside {hull:?}");
        }
    }

    #[test]
    fn hull_is_strictly_convex_counter_clockwise_and_made_of_input_points(feet in points(10)) {
        let hull = support_polygon(&feet);
        let vs = hull.vertices();
        for v in vs {
            prop_assert!(feet.contains(v));
        }
        if vs.len() >= 3 {
            prop_assert!(hull.area() > 0.0);
            for i in 0..vs.len() {
                let (a, b, c) = (vs[i], vs[(i + 1) % vs.len()], vs[(i + 2) % vs.len()]);
                prop_assert!(cross(a, b, c) > 0.0, "turn at {b:?} in {vs:?}");
            }
        }
        if vs.len() == 2 {
            prop_assert!(vs[0] != vs[1]);
        }
        prop_assert_eq!(hull.is_empty(), feet.is_empty());
    }

    #[test]
    fn hull_is_idempotent_and_independent_of_order(feet in points(10)) {
        let hull = support_polygon(&feet);
        prop_assert_eq!(&support_polygon(hull.vertices()), &hull);
        let mut reversed = feet.clone();
        reversed.reverse();
        prop_assert_eq!(&support_polygon(&reversed), &hull);
        let mut rotated = feet.clone();
        if !rotated.is_empty() {
            rotated.rotate_left(1);
        }
        prop_assert_eq!(&support_polygon(&rotated), &hull);
    }

    #[test]
    fn signed_distance_matches_brute_force(feet in points(10), q in query()) {
        let hull = support_polygon(&feet);
        let sd = hull.signed_distance(q);
        if hull.is_empty() {
            prop_assert_eq!(sd, f64::NEG_INFINITY);
        } else {
            prop_assert!((sd.abs() - boundary_distance(&hull, q)).abs() <= EPS);
        }
    }

    #[test]
    fn margin_sign_agrees_with_contains(feet in points(10), q in query()) {
        let hull = support_polygon(&feet);
        let sd = hull.signed_distance(q);
        if sd > 0.0 {
            prop_assert!(hull.contains(q));
        }
        if sd < 0.0 {
            prop_assert!(!hull.contains(q));
        }
        if hull.is_degenerate() {
            prop_assert!(sd <= 0.0);
            prop_assert!(!hull.contains(q));
        } else {
            prop_assert_eq!(hull.contains(q), sd >= 0.0);
        }
    }

    #[test]
    fn intersection_is_the_common_part(a in points(8), b in points(8), q in query()) {
        let (pa, pb) = (support_polygon(&a), support_polygon(&b));
        let i = pa.intersection(&pb);
        for &v in i.vertices() {
            prop_assert!(pa.signed_distance(v) >= -EPS);
            prop_assert!(pb.signed_distance(v) >= -EPS);
        }
        // Inside both, the nearest boundary of the intersection is the nearer of the two
        // boundaries; anywhere, the intersection is no nearer to containing q than either.
        let (da, db, di) = (pa.signed_distance(q), pb.signed_distance(q), i.signed_distance(q));
        let lower = da.min(db);
        prop_assert!(di <= lower + EPS, "{di} > min({da}, {db})");
        if da > 0.0 && db > 0.0 {
            prop_assert!((di - lower).abs() <= EPS, "{di} != min({da}, {db})");
        }
        let j = pb.intersection(&pa);
        prop_assert!((i.area() - j.area()).abs() <= EPS);
    }

    #[test]
    fn conservative_polygon_lies_inside_the_support_polygon(feet in points(8)) {
        let support = support_polygon(&feet);
        let conservative = conservative_support_polygon(&feet);
        if feet.len() < 4 {
            prop_assert!(conservative.is_empty());
        }
        for &v in conservative.vertices() {
            prop_assert!(support.signed_distance(v) >= -EPS, "{v:?} outside {support:?}");
        }
        prop_assert!(conservative.area() <= support.area() + EPS);
    }

    #[test]
    fn conservative_polygon_is_the_leave_one_out_intersection(
        feet in prop::collection::vec(point(), 4..=8),
        q in query(),
    ) {
        let conservative = conservative_support_polygon(&feet);
        let remaining = leave_one_out(&feet);
        for &v in conservative.vertices() {
            for r in &remaining {
                prop_assert!(r.signed_distance(v) >= -EPS);
            }
        }
        let lower = remaining
            .iter()
            .map(|r| r.signed_distance(q))
            .fold(f64::INFINITY, f64::min);
        let dc = conservative.signed_distance(q);
        prop_assert!(dc <= lower + EPS);
        if lower > 0.0 {
            prop_assert!((dc - lower).abs() <= EPS, "{dc} != {lower}");
        }
    }

    #[test]
    fn conservative_polygon_moves_with_the_feet(
        feet in points(8),
        dx in -100.0..100.0f64,
        dy in -100.0..100.0f64,
    ) {
        let shifted: Vec<_> = feet.iter().map(|f| Point2::new(f.x + dx, f.y + dy)).collect();
        let (a, b) = (conservative_support_polygon(&feet), conservative_support_polygon(&shifted));
        // Rounding differs after the move, and near a degenerate arrangement of feet (all
        // nearly on a line, say) the intersection jumps between a point, a segment and
        // nothing under tiny changes. Its area does not jump; its shape does not either once
        // it has a real interior.
        let d = nalgebra::Vector2::new(dx, dy);
        prop_assert!((a.area() - b.area()).abs() <= 1e-8);
        if a.area() <= 1e-6 {
            return Ok(());
        }
        for &v in a.vertices() {
            prop_assert!(b.signed_distance(v + d) >= -1e-8);
        }
        for &v in b.vertices() {
            prop_assert!(a.signed_distance(v - d) >= -1e-8);
        }
    }

    #[test]
    fn margin_along_a_segment_is_its_minimum(
        feet in points(8),
        from in query(),
        to in query(),
        (z0, z1) in (-1.0..1.0f64, -1.0..1.0f64),
        t in 0.0..=1.0f64,
    ) {
        let support = support_polygon(&feet);
        let (a, b) = (Point3::new(from.x, from.y, z0), Point3::new(to.x, to.y, z1));
        let min = margin_along(&support, a, b);
        let (ma, mb) = (stability_margin(&support, a), stability_margin(&support, b));
        prop_assert_eq!(min.margin_m, ma.min(mb));
        prop_assert!(min.at == a || min.at == b);
        // Concavity: no point of the segment is below the chord of the end margins, so none
        // is below the smaller end.
        let on = a + (b - a) * t;
        let m = stability_margin(&support, on);
        let chord = ma + (mb - ma) * t;
        if chord.is_finite() {
            prop_assert!(m >= chord - EPS, "{m} below chord {chord}");
        }
        prop_assert!(m >= min.margin_m - EPS, "{m} below the end minimum {}", min.margin_m);
    }

    #[test]
    fn margin_along_a_path_is_the_smallest_segment_minimum(
        feet in points(8),
        path in prop::collection::vec(query(), 1..6),
    ) {
        let support = support_polygon(&feet);
        let path: Vec<_> = path.iter().map(|p| Point3::new(p.x, p.y, 0.5)).collect();
        let whole = margin_along_path(&support, &path).unwrap();
        let by_segments = path
            .windows(2)
            .map(|w| margin_along(&support, w[0], w[1]).margin_m)
            .fold(stability_margin(&support, path[0]), f64::min);
        prop_assert_eq!(whole.margin_m, by_segments);
    }

    #[test]
    fn occupied_quadrants_enclose_the_cg(
        cg in query(),
        heading in -10.0..10.0f64,
        candidates in points(10),
    ) {
        let report = quadrant_test(cg, heading, &candidates).unwrap();
        let mut seen: Vec<usize> = Quadrant::ALL
            .into_iter()
            .flat_map(|q| report.members(q).to_vec())
            .chain(report.on_axes().iter().copied())
            .collect();
        seen.sort_unstable();
        prop_assert_eq!(seen, (0..candidates.len()).collect::<Vec<_>>());
        for q in Quadrant::ALL {
            for &i in report.members(q) {
                prop_assert_eq!(Quadrant::of(cg, heading, candidates[i]), Some(q));
            }
            prop_assert_eq!(report.is_occupied(q), !report.empty_quadrants().contains(&q));
        }
        if report.all_occupied() {
            prop_assert!(support_polygon(&candidates).signed_distance(cg) >= -EPS);
        }
    }

    #[test]
    fn centre_of_mass_is_a_weighted_mean(
        links in prop::collection::vec(
            (0.0..50.0f64, -5.0..5.0f64, -5.0..5.0f64, -5.0..5.0f64),
            1..8,
        ),
        shift in (-100.0..100.0f64, -100.0..100.0f64, -100.0..100.0f64),
        scale in 0.01..100.0f64,
    ) {
        let links: Vec<_> = links
            .into_iter()
            .map(|(m, x, y, z)| (m, Point3::new(x, y, z)))
            .collect();
        let total: f64 = links.iter().map(|l| l.0).sum();
        let Ok(com) = centre_of_mass(&links) else {
            prop_assert!(total <= 0.0);
            return Ok(());
        };
        // Inside the bounding box of the links that have mass.
        for axis in 0..3 {
            let massive = links.iter().filter(|l| l.0 > 0.0).map(|l| l.1[axis]);
            let lo = massive.clone().fold(f64::INFINITY, f64::min);
            let hi = massive.fold(f64::NEG_INFINITY, f64::max);
            prop_assert!(com[axis] >= lo - EPS && com[axis] <= hi + EPS);
        }
        let d = nalgebra::Vector3::new(shift.0, shift.1, shift.2);
        let moved: Vec<_> = links.iter().map(|&(m, p)| (m, p + d)).collect();
        prop_assert!((centre_of_mass(&moved).unwrap() - (com + d)).norm() <= 1e-8);
        let heavier: Vec<_> = links.iter().map(|&(m, p)| (m * scale, p)).collect();
        prop_assert!((centre_of_mass(&heavier).unwrap() - com).norm() <= EPS);
    }
}
