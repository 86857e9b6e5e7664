use nalgebra::Point2;
use tca_robot::terrain::asc::{NoData, read_height_field};

use super::*;

fn heights(c: &LeggedCourse) -> &[f64] {
    c.terrain.grid().cells()
}

#[test]
fn every_name_builds_and_round_trips() {
    for (name, course) in NAMES.iter().zip(Course::ALL) {
        assert_eq!(course.name(), *name);
        assert_eq!(Course::from_name(name).unwrap(), course);
        let c = Course::builtin(name, 3).unwrap();
        assert_eq!(c.name, *name);
        assert_eq!(c.seed, 3);
    }
}

#[test]
fn unknown_names_list_the_known_ones() {
    let err = Course::builtin("moon", 0).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("moon"), "{text}");
    for name in NAMES {
        assert!(text.contains(name), "{text}");
    }
}

#[test]
fn same_seed_same_course_other_seed_other_course() {
    for name in NAMES {
        let a = Course::builtin(name, 11).unwrap();
        let b = Course::builtin(name, 11).unwrap();
        assert_eq!(heights(&a), heights(&b), "{name}");
    }
    for name in [
        "boulders",
        "rough",
        "hexapod-rough",
        "cliff",
        "walled-goal",
        "rock-field",
    ] {
        let a = Course::builtin(name, 1).unwrap();
        let b = Course::builtin(name, 2).unwrap();
        assert_ne!(heights(&a), heights(&b), "{name}");
    }
}

#[test]
fn scales_starts_and_goals() {
    for name in ["boulders", "ditch", "slope", "flat", "rough"] {
        let c = Course::builtin(name, 0).unwrap();
        let (lo, hi) = c.terrain.extent();
        assert!((hi.x - lo.x - 28.0).abs() < 1e-9 && (hi.y - lo.y - 14.0).abs() < 1e-9);
        assert!((c.terrain.grid().resolution_m() - 0.1).abs() < 1e-12);
        assert_eq!(
            c.start,
            CourseStart {
                x_m: 3.0,
                y_m: 0.0,
                yaw_rad: 0.0
            }
        );
        assert_eq!(c.goal, Point2::new(23.0, 0.0));
        assert_eq!(c.robot_hint, "ambler");
    }
    for name in ["hexapod-rough", "hexapod-flat"] {
        let c = Course::builtin(name, 0).unwrap();
        let (lo, hi) = c.terrain.extent();
        assert!((hi.x - lo.x - 3.5).abs() < 1e-9 && (hi.y - lo.y - 1.5).abs() < 1e-9);
        assert!((c.terrain.grid().resolution_m() - 0.02).abs() < 1e-12);
        assert_eq!(
            c.start,
            CourseStart {
                x_m: 0.3,
                y_m: 0.0,
                yaw_rad: 0.0
            }
        );
        assert_eq!(c.goal, Point2::new(3.2, 0.0));
        assert_eq!(c.robot_hint, "hexapod");
    }
}

/// Heights of every sample within `radius` of the start.
fn start_patch(c: &LeggedCourse, radius: f64) -> Vec<f64> {
    let s = Point2::new(c.start.x_m, c.start.y_m);
    let g = c.terrain.grid();
    g.iter()
        .filter(|(cell, _)| (g.cell_center(*cell) - s).norm() <= radius)
        .map(|(_, h)| *h)
        .collect()
}

#[test]
fn every_start_patch_is_level() {
    for seed in [0, 1, 99] {
        for name in NAMES {
            let c = Course::builtin(name, seed).unwrap();
            if c.robot_hint == "athlete" {
                continue; // level under its wheels instead: see the rock field's test
            }
            let radius = if c.robot_hint == "ambler" { 3.0 } else { 0.3 };
            let patch = start_patch(&c, radius);
            assert!(patch.len() > 100, "{name}");
            let (lo, hi) = patch
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
                    (a.min(*h), b.max(*h))
                });
            assert!(
                hi - lo < 1e-9,
                "{name} seed {seed}: start patch spans {lo}..{hi}"
            );
        }
    }
}

