//! PDM benchmarks: drawing the elevation map of the whole course pit (6 x 11 m at 5 cm, 121 x
//! 221 cells) built from Erim images of course 3, with ten footfalls over it, to a picture and
//! to PNG bytes.
//!
//! `nice -n 10 cargo bench -p tca-pdm --bench render` (figures in the root BENCHMARKS.md).

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use tca_ism::{SensorSpec, VirtualScanner};
use tca_ltm::{LocalTerrainMap, LtmConfig};
use tca_pdm::{RenderOptions, render, render_png};
use tca_robot::{CarriagePose, Course, LegParams};
use tca_single_leg_messages::{MapGrid, MapKind, MapRegion, Overlay, PlanePoint, WorldPoint};

fn pit_map(kind: MapKind) -> MapGrid {
    let terrain = Arc::new(
        Course::builtin(3)
            .and_then(|course| Ok(course.height_field()?))
            .expect("course 3 renders"),
    );
    let scanner = VirtualScanner::new(SensorSpec::erim(), terrain, &LegParams::default());
    let mut map = LocalTerrainMap::new(LtmConfig::default()).expect("a map");
    for (k, y) in [1.0, 3.0, 5.0, 7.0].into_iter().enumerate() {
        let image = scanner
            .cast(&CarriagePose::level(y), k as u64)
            .expect("casts");
        map.add_image(&image).expect("merges");
    }
    let pit = [(0.0, 0.0), (6.0, 0.0), (6.0, 11.0), (0.0, 11.0)]
        .iter()
        .map(|&(x_m, y_m)| PlanePoint { x_m, y_m })
        .collect();
    map.query(&MapRegion {
        kind,
        polygon: pit,
        resolution_m: 0.05,
        refresh: false,
    })
    .expect("the pit's map")
}

fn bench(c: &mut Criterion) {
    let footfalls: Vec<Overlay> = (0..10)
        .map(|k| Overlay::Point {
            at: WorldPoint {
                x_m: 3.5,
                y_m: 1.0 + f64::from(k) * 0.9,
                z_m: 0.0,
            },
            label: format!("{}", k + 1),
        })
        .collect();
    let options = RenderOptions::default();
    let mut group = c.benchmark_group("render");
    for kind in [MapKind::Elevation, MapKind::Footfall] {
        let grid = pit_map(kind);
        group.bench_function(format!("{kind:?} 121 x 221 cells -> picture"), |b| {
            b.iter(|| render(black_box(&grid), &footfalls, &options).expect("draws"))
        });
        group.bench_function(format!("{kind:?} 121 x 221 cells -> PNG bytes"), |b| {
            b.iter(|| render_png(black_box(&grid), &footfalls, &options).expect("encodes"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
