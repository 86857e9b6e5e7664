//! Maps from a legged robot's scanner: images taken from a body at any position and
//! orientation merge into a map that matches the terrain, and the window scrolls with the
//! body, at the Ambler's and at the hexapod's scale.

use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion};
use tca_ism::{BodyDimensions, SensorSpec, VirtualScanner};
use tca_ltm::{LocalTerrainMap, LtmConfig};
use tca_robot::HeightField;
use tca_single_leg_messages::{MapKind, MapRegion, PlanePoint, SensorKind};

/// Smooth relief plus one rounded boulder, scaled by `s` (1 for the Ambler's scale).
fn terrain(s: f64, cell: f64) -> Arc<HeightField> {
    let lo = Point2::new(-10.0 * s, -15.0 * s);
    let n = |span: f64| (span * s / cell).round() as usize + 1;
    let (nx, ny) = (n(40.0), n(40.0));
    let mut h = Vec::with_capacity(nx * ny);
    for iy in 0..ny {
        for ix in 0..nx {
            let (x, y) = (ix as f64 * cell / s - 10.0, iy as f64 * cell / s - 15.0);
            let relief = 0.3 * (0.5 * x).sin() * (0.4 * y).cos() + 0.15 * (0.9 * x + 0.3 * y).sin();
            let d = ((x - 8.0).powi(2) + (y - 6.5).powi(2)).sqrt() / 0.8;
            let boulder = if d < 1.0 {
                0.4 + 0.4 * (std::f64::consts::PI * d).cos()
            } else {
                0.0
            };
            h.push(s * (relief + boulder));
        }
    }
    Arc::new(HeightField::new(lo, cell, nx, ny, h).unwrap())
}

/// The body standing over `(x, y)` with the given attitude, `height` above the ground.
fn body_at(t: &HeightField, x: f64, y: f64, height: f64, rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, y, t.height_at(x, y) + height),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

/// Errors (map minus truth) of the cells ahead of the body, and the share of them known.
fn errors_ahead(
    map: &LocalTerrainMap,
    t: &HeightField,
    body: &Isometry3<f64>,
    ahead: (f64, f64),
    half_width: f64,
) -> (Vec<f64>, f64) {
    let r = map.store().resolution_m();
    let yaw = body.rotation.euler_angles().2;
    let (c, s) = (yaw.cos(), yaw.sin());
    let o = body.translation.vector;
    let (mut errors, mut total) = (Vec::new(), 0usize);
    let steps = |a: f64, b: f64| (0..=((b - a) / r) as usize).map(move |k| a + k as f64 * r);
    for f in steps(ahead.0, ahead.1) {
        for l in steps(-half_width, half_width) {
            let p = Point2::new(o.x + c * f - s * l, o.y + s * f + c * l);
            // The centre of the cell holding p.
            let centre = Point2::new((p.x / r).round() * r, (p.y / r).round() * r);
            total += 1;
            let cell = map.cell_at(centre).unwrap();
            if cell.is_known() {
                errors.push(f64::from(cell.elevation_m) - t.height_at(centre.x, centre.y));
            }
        }
    }
    let known = errors.len() as f64 / total as f64;
    (errors, known)
}

fn percentile(errors: &[f64], q: f64) -> f64 {
    let mut a: Vec<f64> = errors.iter().map(|e| e.abs()).collect();
    a.sort_by(f64::total_cmp);
    a[((a.len() - 1) as f64 * q) as usize]
}

