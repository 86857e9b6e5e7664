//! LTM Manager benchmarks: Erim and Perceptron image -> elevation map, merging
//! into a 20 x 20 m map at 10 cm, footfall evaluation and region queries, on course 3 seen from
//! a carriage at y = 1 m.
//!
//! `CARGO_TARGET_DIR=/work/target-perception cargo bench -p tca-ltm --bench ltm`

use std::hint::black_box;
use std::sync::Arc;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use tca_ism::{SensorSpec, VirtualScanner};
use tca_ltm::{BuilderConfig, Cell, LocalTerrainMap, LtmConfig, Patch, build_map};
use tca_robot::{CarriagePose, Course, HeightField, LegParams};
use tca_single_leg_messages::{MapKind, MapRegion, PlanePoint, RangeImage};

fn course3() -> Arc<HeightField> {
    Arc::new(
        Course::builtin(3)
            .and_then(|course| Ok(course.height_field()?))
            .expect("course 3 renders"),
    )
}

fn image(spec: SensorSpec, terrain: &Arc<HeightField>, y_m: f64, seq: u64) -> RangeImage {
    VirtualScanner::new(spec, terrain.clone(), &LegParams::default())
        .cast(&CarriagePose::level(y_m), seq)
        .expect("casts")
}

fn builder(resolution_m: f64, threads: usize) -> BuilderConfig {
    BuilderConfig {
        resolution_m,
        threads,
        ..BuilderConfig::default()
    }
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<PlanePoint> {
    [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        .iter()
        .map(|&(x_m, y_m)| PlanePoint { x_m, y_m })
        .collect()
}

fn build(c: &mut Criterion) {
    let terrain = course3();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut group = c.benchmark_group("build");
    for spec in [SensorSpec::erim(), SensorSpec::perceptron()] {
        let img = image(spec, &terrain, 1.0, 0);
        for res in [0.1, 0.05] {
            for threads in [1, cores] {
                let config = builder(res, threads);
                group.bench_function(
                    format!(
                        "{:?} image -> map at {res} m, {threads} thread(s)",
                        spec.kind
                    ),
                    |b| b.iter(|| build_map(black_box(&img), &config).expect("builds")),
                );
            }
        }
    }
    group.finish();
}

/// A map at the configured resolution already holding `window`.
fn filled(config: &LtmConfig, window: &Patch) -> LocalTerrainMap {
    let mut map = LocalTerrainMap::new(config.clone()).expect("map");
    map.merge(window).expect("merges");
    map
}

fn merge(c: &mut Criterion) {
    let terrain = course3();
    let config = LtmConfig {
        builder: builder(0.1, 1),
        ..LtmConfig::default()
    };
    let erim = build_map(
        &image(SensorSpec::erim(), &terrain, 1.0, 0),
        &config.builder,
    )
    .expect("builds");
    // A patch covering the whole 20 x 20 m window.
    let mut window = Patch::unknown(-70, -90, 200, 200, 0.1);
    for (k, cell) in window.cells.iter_mut().enumerate() {
        *cell = Cell::known((k % 7) as f32 * 0.01, 0.02);
    }
    let mut group = c.benchmark_group("merge");
    group.bench_function("Erim patch into a 20 x 20 m map at 0.1 m", |b| {
        b.iter_batched_ref(
            || filled(&config, &window),
            |map| map.merge(black_box(&erim)).expect("merges"),
            BatchSize::LargeInput,
        )
    });
    group.bench_function("20 x 20 m patch into a 20 x 20 m map at 0.1 m", |b| {
        b.iter_batched_ref(
            || filled(&config, &window),
            |map| map.merge(black_box(&window)).expect("merges"),
            BatchSize::LargeInput,
        )
    });
    group.bench_function(
        "Erim image -> map -> merge at 0.1 m (whole add_image)",
        |b| {
            let img = image(SensorSpec::erim(), &terrain, 1.2, 3);
            b.iter_batched_ref(
                || filled(&config, &window),
                |map| map.add_image(black_box(&img)).expect("merges"),
                BatchSize::LargeInput,
            )
        },
    );
    group.finish();
}

fn queries(c: &mut Criterion) {
    let terrain = course3();
    let config = LtmConfig {
        builder: builder(0.05, 1),
        ..LtmConfig::default()
    };
    let mut map = LocalTerrainMap::new(config).expect("map");
    map.add_image(&image(SensorSpec::erim(), &terrain, 1.0, 0))
        .expect("merges");
    map.add_image(&image(SensorSpec::perceptron(), &terrain, 1.0, 1))
        .expect("merges");
    // 4 x 4 m in front of the leg, where the gait planner looks for footfalls.
    let region = |kind| MapRegion {
        kind,
        polygon: rect(1.0, 5.0, 5.0, 9.0),
        resolution_m: 0.05,
        refresh: false,
    };
    let mut group = c.benchmark_group("query");
    for kind in [MapKind::Elevation, MapKind::Footfall] {
        group.bench_function(format!("{kind:?} 4 x 4 m at 0.05 m, not cached"), |b| {
            b.iter(|| {
                map.clear_cache();
                map.query(black_box(&region(kind))).expect("answers")
            })
        });
        group.bench_function(format!("{kind:?} 4 x 4 m at 0.05 m, cached"), |b| {
            map.query(&region(kind)).expect("answers");
            b.iter(|| map.query(black_box(&region(kind))).expect("answers"))
        });
    }
    group.finish();
}

criterion_group!(benches, build, merge, queries);
criterion_main!(benches);
