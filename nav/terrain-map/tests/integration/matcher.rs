//! The LTM Matcher finds a known misplacement of a frame on uneven ground and refuses to
//! guess on flat ground.

use nalgebra::{Point2, Point3};
use tca_nav_terrain_map::{Ageing, MatchParams, TerrainMap};

fn ground(x: f64, y: f64) -> f64 {
    0.05 * (3.0 * x).sin() * (2.5 * y).cos() + 0.03 * (1.7 * x + 2.9 * y).sin()
}

/// Points of `f` over a square, every 5 mm.
fn sample(f: impl Fn(f64, f64) -> f64, cx: f64, cy: f64, half: f64) -> Vec<Point3<f64>> {
    let n = (2.0 * half / 0.005) as i32;
    let mut v = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (cx - half + i as f64 * 0.005, cy - half + j as f64 * 0.005);
            v.push(Point3::new(x, y, f(x, y)));
        }
    }
    v
}

fn map_of(f: impl Fn(f64, f64) -> f64) -> TerrainMap {
    let mut m = TerrainMap::new(Point2::new(0.0, 0.0), 0.02, 150, 150, Ageing::PAPER).unwrap();
    m.insert_frame(sample(f, 1.5, 1.5, 1.0));
    m
}

/// The points of the true ground around `c`, placed as a pose off by (ex, ey, eyaw) about
/// `c` would place them.
fn misplaced(c: Point2<f64>, ex: f64, ey: f64, eyaw: f64) -> Vec<Point3<f64>> {
    let (s, co) = eyaw.sin_cos();
    sample(ground, c.x, c.y, 0.5)
        .into_iter()
        .map(|p| {
            let (x, y) = (p.x - c.x, p.y - c.y);
            Point3::new(c.x + co * x - s * y + ex, c.y + s * x + co * y + ey, p.z)
        })
        .collect()
}

#[test]
fn a_misplaced_frame_is_put_back() {
    let map = map_of(ground);
    let c = Point2::new(1.5, 1.4);
    let (ex, ey, eyaw) = (0.008, -0.005, 0.006);
    let pts = misplaced(c, ex, ey, eyaw);
    let r = map
        .register(&pts, c, &MatchParams::default())
        .expect("a correction");
    // Moving the misplaced points by the correction puts them back where they belong.
    let probe = Point2::new(c.x + 0.3, c.y - 0.2);
    let (s, co) = eyaw.sin_cos();
    let off = Point2::new(
        c.x + co * (probe.x - c.x) - s * (probe.y - c.y) + ex,
        c.y + s * (probe.x - c.x) + co * (probe.y - c.y) + ey,
    );
    let back = r.apply(c, off);
    assert!((back - probe).norm() < 4e-3, "{r:?}: {back} vs {probe}");
    assert!(r.rms_after_m < r.rms_before_m, "{r:?}");
}

#[test]
fn a_well_placed_frame_stays() {
    let map = map_of(ground);
    let c = Point2::new(1.2, 1.7);
    let r = map
        .register(&misplaced(c, 0.0, 0.0, 0.0), c, &MatchParams::default())
        .expect("a correction");
    assert!(
        r.dx_m.hypot(r.dy_m) < 2e-3 && r.dyaw_rad.abs() < 1e-3,
        "{r:?}"
    );
}

#[test]
fn flat_ground_and_unknown_ground_give_no_correction() {
    let flat = map_of(|_, _| 0.1);
    let c = Point2::new(1.5, 1.5);
    let pts: Vec<_> = sample(|_, _| 0.1, c.x + 0.004, c.y, 0.5);
    assert_eq!(flat.register(&pts, c, &MatchParams::default()), None);
    let map = map_of(ground);
    let far: Vec<_> = sample(ground, 2.9, 2.9, 0.05);
    assert_eq!(
        map.register(&far, Point2::new(2.9, 2.9), &MatchParams::default()),
        None
    );
    assert_eq!(map.register(&[], c, &MatchParams::default()), None);
}
