//! Virtual scanner benchmarks: one Erim (64 x 256) and one Perceptron (256 x 256) image of
//! course 3 from a carriage at y = 1 m, with noise, on one thread and on all cores; and the
//! calibration target fit.
//!
//! `CARGO_TARGET_DIR=/work/target-perception cargo bench -p tca-ism --bench scan`

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use tca_ism::{SensorSpec, VirtualScanner};
use tca_robot::{CarriagePose, Course, LegParams};

fn bench(c: &mut Criterion) {
    let terrain = Arc::new(
        Course::builtin(3)
            .and_then(|course| Ok(course.height_field()?))
            .expect("course 3 renders"),
    );
    let params = LegParams::default();
    let pose = CarriagePose::level(1.0);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut group = c.benchmark_group("acquire");
    for spec in [SensorSpec::erim(), SensorSpec::perceptron()] {
        for threads in [1, cores] {
            let scanner = VirtualScanner::new(spec, terrain.clone(), &params).with_threads(threads);
            group.bench_function(
                format!("{:?} course 3, {threads} thread(s)", spec.kind),
                |b| b.iter(|| scanner.cast(black_box(&pose), 0).expect("casts")),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
