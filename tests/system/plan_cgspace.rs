//! `tca plan cgspace`, whole: the built binary planning the Ambler's route and footfalls on
//! the CG-space courses, its picture, and its refusals of bad input.

use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// Runs `tca ARGS` to its end with no input.
fn tca(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tca"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("tca runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn xy(v: &Value) -> (f64, f64) {
    (
        v[0].as_f64().expect("x is a number"),
        v[1].as_f64().expect("y is a number"),
    )
}

#[test]
fn the_ambler_takes_the_ramp_up_the_cliff_and_no_foot_stands_on_its_face() {
    let out = tca(&[
        "plan",
        "cgspace",
        "--robot",
        "ambler",
        "--terrain",
        "cliff",
        "--json",
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    let plan: Value = serde_json::from_str(stdout.trim()).expect("one JSON object");
    assert_eq!(plan["planned"], true, "{plan}");
    for key in [
        "route_cells",
        "route_length_m",
        "foot_moves",
        "search_nodes",
        "routes_planned",
        "cells_marked",
        "cg_cells_evaluated",
        "regions_materialised",
        "time_s",
    ] {
        assert!(plan[key].is_number(), "{key} missing");
    }
    let route = plan["route"].as_array().expect("the route");
    assert_eq!(route.len() as u64, plan["route_cells"].as_u64().unwrap());
    assert!(
        route
            .iter()
            .all(|c| c.as_array().is_some_and(|c| c.len() == 3))
    );
    let (x0, y0) = xy(&route[0]);
    let (x1, y1) = xy(route.last().unwrap());
    assert!(
        (x0 - 4.0).abs() < 0.5 && y0.abs() < 0.5,
        "starts at ({x0}, {y0})"
    );
    assert!(
        (x1 - 24.0).abs() < 0.5 && y1.abs() < 0.5,
        "ends at ({x1}, {y1})"
    );
    // The route crosses x = 14 m (the cliff's foot) only by the ramp, north of y = 2 m.
    let mut crossings = 0;
    for w in route.windows(2) {
        let ((ax, ay), (bx, by)) = (xy(&w[0]), xy(&w[1]));
        if (ax - 14.0) * (bx - 14.0) <= 0.0 && ax != bx {
            crossings += 1;
            assert!(ay > 2.0 && by > 2.0, "crosses x = 14 m at y {ay}");
        }
    }
    assert!(crossings > 0, "the route never crosses x = 14 m");

    // Every foot, placed or standing, clear of the cliff face and of the ramp's sides: the
    // ground under its footprint (a CG cell across, the smallest foot's diameter) rises
    // less than 1 m.
    let terrain = tca_legged_courses::Course::builtin("cliff", 1)
        .expect("the cliff course")
        .terrain;
    let footprint = plan["cell_m"].as_f64().expect("the cell size") / 2.0;
    assert!(
        footprint > 0.05 && footprint <= 0.3,
        "footprint {footprint}"
    );
    let relief_near = |x: f64, y: f64| {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in -12..=12 {
            for j in -12..=12 {
                let (dx, dy) = (f64::from(i) * 0.025, f64::from(j) * 0.025);
                if dx.hypot(dy) <= footprint {
                    let h = terrain.height_at(x + dx, y + dy);
                    lo = lo.min(h);
                    hi = hi.max(h);
                }
            }
        }
        hi - lo
    };
    let footfalls = plan["footfalls"].as_array().expect("the footfalls");
    assert!(footfalls.len() as u64 <= plan["foot_moves"].as_u64().unwrap());
    assert!(!footfalls.is_empty());
    let legs: Vec<&str> = plan["legs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    for f in footfalls {
        assert!(
            legs.contains(&f["leg"].as_str().expect("a leg name")),
            "{f}"
        );
        let (x, y) = (f["x"].as_f64().unwrap(), f["y"].as_f64().unwrap());
        let d = relief_near(x, y);
        assert!(d < 1.0, "a foot at ({x}, {y}) by a {d:.2} m drop");
    }
    let stances = plan["stances"].as_array().expect("the stances");
    assert!(stances.len() > footfalls.len());
    for s in stances {
        let feet = s.as_array().expect("one entry per leg");
        assert_eq!(feet.len(), legs.len());
        assert!(feet.iter().filter(|f| !f.is_null()).count() >= 3, "{s}");
        for f in feet.iter().filter(|f| !f.is_null()) {
            let (x, y) = xy(f);
            let d = relief_near(x, y);
            assert!(d < 1.0, "a foot stands at ({x}, {y}) by a {d:.2} m drop");
        }
    }
    // The first stance stands about the start.
    for f in stances[0]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| !f.is_null())
    {
        let (x, y) = xy(f);
        assert!(
            (x - x0).hypot(y - y0) < 6.0,
            "a starting foot at ({x}, {y})"
        );
    }
}

#[test]
fn a_walled_in_goal_is_no_route_quickly_and_still_drawn() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let png = dir.path().to_str().expect("a UTF-8 path");
    let began = Instant::now();
    let out = tca(&[
        "plan",
        "cgspace",
        "--robot",
        "ambler",
        "--terrain",
        "walled-goal",
        "--png",
        png,
    ]);
    let took = began.elapsed();
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(2), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("no route"), "{stdout}");
    assert!(stdout.contains("cannot be reached"), "{stdout}");
    assert!(took < Duration::from_secs(60), "took {took:?}");
    // The picture without a route.
    let file = dir.path().join("cgspace-1.png");
    let bytes = std::fs::read(&file).expect("the picture written");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");

    let out = tca(&[
        "plan",
        "cgspace",
        "--robot",
        "ambler",
        "--terrain",
        "walled-goal",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let v: Value = serde_json::from_str(text(&out.stdout).trim()).expect("one JSON object");
    assert_eq!(v["planned"], false);
    assert_eq!(v["unreachable"], true);
}

#[test]
fn the_picture_decodes_and_shows_the_route_and_invalid_cells() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let png = dir.path().to_str().expect("a UTF-8 path");
    let out = tca(&[
        "plan",
        "cgspace",
        "--robot",
        "ambler",
        "--terrain",
        "cliff",
        "--theta",
        "0",
        "--png",
        png,
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    for part in [
        "seed 1: route of",
        "foot moves",
        "search nodes",
        "routes planned",
        "cells marked",
        "CG cells evaluated",
        "regions",
        "planned in",
    ] {
        assert!(stdout.contains(part), "{part:?} missing from {stdout}");
    }
    let file = dir.path().join("cgspace-1.png");
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&file).expect("the picture written"),
    ));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut buf).expect("the image decodes");
    assert!(info.width > 100 && info.height > 100);
    assert!(info.width <= 2000 && info.height <= 2000);
    let pixels: Vec<[u8; 3]> = buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let count = |c: [u8; 3]| pixels.iter().filter(|p| **p == c).count();
    assert!(
        count(tca_cg_space::picture::INVALID_CG) > 1000,
        "invalid cells"
    );
    assert!(count(tca_cg_space::picture::ROUTE) > 100, "the route");
    assert!(
        count(tca_cg_space::picture::FOOTFALL) > 100,
        "the footfalls"
    );
    assert!(
        count(tca_cg_space::picture::INVALID_FOOT) > 100,
        "the foot map"
    );
}

