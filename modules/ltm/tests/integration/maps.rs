//! The LTM Manager's behaviour on scenes of known geometry.

use crate::common;

use common::{BOX, image, rect, scanner, terrain};
use nalgebra::Point2;
use tca_ism::SensorSpec;
use tca_ltm::{BuilderConfig, CellState, LocalTerrainMap, LtmConfig, LtmError, build_map};
use tca_single_leg_messages::{MapCell, MapKind, MapRegion, PlanePoint};

fn config() -> LtmConfig {
    LtmConfig {
        builder: BuilderConfig {
            resolution_m: 0.05,
            ..BuilderConfig::default()
        },
        ..LtmConfig::default()
    }
}

fn known_elevations(patch: &tca_ltm::Patch) -> Vec<f32> {
    patch
        .cells
        .iter()
        .filter(|c| c.state == CellState::Known)
        .map(|c| c.elevation_m)
        .collect()
}

#[test]
fn level_terrain_gives_a_level_map_within_the_resolution() {
    for spec in [SensorSpec::erim(), SensorSpec::perceptron()] {
        let resolution = spec.range_resolution_m() as f32;
        // Without noise: every known cell within the range resolution.
        let s = scanner(spec, terrain(&[]), false, 0);
        let patch = build_map(&image(&s, 1.0, 0), &BuilderConfig::default()).unwrap();
        let z = known_elevations(&patch);
        assert!(z.len() > 5_000, "{:?}: {} known cells", spec.kind, z.len());
        let worst = z.iter().fold(0f32, |m, v| m.max(v.abs()));
        assert!(worst < resolution, "{:?}: worst {worst} m", spec.kind);
        let (_, occluded, _) = patch.counts();
        assert_eq!(occluded, 0, "{:?}: nothing hides level ground", spec.kind);
        // With noise: unbiased, and nearly all within the resolution.
        let s = scanner(spec, terrain(&[]), true, 1);
        let patch = build_map(&image(&s, 1.0, 0), &BuilderConfig::default()).unwrap();
        let z = known_elevations(&patch);
        let mean = z.iter().sum::<f32>() / z.len() as f32;
        let within = z.iter().filter(|v| v.abs() < resolution).count() as f32 / z.len() as f32;
        assert!(
            mean.abs() < resolution / 4.0,
            "{:?}: mean {mean}",
            spec.kind
        );
        assert!(within > 0.98, "{:?}: {within} within", spec.kind);
    }
}

#[test]
fn a_box_appears_at_its_place_and_height_and_hides_what_is_behind() {
    for spec in [SensorSpec::erim(), SensorSpec::perceptron()] {
        let s = scanner(spec, terrain(&[BOX]), true, 2);
        let patch = build_map(&image(&s, 1.0, 0), &BuilderConfig::default()).unwrap();
        // The top, away from its edges, is known at the box's height. (The Erim's rows are
        // 15 cm apart on the box top and its ranges come in 7.6 cm steps, so its view of the
        // far edge is jagged by up to about 20 cm.)
        let mut top = Vec::new();
        for (i, j, c) in patch.iter() {
            let p = patch.center(i, j);
            let inner = p.x > BOX.min.x + 0.1
                && p.x < BOX.max.x - 0.1
                && p.y > BOX.min.y + 0.1
                && p.y < BOX.max.y - 0.2;
            if inner {
                assert_eq!(c.state, CellState::Known, "{:?} at {p}", spec.kind);
                top.push(c.elevation_m);
            }
        }
        let mean = top.iter().sum::<f32>() / top.len() as f32;
        assert!(
            (mean - BOX.height_m as f32).abs() < 0.03,
            "{:?}: box top at {mean} m",
            spec.kind
        );
        assert!(top.iter().all(|z| (z - 0.5).abs() < 0.1), "{:?}", spec.kind);
        // The ground in front of it is at 0.
        let front = patch.at(Point2::new(3.0, 7.0));
        assert_eq!(front.state, CellState::Known);
        assert!(front.elevation_m.abs() < 0.08, "{front:?}");
        // Behind it: occluded, with a bound between the ground and the box top. The scanner is
        // 4.5 m high and 6.5 m before the box's far edge: the shadow reaches 0.875 m behind it.
        for y in [8.65, 8.9, 9.2] {
            for x in [2.8, 3.0, 3.2] {
                let c = patch.at(Point2::new(x, y));
                assert_eq!(
                    c.state,
                    CellState::Occluded,
                    "{:?} at ({x}, {y}): {c:?}",
                    spec.kind
                );
                assert!(c.elevation_m > 0.0 && c.elevation_m <= 0.55, "{c:?}");
            }
        }
        // Beyond the shadow: ground again.
        let beyond = patch.at(Point2::new(3.0, 9.6));
        assert_eq!(beyond.state, CellState::Known, "{:?}", spec.kind);
        // Outside the field of view: unknown.
        assert_eq!(patch.at(Point2::new(3.0, 1.0)).state, CellState::Unknown);
    }
}

