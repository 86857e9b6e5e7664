//! Where the Gait Planner puts the foot: clear of pylons and obstacles, never in a trench
//! too deep to reach, never on unknown or unreachable cells; how far it moves the body.

use crate::common;

use common::*;
use nalgebra::Point2;
use proptest::prelude::*;
use tca_gait_planner::{GaitError, GaitMaps, GaitParams, GaitPlanner, synthetic};
use tca_lrp::MapValue;
use tca_robot::{Course, FeatureKind, Grid, HeightField, LegParams};

fn object_distance(course: &Course, p: Point2<f64>) -> f64 {
    course
        .features
        .iter()
        .filter(|f| f.is_object())
        .filter_map(|f| {
            let (lo, hi) = f.footprint()?;
            let dx = (lo.x - p.x).max(p.x - hi.x).max(0.0);
            let dy = (lo.y - p.y).max(p.y - hi.y).max(0.0);
            Some(dx.hypot(dy))
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn footfalls_keep_clear_of_the_steeplechase_pylons() {
    let course = Course::builtin(2).unwrap();
    let terrain = course.height_field().unwrap();
    for k in 0..14 {
        let body_y = 1.0 + 0.5 * f64::from(k);
        let step = plan_open(&terrain, body_y, 10.0).unwrap();
        let f = Point2::new(step.footfall.x, step.footfall.y);
        for pylon in course.features_named("pylon-") {
            let d = (pylon.center() - f).norm();
            assert!(
                d >= 0.5,
                "body {body_y}: footfall {f} is {d:.2} m from {}",
                pylon.name
            );
        }
        // A 70 cm clear region on the true terrain (the sand rolls a little).
        let r = relief(&terrain, f, 0.35);
        assert!(
            r < 0.03,
            "body {body_y}: footfall {f} has {r:.3} m of relief around it"
        );
        assert!(
            object_distance(&course, f) > 0.3,
            "body {body_y}: {f} next to an object"
        );
        assert!(step.advance_m > 0.0 && step.advance_m <= 1.5 + 1e-9);
        assert!(step.footfall.y >= body_y);
    }
}

#[test]
fn a_trench_too_deep_to_reach_is_never_chosen() {
    // Flat sand studded with pylons every 0.5 m, except a wide trench with a flat floor.
    let build = |depth: f64| {
        let grid = Grid::from_fn(Point2::new(0.0, 0.0), 0.02, 301, 401, |_, p| {
            if (1.0..=5.0).contains(&p.x) && (3.0..=4.6).contains(&p.y) {
                return -depth;
            }
            let (u, v) = ((p.x / 0.5).fract() - 0.5, (p.y / 0.5).fract() - 0.5);
            let d = 0.5 * u.hypot(v);
            if d < 0.1 { 0.3 * (1.0 - d / 0.1) } else { 0.0 }
        })
        .unwrap();
        HeightField::from_grid(grid).unwrap()
    };
    let deep = build(0.9);
    match plan_open(&deep, 2.0, 8.0) {
        Err(GaitError::NoFootfall { elevation, .. }) => assert!(elevation > 0),
        other => panic!("expected no footfall, got {other:?}"),
    }
    // The same trench 0.3 m deep is within reach: its floor is the only clear place.
    let shallow = build(0.3);
    let step = plan_open(&shallow, 2.0, 8.0).unwrap();
    assert!(
        (1.35..=4.65).contains(&step.footfall.x) && (3.35..=4.25).contains(&step.footfall.y),
        "{}",
        step.footfall
    );
    assert!((step.footfall.z + 0.3).abs() < 1e-6);
}

#[test]
fn course_4_deep_trench_and_dense_pylons_are_avoided() {
    let course = Course::builtin(4).unwrap();
    let terrain = course.height_field().unwrap();
    let trench = course.feature("deep-trench").unwrap().footprint().unwrap();
    let mut planned = 0;
    for k in 0..10 {
        let body_y = 2.0 + 0.7 * f64::from(k);
        let Ok(step) = plan_open(&terrain, body_y, 10.0) else {
            continue;
        };
        let f = Point2::new(step.footfall.x, step.footfall.y);
        let inside = f.x > trench.0.x - 0.3
            && f.x < trench.1.x + 0.3
            && f.y > trench.0.y - 0.3
            && f.y < trench.1.y + 0.3;
        assert!(
            !inside,
            "body {body_y}: footfall {f} in or at the deep trench"
        );
        for pylon in course.features_named("dense-pylon-") {
            assert!(
                (pylon.center() - f).norm() >= 0.5,
                "body {body_y}: {f} among the dense pylons"
            );
        }
        assert!(step.footfall.z > -0.4);
        planned += 1;
    }
    assert!(planned >= 8, "only {planned} steps planned");
}

#[test]
fn the_filtered_footfall_steers_away_from_an_obstacle() {
    let grid = Grid::from_fn(Point2::new(0.0, 0.0), 0.02, 301, 401, |_, p| {
        if (p.x - 3.0).abs() <= 0.2 && (p.y - 3.5).abs() <= 0.2 {
            0.4
        } else {
            0.0
        }
    })
    .unwrap();
    let terrain = HeightField::from_grid(grid).unwrap();
    let step = plan_open(&terrain, 2.0, 8.0).unwrap();
    let filtered = &step.maps.filtered_footfall;
    let at = |x: f64, y: f64| {
        *filtered
            .get(step.region.layout.cell_at(Point2::new(x, y)).unwrap())
            .unwrap()
    };
    // Falling with the distance from the box's edge, and zero beyond the filter's radius.
    let near = at(3.45, 3.55);
    let mid = at(3.75, 3.55);
    let far = at(4.25, 3.55);
    assert!(near > mid && mid > far, "{near} {mid} {far}");
    assert_eq!(at(4.65, 3.55), 0.0);
    let f = Point2::new(step.footfall.x, step.footfall.y);
    let dx = ((f.x - 3.0).abs() - 0.2).max(0.0);
    let dy = ((f.y - 3.5).abs() - 0.2).max(0.0);
    assert!(dx.hypot(dy) > 0.5, "footfall {f} next to the box");
}

#[test]
fn the_sun_box_region_is_unreachable_and_avoided() {
    let course = Course::builtin(3).unwrap();
    let terrain = course.height_field().unwrap();
    let start = planted(&terrain, 1.5, Point2::new(3.3, 0.6));
    let step = plan_with_lrp(&terrain, 1.5, 9.0, &start).unwrap();
    let sun = course.feature("sun-box").unwrap().footprint().unwrap();
    let f = Point2::new(step.footfall.x, step.footfall.y);
    let dx = (sun.0.x - f.x).max(f.x - sun.1.x).max(0.0);
    let dy = (sun.0.y - f.y).max(f.y - sun.1.y).max(0.0);
    assert!(dx.hypot(dy) > 0.4, "footfall {f} beside the sun box");
    // The cells over the box are unreachable.
    let over = step.region.layout.cell_at(Point2::new(3.3, 2.1)).unwrap();
    assert!(!step.maps.reachable.get(over).unwrap());
    assert!(step.maps.total.get(over).unwrap().is_none());
}

#[test]
fn walking_backward_plans_behind_the_carriage() {
    let terrain = Course::builtin(2).unwrap().height_field().unwrap();
    let step = plan_open(&terrain, 8.0, 2.0).unwrap();
    assert!(step.footfall.y <= 8.0);
    assert!(step.advance_m < 0.0 && step.advance_m >= -1.5 - 1e-9);
    assert!((step.body_target_y_m - (8.0 + step.advance_m)).abs() < 1e-12);
}

#[test]
fn the_body_move_is_limited_by_the_threshold_and_the_goal() {
    let terrain = Course::builtin(1).unwrap().height_field().unwrap();
    let step = plan_open(&terrain, 1.0, 9.0).unwrap();
    let a_max = step.maps.body_advance_m.get(step.cell).unwrap().unwrap();
    assert!((step.advance_m - a_max.min(1.5)).abs() < 1e-9);
    let near = plan_open(&terrain, 1.0, 1.4).unwrap();
    assert!((near.advance_m - 0.4).abs() < 1e-9, "{}", near.advance_m);
    // A different threshold from the parameter file.
    let text = tca_gait_planner::params::DEFAULT_GAIT_TOML
        .replace("threshold_m = 1.5", "threshold_m = 0.7");
    let p = GaitPlanner::new(
        LegParams::default(),
        GaitParams::from_toml_str(&text).unwrap(),
    )
    .unwrap();
    let (ff, el) = maps_for(&terrain, 1.0, 9.0);
    let step = p
        .plan(
            1.0,
            9.0,
            &GaitMaps {
                footfall: &ff,
                elevation: &el,
                reachable: &|_| true,
            },
        )
        .unwrap();
    assert!(step.advance_m <= 0.7 + 1e-9);
}

#[test]
fn bad_input_is_a_clear_error() {
    let terrain = Course::builtin(1).unwrap().height_field().unwrap();
    let (ff0, el0) = maps_for(&terrain, 3.0, 9.0);
    let open = GaitMaps {
        footfall: &ff0,
        elevation: &el0,
        reachable: &|_| true,
    };
    assert!(matches!(
        planner().plan(3.0, 3.005, &open),
        Err(GaitError::AtGoal { .. })
    ));
    let err = planner().plan(f64::NAN, 3.0, &open).unwrap_err();
    assert!(err.to_string().contains("not a finite number"), "{err}");
    // Nothing known: no footfall, and the message says what to do.
    let (mut ff, el) = maps_for(&terrain, 3.0, 9.0);
    for v in ff.grid_mut().cells_mut() {
        *v = MapValue::Unknown;
    }
    let err = planner()
        .plan(
            3.0,
            9.0,
            &GaitMaps {
                footfall: &ff,
                elevation: &el,
                reachable: &|_| true,
            },
        )
        .unwrap_err();
    assert!(
        matches!(err, GaitError::NoFootfall { unknown, .. } if unknown > 0),
        "{err}"
    );
    assert!(err.to_string().contains("acquire a fresh terrain map"));
    // Nothing reachable.
    let (ff, el) = maps_for(&terrain, 3.0, 9.0);
    let err = planner()
        .plan(
            3.0,
            9.0,
            &GaitMaps {
                footfall: &ff,
                elevation: &el,
                reachable: &|_| false,
            },
        )
        .unwrap_err();
    assert!(
        matches!(err, GaitError::NoFootfall { out_of_reach, .. } if out_of_reach > 0),
        "{err}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Whatever parts of the map are unknown and whatever the reachability says, the chosen
    /// cell is known, reachable, and has a known clear region around it.
    #[test]
    fn never_unknown_or_unreachable(
        body_y in 1.0f64..8.0,
        holes in proptest::collection::vec((0.5f64..5.5, 0.0f64..3.0, 0.1f64..0.8), 0..6),
        walls in proptest::collection::vec((0.5f64..5.5, 0.0f64..3.0, 0.2f64..1.0), 0..4),
    ) {
        let terrain = Course::builtin(1).unwrap().height_field().unwrap();
        let (mut ff, mut el) = maps_for(&terrain, body_y, 10.0);
        let in_hole = |p: Point2<f64>| {
            holes.iter().any(|&(x, dy, r)| (p - Point2::new(x, body_y + dy)).norm() < r)
        };
        for map in [&mut ff, &mut el] {
            let g = map.grid_mut();
            let cells: Vec<_> = g.iter().map(|(c, _)| c).collect();
            for c in cells {
                if in_hole(g.cell_center(c)) {
                    *g.get_mut(c).unwrap() = MapValue::Unknown;
                }
            }
        }
        let reachable = |p: Point2<f64>| {
            !walls.iter().any(|&(x, dy, r)| (p - Point2::new(x, body_y + dy)).norm() < r)
        };
        let result = planner().plan(body_y, 10.0, &GaitMaps { footfall: &ff, elevation: &el, reachable: &reachable });
        if let Ok(step) = result {
            let f = Point2::new(step.footfall.x, step.footfall.y);
            prop_assert!(reachable(f));
            prop_assert!(ff.value_at(f).known().is_some());
            for k in 0..16 {
                let a = f64::from(k) * std::f64::consts::TAU / 16.0;
                let p = f + nalgebra::Vector2::new(a.cos(), a.sin()) * 0.3;
                prop_assert!(el.value_at(p).known().is_some(), "unknown terrain at {} near {}", p, f);
            }
        }
    }
}

#[test]
fn the_cost_maps_make_a_picture() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let step = plan_open(&terrain, 1.5, 9.0).unwrap();
    let pic = tca_gait_planner::picture::cost_maps_picture(&step);
    let (nx, ny) = (
        step.region.layout.nx() as u32,
        step.region.layout.ny() as u32,
    );
    assert_eq!(pic.width(), 4 * nx * 6 + 24);
    assert_eq!(pic.height(), 2 * ny * 6 + 8);
    assert!(pic.to_png().unwrap().starts_with(b"\x89PNG"));
    let _ = synthetic::elevation_map;
    let _ = FeatureKind::Box {
        center: Point2::origin(),
        size_x_m: 0.0,
        size_y_m: 0.0,
        height_m: 0.0,
    };
}
