//! Ray casting benchmark: a Perceptron-like 256 x 256 image (60 x 60 degrees) and an
//! Erim-like 64 x 256 image (30 degrees elevation x 80 degrees azimuth) cast from the
//! scanner's pose against course 3 at 2 cm, carriage at y = 1 m.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point3, Vector3};
use tca_robot::{CarriagePose, Course, HeightField, LegParams};

fn directions(
    rows: usize,
    cols: usize,
    elevation_fov_rad: f64,
    azimuth_fov_rad: f64,
) -> (Point3<f64>, Vec<Vector3<f64>>) {
    let params = LegParams::default();
    let pose = params
        .scanner
        .world_from_scanner(&params.carriage, &CarriagePose::level(1.0));
    let mut dirs = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        let el = elevation_fov_rad * (0.5 - (r as f64 + 0.5) / rows as f64);
        for c in 0..cols {
            let az = azimuth_fov_rad * (0.5 - (c as f64 + 0.5) / cols as f64);
            let local = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
            dirs.push(pose * local);
        }
    }
    (pose * Point3::origin(), dirs)
}

fn cast_all(t: &HeightField, origin: &Point3<f64>, dirs: &[Vector3<f64>]) -> usize {
    dirs.iter()
        .filter(|d| t.cast_ray(origin, d, 40.0).is_some())
        .count()
}

fn bench(c: &mut Criterion) {
    let course = Course::builtin(3).expect("course 3 exists");
    let terrain = course.height_field().expect("course 3 renders");
    let (origin, perceptron) = directions(256, 256, 60f64.to_radians(), 60f64.to_radians());
    let (_, erim) = directions(64, 256, 30f64.to_radians(), 80f64.to_radians());
    c.bench_function("cast 256x256 (Perceptron) course 3", |b| {
        b.iter(|| cast_all(black_box(&terrain), &origin, &perceptron))
    });
    c.bench_function("cast 64x256 (Erim) course 3", |b| {
        b.iter(|| cast_all(black_box(&terrain), &origin, &erim))
    });
    c.bench_function("render course 3 at 2 cm", |b| {
        b.iter(|| course.height_field())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