#[test]
fn two_merged_scans_are_more_certain_than_either() {
    let s = scanner(SensorSpec::erim(), terrain(&[BOX]), true, 3);
    let first = build_map(&image(&s, 1.0, 0), &BuilderConfig::default()).unwrap();
    let second = build_map(&image(&s, 1.6, 1), &BuilderConfig::default()).unwrap();
    let mut map = LocalTerrainMap::new(config()).unwrap();
    map.merge(&first).unwrap();
    map.merge(&second).unwrap();
    let mut both = 0;
    for (i, j, a) in first.iter() {
        let b = second.get(i, j);
        if a.state == CellState::Known && b.state == CellState::Known {
            let merged = map.store().cell(i, j).unwrap();
            assert_eq!(merged.state, CellState::Known);
            assert!(
                merged.sigma_m < a.sigma_m && merged.sigma_m < b.sigma_m,
                "({i}, {j}): {a:?} + {b:?} -> {merged:?}"
            );
            both += 1;
        }
    }
    assert!(both > 5_000, "{both} cells seen twice");
}

#[test]
fn a_map_scrolled_to_disk_and_back_is_unchanged() {
    let s = scanner(SensorSpec::erim(), terrain(&[BOX]), true, 4);
    let mut map = LocalTerrainMap::new(config()).unwrap();
    map.add_image(&image(&s, 1.0, 0)).unwrap();
    map.add_image(&image(&s, 2.0, 1)).unwrap();
    let (i0, j0, n) = (-40, 60, 200);
    let before = map.store().extract(i0, j0, n, n).unwrap();
    assert!(before.counts().2 > 10_000);
    let resident = map.store().resident_tiles();
    // Walk 40 m on: every tile leaves the window.
    let out = map.scroll_to(3.0, 42.0).unwrap();
    assert_eq!(out.paged_out, resident);
    assert_eq!(map.store().resident_tiles(), 0);
    // Walk back.
    let back = map.scroll_to(3.0, 2.0).unwrap();
    assert!(back.paged_in > 0);
    assert_eq!(map.store().extract(i0, j0, n, n).unwrap(), before);
}