fn check_scale(body: BodyDimensions, s: f64, cell: f64, foot: f64, tolerance: f64) {
    let t = terrain(s, cell / 2.0);
    let scanner = VirtualScanner::on_body(SensorSpec::perceptron(), t.clone(), body.mast_mount())
        .with_seed(4);
    let mut map = LocalTerrainMap::new(LtmConfig::for_robot(cell, 5.0 * s, foot)).unwrap();
    let reach = body.leg_reach_m();
    let ahead = (0.5 * body.length_m, 0.5 * body.length_m + 1.5 * reach);
    let half_width = 0.5 * body.width_m + 0.5 * reach;

    // Turned 0.7 rad, rolled and pitched a few degrees.
    let a = body_at(
        &t,
        5.0 * s,
        3.0 * s,
        body.standing_height_m,
        [0.05, -0.04, 0.7],
    );
    let image = scanner.cast_from_body(&a, 0).unwrap();
    let report = map.add_image(&image).unwrap();
    assert!(report.known > 1000, "{report:?}");
    let (errors, known) = errors_ahead(&map, &t, &a, ahead, half_width);
    let (p95, max) = (percentile(&errors, 0.95), percentile(&errors, 1.0));
    println!(
        "{body:?}: {:.0} % known ahead, 95 % within {p95:.4} m, max {max:.4} m",
        known * 100.0
    );
    assert!(
        known > 0.9,
        "{body:?}: only {known} of the cells ahead known"
    );
    assert!(p95 < tolerance, "{body:?}: 95th percentile error {p95} m");
    assert!(max < 3.0 * tolerance, "{body:?}: largest error {max} m");

    // A second image from another heading and attitude merges consistently.
    let b = body_at(
        &t,
        5.5 * s,
        2.5 * s,
        body.standing_height_m,
        [-0.03, 0.06, 0.2],
    );
    map.add_image(&scanner.cast_from_body(&b, 1).unwrap())
        .unwrap();
    let (errors, known) = errors_ahead(&map, &t, &a, ahead, half_width);
    assert!(known > 0.9);
    assert!(
        percentile(&errors, 0.95) < tolerance,
        "after the second image"
    );

    // Walk 10 m along the heading: the window follows, the first area pages out to disk
    // and still reads back.
    let yaw = 0.7_f64;
    let (x, y) = (
        5.0 * s + 10.0 * s * yaw.cos(),
        3.0 * s + 10.0 * s * yaw.sin(),
    );
    let c = body_at(&t, x, y, body.standing_height_m, [0.0, 0.02, yaw]);
    let report = map
        .add_image(&scanner.cast_from_body(&c, 2).unwrap())
        .unwrap();
    assert!(report.scroll.paged_out > 0, "{report:?}");
    let centre = map.store().center().unwrap();
    assert!((centre - Point2::new(x, y)).norm() < 1e-9);
    // The ground under the rear of the body at the first pose: its tile left the 10 m
    // window, its contents did not.
    let back = 0.5 * body.length_m - cell;
    let first = Point2::new(
        a.translation.x - back * yaw.cos(),
        a.translation.y - back * yaw.sin(),
    );
    let (i, j) = (
        (first.x / cell + 0.5).floor() as i64,
        (first.y / cell + 0.5).floor() as i64,
    );
    let (key, _) = map.store().locate(i, j);
    assert!(
        !map.store().is_resident(key),
        "the first area is still in memory"
    );
    assert!(map.cell_at(first).unwrap().is_known());
    assert!(map.store().tiles_on_disk() > 0);

    // Footfall maps answer for the robot's foot.
    let at = Point2::new(
        c.translation.x + 2.0 * ahead.0 * yaw.cos(),
        c.translation.y + 2.0 * ahead.0 * yaw.sin(),
    );
    let d = 2.0 * cell;
    let grid = map
        .query(&MapRegion {
            kind: MapKind::Footfall,
            polygon: vec![
                PlanePoint {
                    x_m: at.x - d,
                    y_m: at.y - d,
                },
                PlanePoint {
                    x_m: at.x + d,
                    y_m: at.y - d,
                },
                PlanePoint {
                    x_m: at.x + d,
                    y_m: at.y + d,
                },
                PlanePoint {
                    x_m: at.x - d,
                    y_m: at.y + d,
                },
            ],
            resolution_m: cell,
            refresh: false,
        })
        .unwrap();
    assert!(!grid.cells.is_empty());
    assert_eq!(map.config().sensor, SensorKind::Perceptron);
}

#[test]
fn ambler_scale_images_from_a_turned_tilted_body_map_the_terrain() {
    check_scale(BodyDimensions::AMBLER, 1.0, 0.1, 0.15, 0.03);
}

#[test]
fn hexapod_scale_images_from_a_turned_tilted_body_map_the_terrain() {
    check_scale(BodyDimensions::HEXAPOD, 0.1, 0.02, 0.012, 0.015);
}

#[test]
fn robot_sized_configurations_are_checked() {
    let c = LtmConfig::for_robot(0.02, 1.0, 0.012);
    assert_eq!(c.builder.resolution_m, 0.02);
    assert_eq!(c.window_m, 2.0);
    assert_eq!(c.foot.radius_m, 0.012);
    assert!((8..=256).contains(&c.tile_cells));
    assert!(LocalTerrainMap::new(c).is_ok());
    assert!(LocalTerrainMap::new(LtmConfig::for_robot(0.0, 1.0, 0.012)).is_err());
    assert!(LocalTerrainMap::new(LtmConfig::for_robot(0.1, f64::NAN, 0.15)).is_err());
    assert!(LocalTerrainMap::new(LtmConfig::for_robot(0.1, 10.0, -1.0)).is_err());
}