#[test]
fn boulders_reach_one_metre_and_leave_footholds() {
    for seed in 0..8 {
        let c = Course::builtin("boulders", seed).unwrap();
        let top = c.terrain.max_height_m();
        assert!(
            (0.99..=1.0 + 1e-12).contains(&top),
            "seed {seed}: tallest {top}"
        );
        assert!(c.terrain.min_height_m() >= 0.0);
        let g = c.terrain.grid();
        // Boulders only over x 5..25 m.
        for (cell, h) in g.iter() {
            let p = g.cell_center(cell);
            if !(5.0..=25.0).contains(&p.x) {
                assert_eq!(*h, 0.0, "seed {seed}: height {h} at {p}");
            }
        }
        // Many boulders, and none lower than 0.3 m.
        let (list, holds) = ambler::boulder_list(seed);
        assert!(list.len() > 80, "seed {seed}: {} boulders", list.len());
        assert!(list.iter().all(|b| b.height_m >= 0.3 && b.radius_m >= 0.35));
        // Every reserved foothold is level ground, and every metre of the field along X
        // has one every 2 m across.
        for h in &holds {
            if (h - Point2::new(3.0, 0.0)).norm() > 3.0 {
                assert!(
                    c.terrain.max_height_in_disc(*h, 0.25) < 1e-9,
                    "seed {seed}: {h}"
                );
            }
        }
        for step in 0..20 {
            let x0 = 5.0 + step as f64;
            let mut y0 = -6.0;
            while y0 < 6.0 {
                let found = holds
                    .iter()
                    .any(|h| h.x >= x0 - 0.15 && h.x <= x0 + 1.15 && h.y >= y0 && h.y <= y0 + 2.5);
                assert!(found, "seed {seed}: no foothold near x {x0}, y {y0}");
                y0 += 2.0;
            }
        }
    }
}

#[test]
fn ditch_is_one_metre_wide_and_deep_across_the_course() {
    let c = Course::builtin("ditch", 0).unwrap();
    let g = c.terrain.grid();
    let r = g.resolution_m();
    for iy in 0..g.ny() {
        // The opening: from the last level sample before the ditch to the first after it.
        let row: Vec<f64> = (0..g.nx())
            .map(|ix| *g.get(tca_robot::CellIndex::new(ix, iy)).unwrap())
            .collect();
        let first = row.iter().position(|h| *h < -1e-9).unwrap();
        let last = row.iter().rposition(|h| *h < -1e-9).unwrap();
        let opening = (last + 1 - (first - 1)) as f64 * r;
        assert!((opening - 1.0).abs() < 1e-9, "row {iy}: opening {opening}");
        let centre = g.origin().x + 0.5 * (first + last) as f64 * r;
        assert!((centre - 12.0).abs() < 1e-9);
        assert!((row[(first + last) / 2] + 1.0).abs() < 1e-12);
    }
    assert_eq!(c.terrain.max_height_m(), 0.0);
    assert_eq!(c.terrain.min_height_m(), -1.0);
}

#[test]
fn slope_climbs_at_25_degrees_to_a_plateau() {
    let c = Course::builtin("slope", 0).unwrap();
    let t = &c.terrain;
    let r = t.grid().resolution_m();
    for y in [-5.0, 0.0, 4.3] {
        for x in [9.0, 10.0, 11.5] {
            let rise = t.height_at(x + r, y) - t.height_at(x, y);
            let angle = (rise / r).atan().to_degrees();
            assert!((angle - 25.0).abs() < 1e-6, "angle {angle} at {x}");
        }
        assert_eq!(t.height_at(7.9, y), 0.0);
        assert!((t.height_at(20.0, y) - 2.0).abs() < 1e-12);
        assert!((t.height_at(c.goal.x, c.goal.y) - 2.0).abs() < 1e-12);
    }
}

#[test]
fn rough_relief_stays_within_its_bounds() {
    for seed in 0..4 {
        let c = Course::builtin("rough", seed).unwrap();
        let (lo, hi) = (c.terrain.min_height_m(), c.terrain.max_height_m());
        assert!(lo >= -0.15 - 1e-12 && hi <= 0.15 + 1e-12, "{lo}..{hi}");
        assert!(hi - lo > 0.2, "{lo}..{hi}");
        let h = Course::builtin("hexapod-rough", seed).unwrap();
        let (lo, hi) = (h.terrain.min_height_m(), h.terrain.max_height_m());
        assert!(lo >= -0.021 && hi <= 0.061 && hi > 0.02, "{lo}..{hi}");
        assert_eq!(
            Course::builtin("flat", seed)
                .unwrap()
                .terrain
                .max_height_m(),
            0.0
        );
        assert_eq!(
            Course::builtin("hexapod-flat", seed)
                .unwrap()
                .terrain
                .min_height_m(),
            0.0
        );
    }
}