#[test]
fn polygon_queries_mark_outside_cells_unknown_even_after_scrolling() {
    let s = scanner(SensorSpec::erim(), terrain(&[BOX]), true, 5);
    let mut map = LocalTerrainMap::new(config()).unwrap();
    map.add_image(&image(&s, 1.0, 0)).unwrap();
    let triangle = vec![
        PlanePoint { x_m: 1.0, y_m: 6.0 },
        PlanePoint { x_m: 5.0, y_m: 6.0 },
        PlanePoint {
            x_m: 3.0,
            y_m: 10.0,
        },
    ];
    for kind in [
        MapKind::Elevation,
        MapKind::ElevationUncertainty,
        MapKind::Footfall,
        MapKind::Slope,
    ] {
        let request = MapRegion {
            kind,
            polygon: triangle.clone(),
            resolution_m: 0.1,
            refresh: false,
        };
        let grid = map.query(&request).unwrap();
        assert_eq!(grid.kind, kind);
        assert_eq!((grid.nx, grid.ny), (41, 41));
        assert_eq!((grid.origin_x_m, grid.origin_y_m), (1.0, 6.0));
        let mut inside_known = 0;
        for (k, cell) in grid.cells.iter().enumerate() {
            let x = grid.origin_x_m + (k % grid.nx as usize) as f64 * grid.resolution_m;
            let y = grid.origin_y_m + (k / grid.nx as usize) as f64 * grid.resolution_m;
            // Outside the triangle (with a margin for cells on its edges): unknown.
            let half_width = 2.0 * (10.0 - y) / 4.0;
            if (x - 3.0).abs() > half_width + 0.01 || y < 6.0 {
                assert_eq!(*cell, MapCell::Unknown, "{kind:?} at ({x}, {y})");
            } else if (x - 3.0).abs() < half_width - 0.2 && matches!(cell, MapCell::Known { .. }) {
                inside_known += 1;
            }
        }
        assert!(inside_known > 300, "{kind:?}: {inside_known}");
        // After walking away and dropping the cache, the same answer comes from disk.
        map.scroll_to(3.0, 45.0).unwrap();
        map.clear_cache();
        assert_eq!(
            map.query(&request).unwrap(),
            grid,
            "{kind:?} after scrolling"
        );
        map.scroll_to(3.0, 1.0).unwrap();
    }
}

#[test]
fn footfall_and_slope_see_the_box_edges() {
    let s = scanner(SensorSpec::perceptron(), terrain(&[BOX]), true, 6);
    let mut map = LocalTerrainMap::new(config()).unwrap();
    map.add_image(&image(&s, 1.0, 0)).unwrap();
    let value = |kind, x: f64, y: f64, map: &mut LocalTerrainMap| {
        let g = map
            .query(&MapRegion {
                kind,
                polygon: rect(x - 0.01, y - 0.01, x + 0.01, y + 0.01),
                resolution_m: 0.05,
                refresh: false,
            })
            .unwrap();
        g.cells[0]
    };
    // Flat ground and the box top are good footfalls; the box's front edge is not.
    for (x, y) in [(3.0, 6.5), (3.0, 8.0)] {
        match value(MapKind::Footfall, x, y, &mut map) {
            MapCell::Known { value, .. } => assert!(value < 0.05, "({x}, {y}): {value}"),
            other => panic!("({x}, {y}): {other:?}"),
        }
    }
    match value(MapKind::Footfall, 3.0, 7.5, &mut map) {
        MapCell::Known { value, .. } => assert!(value > 0.15, "edge: {value}"),
        other => panic!("edge: {other:?}"),
    }
    match value(MapKind::Slope, 3.0, 6.5, &mut map) {
        MapCell::Known { value, .. } => assert!(value < 0.05, "{value}"),
        other => panic!("{other:?}"),
    }
    // Right behind the box the foot would stand in its shadow.
    assert!(matches!(
        value(MapKind::Footfall, 3.0, 8.9, &mut map),
        MapCell::Occluded { .. }
    ));
}

#[test]
fn overlapping_queries_reuse_cached_cells() {
    let s = scanner(SensorSpec::erim(), terrain(&[]), true, 7);
    let mut map = LocalTerrainMap::new(config()).unwrap();
    map.add_image(&image(&s, 1.0, 0)).unwrap();
    let q = |x0: f64| MapRegion {
        kind: MapKind::Footfall,
        polygon: rect(x0, 6.0, x0 + 2.0, 8.0),
        resolution_m: 0.1,
        refresh: false,
    };
    let a = map.query(&q(2.0)).unwrap();
    let after_a = map.cache_stats();
    assert_eq!(after_a.computed, 21 * 21);
    // Half of the second region overlaps the first: only the new half is computed.
    let b = map.query(&q(3.0)).unwrap();
    let after_b = map.cache_stats();
    assert_eq!(after_b.computed - after_a.computed, 10 * 21);
    assert_eq!(after_b.reused - after_a.reused, 11 * 21);
    // The overlap has the same values.
    assert_eq!(a.cells[10], b.cells[0]);
    // Merging a new image invalidates the cells it touches.
    map.add_image(&image(&s, 1.2, 1)).unwrap();
    map.query(&q(3.0)).unwrap();
    assert!(map.cache_stats().computed - after_b.computed >= 21 * 21);
}

