//! The PDM's pictures: values coloured, unknown and occluded distinct, overlays drawn, bad
//! grids refused; and a real map of a box drawn end to end.

use std::sync::Arc;

use nalgebra::Point2;
use tca_ism::{SensorSpec, VirtualScanner};
use tca_ltm::{LocalTerrainMap, LtmConfig};
use tca_pdm::render::{OCCLUDED_COLOURS, OVERLAY, UNKNOWN_COLOURS, ramp};
use tca_pdm::{MapLayout, PdmError, RenderOptions, render, write_png};
use tca_robot::{CarriagePose, HeightField, LegParams};
use tca_single_leg_messages::{
    MapCell, MapGrid, MapKind, MapRegion, Overlay, PlanePoint, WorldPoint,
};

/// A 10 x 10 grid: values rising with x in the lower half, unknown top-left quarter, occluded
/// top-right quarter.
fn grid(kind: MapKind) -> MapGrid {
    let mut cells = Vec::new();
    for iy in 0..10 {
        for ix in 0..10 {
            cells.push(if iy < 5 {
                MapCell::Known {
                    value: ix as f32 / 9.0,
                    sigma_m: 0.01 * (1 + iy) as f32,
                }
            } else if ix < 5 {
                MapCell::Unknown
            } else {
                MapCell::Occluded {
                    max_elevation_m: 0.5,
                }
            });
        }
    }
    MapGrid {
        kind,
        origin_x_m: 1.0,
        origin_y_m: 2.0,
        resolution_m: 0.1,
        nx: 10,
        ny: 10,
        cells,
    }
}

#[test]
fn values_unknown_and_occluded_cells_are_told_apart() {
    let g = grid(MapKind::Elevation);
    let options = RenderOptions::default();
    let pic = render(&g, &[], &options).unwrap();
    let layout = MapLayout::of(&g, &options).unwrap();
    assert_eq!(layout.cell_px, 24);
    let at = |ix, iy| {
        let (x, y) = layout.cell_center(ix, iy);
        pic.pixel(x, y).unwrap()
    };
    assert_eq!(at(0, 0), ramp(0.0));
    assert_eq!(at(9, 2), ramp(1.0));
    // Patterns: sample the whole cell, both colours of the pattern appear and nothing else.
    for (ix, iy, colours) in [(2, 7, UNKNOWN_COLOURS), (7, 7, OCCLUDED_COLOURS)] {
        let (cx, cy) = layout.cell_center(ix, iy);
        let mut seen = std::collections::HashSet::new();
        for y in cy - 10..cy + 10 {
            for x in cx - 10..cx + 10 {
                let c = pic.pixel(x, y).unwrap();
                assert!(colours.contains(&c), "({ix}, {iy}): {c:?}");
                seen.insert(c);
            }
        }
        assert_eq!(seen.len(), 2);
    }
    // Uncertainty maps are coloured by sigma: rows differ, columns do not.
    let g = grid(MapKind::ElevationUncertainty);
    let pic = render(&g, &[], &options).unwrap();
    let px = |ix, iy| {
        let (x, y) = layout.cell_center(ix, iy);
        pic.pixel(x, y).unwrap()
    };
    assert_eq!(px(0, 0), px(9, 0));
    assert_eq!(px(0, 0), ramp(0.0));
    assert_eq!(px(3, 4), ramp(1.0));
}

#[test]
fn overlays_are_drawn_where_they_are() {
    let g = grid(MapKind::Footfall);
    let options = RenderOptions::default();
    let layout = MapLayout::of(&g, &options).unwrap();
    let foot = WorldPoint {
        x_m: 1.3,
        y_m: 2.2,
        z_m: 0.1,
    };
    let overlays = [
        Overlay::Point {
            at: foot,
            label: "footfall 1".into(),
        },
        Overlay::Path {
            points: vec![
                WorldPoint {
                    x_m: 1.0,
                    y_m: 2.9,
                    z_m: 0.0,
                },
                WorldPoint {
                    x_m: 1.9,
                    y_m: 2.9,
                    z_m: 0.0,
                },
                // Far off the map: clipped, no panic.
                WorldPoint {
                    x_m: 1e9,
                    y_m: -1e9,
                    z_m: 0.0,
                },
            ],
            label: "leg path".into(),
        },
        Overlay::Point {
            at: WorldPoint {
                x_m: f64::NAN,
                y_m: 0.0,
                z_m: 0.0,
            },
            label: "ignored".into(),
        },
    ];
    let pic = render(&g, &overlays, &options).unwrap();
    // The marker's circle passes 6 px right of the point.
    let (x, y) = layout.to_picture(&foot).unwrap();
    assert_eq!(
        pic.pixel((x + 6.0).round() as u32, y.round() as u32)
            .unwrap(),
        OVERLAY
    );
    // The path runs along y = 2.9 (cell row 9).
    let (px, py) = layout.cell_center(5, 9);
    assert_eq!(pic.pixel(px, py).unwrap(), OVERLAY);
}