#[test]
fn written_courses_read_back_the_same() {
    let dir = tempfile::tempdir().unwrap();
    for name in NAMES {
        let path = dir.path().join(format!("{name}.asc"));
        let course = write_course(name, 5, &path).unwrap();
        let back = read_height_field(&path, NoData::Refuse).unwrap();
        assert_eq!(back.grid().nx(), course.terrain.grid().nx());
        assert_eq!(back.grid().ny(), course.terrain.grid().ny());
        assert!((back.grid().origin() - course.terrain.grid().origin()).norm() < 1e-9);
        for (a, b) in back
            .grid()
            .cells()
            .iter()
            .zip(course.terrain.grid().cells())
        {
            assert!((a - b).abs() < 1e-6, "{name}: {a} vs {b}");
        }
    }
    let bad = write_course("flat", 0, dir.path().join("missing/dir/flat.asc"));
    assert!(matches!(bad, Err(CourseError::Write(_))));
}

#[test]
fn cliff_has_its_plateau_ramp_and_relief() {
    for seed in [1, 7] {
        let c = Course::builtin("cliff", seed).unwrap();
        let h = |x: f64, y: f64| c.terrain.height_at(x, y);
        assert_eq!(c.robot_hint, "ambler");
        assert_eq!((c.start.x_m, c.goal.x), (4.0, 24.0));
        // The face: more than 2.4 m up within a cell, on the way from start to goal.
        assert!(h(14.05, 0.0) - h(13.9, 0.0) > 2.4);
        // The ramp rises evenly beside it; the relief stays within 5 cm.
        assert!((h(10.0, 7.0) - 1.25).abs() <= 0.05 + 1e-9);
        assert!((h(24.0, 0.0) - 2.5).abs() <= 0.05 + 1e-9);
        assert!(h(8.0, -5.0).abs() <= 0.05 + 1e-9);
    }
    let w = Course::builtin("walled-goal", 1).unwrap();
    assert!(w.terrain.height_at(25.5, 0.0) > 4.9);
    assert!(w.terrain.height_at(20.0, 0.0).abs() <= 0.05 + 1e-9);
}

#[test]
fn rock_field_is_level_under_the_starting_wheels_and_rocky_around_them() {
    for seed in [0, 1, 7] {
        let c = Course::builtin("rock-field", seed).unwrap();
        assert_eq!(c.robot_hint, "athlete");
        let (lo, hi) = c.terrain.extent();
        assert!((hi.x - lo.x - 14.0).abs() < 1e-9 && (hi.y - lo.y - 14.0).abs() < 1e-9);
        assert!((c.terrain.grid().resolution_m() - 0.05).abs() < 1e-12);
        let top = c.terrain.max_height_m();
        assert!(
            (rocks::ROCK_MAX_M - rocks::RELIEF_PEAK_M
                ..=rocks::ROCK_MAX_M + rocks::RELIEF_PEAK_M + 1e-9)
                .contains(&top),
            "seed {seed}: tallest {top}"
        );
        assert!(c.terrain.min_height_m() >= -rocks::RELIEF_PEAK_M - 1e-9);
        let g = c.terrain.grid();
        for w in rocks::wheel_spots() {
            let patch: Vec<f64> = g
                .iter()
                .filter(|(cell, _)| (g.cell_center(*cell) - w).norm() <= rocks::WHEEL_PATCH_M)
                .map(|(_, h)| *h)
                .collect();
            assert!(patch.len() > 400, "seed {seed}");
            assert!(
                patch.iter().all(|h| h.abs() < 1e-12),
                "seed {seed}: wheel at {w}"
            );
        }
        // Rocks among the wheels: within 4 m of the body centre, at least 15 of them.
        let s = Point2::new(c.start.x_m, c.start.y_m);
        let near = rocks::rock_list(seed)
            .iter()
            .filter(|r| (r.center - s).norm() < 4.0)
            .count();
        assert!(near >= 15, "seed {seed}: {near} rocks near the rover");
    }
}
