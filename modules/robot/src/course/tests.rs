//! Tests of the built-in and random courses.

use nalgebra::Point2;

use super::*;
use crate::LegParams;

/// A clear footfall: a 70 cm disc (§8.2) whose heights spread by at most 8 cm and that the
/// foot can stand on (between 0.5 m below and 0.9 m above the sand).
fn clear_footfall(t: &HeightField, c: Point2<f64>) -> bool {
    let r = 0.35;
    let grid = t.grid();
    let Some((xs, ys)) =
        grid.cell_range(Point2::new(c.x - r, c.y - r), Point2::new(c.x + r, c.y + r))
    else {
        return false;
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for iy in ys {
        for ix in xs.clone() {
            let cell = crate::CellIndex::new(ix, iy);
            if (grid.cell_center(cell) - c).norm() <= r {
                let h = t.sample(cell).unwrap_or(f64::NAN);
                lo = lo.min(h);
                hi = hi.max(h);
            }
        }
    }
    hi - lo <= 0.08 && lo >= -0.45 && hi <= 0.9
}

/// For each carriage stop every 1.5 m from y = 1 m, a clear footfall ahead within reach.
fn assert_walkable(course: &Course) {
    let t = course.height_field().unwrap();
    let params = LegParams::default();
    let reach = params.leg.upper_link_m + params.leg.lower_link_m - 0.2;
    let mut stop = 1.0;
    while stop <= 8.6 {
        let mut found = None;
        'search: for j in 0..=18 {
            let y = stop + 0.5 + 0.1 * j as f64;
            for i in 0..=44 {
                let x = 0.8 + 0.1 * i as f64;
                let c = Point2::new(x, y);
                if (c - Point2::new(params.carriage.x_m, stop)).norm() <= reach
                    && clear_footfall(&t, c)
                {
                    found = Some(c);
                    break 'search;
                }
            }
        }
        assert!(
            found.is_some(),
            "{}: no clear footfall ahead of carriage y = {stop}",
            course.name
        );
        stop += 1.5;
    }
}

#[test]
fn builtin_courses_are_walkable() {
    for n in 1..=4 {
        assert_walkable(&Course::builtin(n).unwrap());
    }
    assert!(matches!(
        Course::builtin(5),
        Err(CourseError::UnknownCourse(5))
    ));
}

#[test]
fn random_courses_are_walkable_and_deterministic() {
    for seed in 0..12 {
        let c = Course::random(seed);
        assert_eq!(c, Course::random(seed));
        assert!(
            c.features.len() >= 8,
            "seed {seed}: only {} features",
            c.features.len()
        );
        assert_walkable(&c);
    }
    assert_ne!(Course::random(1), Course::random(2));
}

#[test]
fn course_1_is_rolling_sand_trenches_and_small_obstacles() {
    let c = Course::builtin(1).unwrap();
    assert!(c.feature("rolling-sand").is_some());
    assert_eq!(c.features_named("trench-").count(), 2);
    let t = c.height_field().unwrap();
    for f in c.features.iter().filter(|f| f.is_object()) {
        let top = t.max_height_in_disc(f.center(), 0.05);
        assert!(top < 0.4, "{} is a small obstacle: {top}", f.name);
    }
    let trench = c.feature("trench-1").unwrap();
    let floor = t.height_at(trench.center().x, trench.center().y);
    assert!(floor < -0.2, "trench floor {floor}");
}

#[test]
fn course_2_is_a_steeplechase_with_boxes_and_rocks() {
    let c = Course::builtin(2).unwrap();
    let pylons: Vec<_> = c.features_named("pylon-").collect();
    assert!(pylons.len() >= 12);
    // Rows across the pit: pylons of a row share a Y.
    let rows: std::collections::BTreeSet<i64> = pylons
        .iter()
        .map(|p| (p.center().y * 10.0).round() as i64)
        .collect();
    assert!(rows.len() >= 4);
    assert!(c.features_named("box-").count() >= 2);
    assert!(c.features_named("rock-").count() >= 3);
    assert!(c.feature("sun-box").is_none());
    let t = c.height_field().unwrap();
    let p = pylons[0].center();
    assert!((t.height_at(p.x, p.y) - 0.7).abs() < 0.05, "pylon tip");
    // Nothing is taller than the foot can lift over (1.0 m).
    assert!(t.max_height_m() < 1.0);
}

#[test]
fn course_3_adds_the_big_box_at_the_beginning() {
    let params = LegParams::default();
    let foot_top = params.carriage.link_plane_height_m - params.leg.vertical.min_m;
    let c2 = Course::builtin(2).unwrap();
    let c3 = Course::builtin(3).unwrap();
    let sun = c3.feature("sun-box").expect("course 3 has the Sun box");
    assert_eq!(c3.features.len(), c2.features.len() + 1);
    let centre = sun.center();
    assert!(centre.y < 3.0, "at the beginning: {centre}");
    assert!(
        (centre.x - params.carriage.x_m).abs() < 0.5,
        "in the leg's way"
    );
    let t = c3.height_field().unwrap();
    let top = t.height_at(centre.x, centre.y);
    assert!(
        top > foot_top + 0.1,
        "taller ({top}) than the foot can lift ({foot_top})"
    );
}

#[test]
fn course_4_has_course_3_on_the_right_and_the_new_obstacles_on_the_left() {
    let params = LegParams::default();
    let foot_bottom = params.carriage.link_plane_height_m - params.leg.vertical.max_m;
    let c3 = Course::builtin(3).unwrap();
    let c4 = Course::builtin(4).unwrap();
    for f in c3
        .features
        .iter()
        .filter(|f| f.footprint().is_some() && f.center().x >= 3.0)
    {
        assert_eq!(
            c4.feature(&f.name),
            Some(f),
            "course 4 keeps {} on the right",
            f.name
        );
    }
    assert!(c4.feature("sun-box").is_some());
    for f in c4
        .features
        .iter()
        .filter(|f| f.footprint().is_some() && f.center().x < 3.0)
    {
        assert!(
            c3.feature(&f.name).is_none(),
            "{} is new on the left",
            f.name
        );
    }
    // Pylons too close for the 30 cm foot.
    let dense: Vec<_> = c4.features_named("dense-pylon-").collect();
    assert!(dense.len() >= 9);
    for a in &dense {
        let nearest = dense
            .iter()
            .filter(|b| b.name != a.name)
            .map(|b| (b.center() - a.center()).norm())
            .fold(f64::INFINITY, f64::min);
        let FeatureKind::Cone { base_radius_m, .. } = a.kind else {
            panic!("pylons are cones")
        };
        assert!(
            nearest - 2.0 * base_radius_m < 0.30,
            "gap {nearest} leaves room for the foot"
        );
        assert!(a.center().x < 3.0);
    }
    let hill = c4.feature("sand-hill").unwrap();
    let trench = c4.feature("deep-trench").unwrap();
    let t = c4.height_field().unwrap();
    assert!(hill.center().x < 3.0 && t.height_at(hill.center().x, hill.center().y) > 0.4);
    let floor = t.height_at(trench.center().x, trench.center().y);
    assert!(
        trench.center().x < 3.0 && floor < foot_bottom - 0.2,
        "floor {floor} beyond reach {foot_bottom}"
    );
}

#[test]
fn render_refuses_a_bad_resolution_and_coarse_rendering_works() {
    let c = Course::builtin(3).unwrap();
    assert!(c.render(0.0).is_err());
    let coarse = c.render(0.1).unwrap();
    assert_eq!((coarse.grid().nx(), coarse.grid().ny()), (61, 111));
}