#[test]
fn bad_grids_are_refused() {
    let mut g = grid(MapKind::Slope);
    g.cells.pop();
    let e = render(&g, &[], &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("need 100 values"), "{e}");
    let mut g = grid(MapKind::Slope);
    g.resolution_m = f64::NAN;
    assert!(matches!(
        render(&g, &[], &RenderOptions::default()),
        Err(PdmError::BadGrid(_))
    ));
    let mut g = grid(MapKind::Slope);
    g.nx = 0;
    g.cells.clear();
    assert!(render(&g, &[], &RenderOptions::default()).is_err());
    let g = MapGrid {
        nx: 10_000,
        ny: 1,
        cells: vec![MapCell::Unknown; 10_000],
        ..grid(MapKind::Slope)
    };
    assert!(matches!(
        render(&g, &[], &RenderOptions::default()),
        Err(PdmError::TooLarge { .. })
    ));
    // An all-unknown map still draws.
    let g = MapGrid {
        cells: vec![MapCell::Unknown; 100],
        ..grid(MapKind::Elevation)
    };
    render(&g, &[], &RenderOptions::default()).unwrap();
}

#[test]
fn a_real_map_of_a_box_is_written_as_png() {
    let (nx, ny, res) = (700, 1400, 0.02);
    let origin = Point2::new(-4.0, -4.0);
    let heights = (0..nx * ny)
        .map(|k| {
            let (x, y) = (
                origin.x + (k % nx) as f64 * res,
                origin.y + (k / nx) as f64 * res,
            );
            if (2.5..=3.5).contains(&x) && (7.5..=8.5).contains(&y) {
                0.5
            } else {
                0.0
            }
        })
        .collect();
    let terrain = Arc::new(HeightField::new(origin, res, nx, ny, heights).unwrap());
    // The scanner pitched 35° down, which puts the box in the Erim's view.
    let mut params = LegParams::default();
    params.scanner.pitch_down_rad = 35f64.to_radians();
    let scanner = VirtualScanner::new(SensorSpec::erim(), terrain, &params);
    let mut map = LocalTerrainMap::new(LtmConfig::default()).unwrap();
    map.add_image(&scanner.cast(&CarriagePose::level(1.0), 0).unwrap())
        .unwrap();
    let region = MapRegion {
        kind: MapKind::Elevation,
        polygon: [(0.0, 5.0), (6.0, 5.0), (6.0, 11.0), (0.0, 11.0)]
            .iter()
            .map(|&(x_m, y_m)| PlanePoint { x_m, y_m })
            .collect(),
        resolution_m: 0.05,
        refresh: false,
    };
    let g = map.query(&region).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.png");
    write_png(&path, &g, &[], &RenderOptions::default()).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let reader = decoder.read_info().unwrap();
    assert!(reader.info().width > 600);
    // The box top is the highest thing: the top of the ramp; its shadow is hatched.
    let options = RenderOptions::default();
    let pic = render(&g, &[], &options).unwrap();
    let layout = MapLayout::of(&g, &options).unwrap();
    let cell = |x: f64, y: f64| {
        let ix = ((x - g.origin_x_m) / g.resolution_m).round() as u32;
        let iy = ((y - g.origin_y_m) / g.resolution_m).round() as u32;
        let (px, py) = layout.cell_center(ix, iy);
        pic.pixel(px, py).unwrap()
    };
    let top = cell(3.0, 8.0);
    assert!(top[1] > 190 && top[2] < 100, "box top drawn as {top:?}");
    let shadow = cell(3.0, 9.0);
    assert!(
        OCCLUDED_COLOURS.contains(&shadow),
        "shadow drawn as {shadow:?}"
    );
    assert!(
        UNKNOWN_COLOURS.contains(&cell(3.0, 5.1)),
        "unseen foreground"
    );
    // An unwritable path is a clear error.
    let e = write_png(dir.path().join("no/such/dir/x.png"), &g, &[], &options).unwrap_err();
    assert!(
        matches!(e, PdmError::Picture(tca_canvas::CanvasError::Write { .. })),
        "{e}"
    );
}