#[test]
fn bad_input_gives_clear_errors() {
    let s = scanner(SensorSpec::erim(), terrain(&[]), false, 0);
    let mut img = image(&s, 1.0, 0);
    let mut map = LocalTerrainMap::new(config()).unwrap();
    // An Erim image with the Perceptron's size.
    img.width = 256;
    img.height = 256;
    let e = map.add_image(&img).unwrap_err();
    assert!(matches!(e, LtmError::Image(_)), "{e}");
    assert!(e.to_string().contains("must be 256 x 64"), "{e}");
    // A truncated image.
    let mut img = image(&s, 1.0, 0);
    img.reflectance.pop();
    assert!(
        map.add_image(&img)
            .unwrap_err()
            .to_string()
            .contains("reflectance")
    );
    // A bad transform.
    let mut img = image(&s, 1.0, 0);
    img.body_from_global.m[0] = 3.0;
    assert!(
        map.add_image(&img)
            .unwrap_err()
            .to_string()
            .contains("body <- global")
    );
    // Bad regions.
    let mut region = MapRegion {
        kind: MapKind::Elevation,
        polygon: rect(0.0, 0.0, 1.0, 1.0)[..2].to_vec(),
        resolution_m: 0.1,
        refresh: false,
    };
    assert!(matches!(
        map.query(&region),
        Err(LtmError::TooFewCorners(2))
    ));
    region.polygon = rect(0.0, 0.0, 1.0, 1.0);
    for bad in [0.0, f64::NAN, -0.1, f64::INFINITY] {
        region.resolution_m = bad;
        assert!(matches!(
            map.query(&region),
            Err(LtmError::BadResolution { .. })
        ));
    }
    region.resolution_m = 1e-5;
    assert!(matches!(
        map.query(&region),
        Err(LtmError::RegionTooLarge { .. })
    ));
    // The map is untouched by all this.
    assert_eq!(map.images_merged(), 0);
}

#[test]
fn wrapped_ranges_are_unwrapped_into_the_elevation_band() {
    // A scanner 25 m above the ground looking down: every Erim range wraps once.
    use nalgebra::{Isometry3, UnitQuaternion, Vector3};
    let ground = terrain(&[]);
    let down = Isometry3::from_parts(
        nalgebra::Translation3::new(0.0, 0.0, 21.0),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2),
    );
    let s = scanner(SensorSpec::erim(), ground, false, 0)
        .with_true_mount(down)
        .with_calibration(down.inverse());
    let patch = build_map(
        &image(&s, 6.0, 0),
        &BuilderConfig {
            max_horizontal_range_m: 30.0,
            ..BuilderConfig::default()
        },
    )
    .unwrap();
    let z = known_elevations(&patch);
    assert!(z.len() > 1000, "{}", z.len());
    assert!(
        z.iter().all(|v| v.abs() < 0.08),
        "{:?}",
        z.iter().fold(0f32, |m, v| m.max(v.abs()))
    );
}

#[test]
fn the_map_does_not_depend_on_the_builders_thread_count() {
    let s = scanner(SensorSpec::perceptron(), terrain(&[BOX]), true, 8);
    let img = image(&s, 1.0, 0);
    let one = build_map(&img, &BuilderConfig::default()).unwrap();
    let three = build_map(
        &img,
        &BuilderConfig {
            threads: 3,
            ..BuilderConfig::default()
        },
    )
    .unwrap();
    assert_eq!(one, three);
}
