//! Leg trajectory per step on course 3 (§7.2: about 12 s per step in 1990): the
//! configuration space, the ETFA search with its trajectory, and the reachability map.
//!
//! Run with `CARGO_TARGET_DIR=/work/target-planning cargo bench -p tca-lrp`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point2, Point3};
use tca_lrp::{LegRecoveryPlanner, LrpParams, TerrainGrid};
use tca_robot::{CarriagePose, Course, ElbowBranch, LegKinematics, LegParams};

fn bench(c: &mut Criterion) {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let body_y = 1.0;
    let map = TerrainGrid::elevation_from_height_field(
        &terrain,
        Point2::new(0.0, body_y - 2.9),
        Point2::new(6.0, body_y + 2.9),
        0.05,
    )
    .unwrap();
    let planner = LegRecoveryPlanner::new(LegParams::default(), LrpParams::default()).unwrap();
    let kin = LegKinematics::new(&LegParams::default());
    let pose = CarriagePose::level(body_y);
    // The first step of the course-3 walk: from behind the sun box to its left.
    let start = kin
        .inverse_world(&pose, &Point3::new(3.8, 0.6, 0.0), ElbowBranch::Positive)
        .unwrap();
    let footfall = Point3::new(
        1.55,
        1.75,
        terrain.max_height_in_disc(Point2::new(1.55, 1.75), 0.15),
    );
    let cs = planner.cspace(&map, body_y).unwrap();

    let mut g = c.benchmark_group("lrp course 3 step");
    g.bench_function("configuration space", |b| {
        b.iter(|| planner.cspace(black_box(&map), body_y).unwrap())
    });
    g.bench_function("ETFA and trajectory", |b| {
        b.iter(|| planner.plan_in(&cs, black_box(&start), &footfall).unwrap())
    });
    g.bench_function("reachability", |b| {
        b.iter(|| {
            planner
                .reachability(&cs, black_box(&start))
                .unwrap()
                .to_grid(Point2::new(0.55, 1.05), 0.1, 50, 25)
                .unwrap()
        })
    });
    g.bench_function("whole leg trajectory", |b| {
        b.iter(|| {
            planner
                .plan(black_box(&map), body_y, &start, &footfall)
                .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