#[test]
fn bad_input_is_refused_naming_what_was_wrong() {
    let refused = |args: &[&str], names: &[&str]| {
        let began = Instant::now();
        let out = tca(args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        for n in names {
            assert!(stderr.contains(n), "{args:?}: {n:?} not in {stderr}");
        }
        assert!(began.elapsed() < Duration::from_secs(20), "{args:?}");
    };
    let base = ["plan", "cgspace"];
    let with = |more: &[&'static str]| -> Vec<&'static str> {
        base.iter().copied().chain(more.iter().copied()).collect()
    };
    refused(
        &with(&["--robot", "no-such-robot", "--terrain", "cliff"]),
        &["--robot", "no-such-robot"],
    );
    refused(
        &with(&["--robot", "ambler", "--terrain", "no-such-course"]),
        &["--terrain", "no-such-course", "cliff"],
    );
    refused(
        &with(&["--robot", "ambler", "--terrain", "cliff", "--from", "100,0"]),
        &["--from", "outside the map"],
    );
    refused(
        &with(&["--robot", "ambler", "--terrain", "cliff", "--to", "5,-40"]),
        &["--to", "outside the map"],
    );
    refused(
        &with(&["--robot", "ambler", "--terrain", "cliff", "--theta", "99"]),
        &["--theta", "99", "heading bin"],
    );
    refused(
        &with(&[
            "--robot",
            "ambler",
            "--terrain",
            "cliff",
            "--theta",
            "north",
        ]),
        &["--theta", "north"],
    );
    refused(
        &with(&["--robot", "ambler", "--terrain", "cliff", "--seeds", "5..2"]),
        &["--seeds"],
    );
}
