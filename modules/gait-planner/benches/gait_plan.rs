//! Gait plan and leg trajectory per step on course 3 (§7.2: about 2 s and 12 s per step in
//! 1990; the target here is both within 20 ms). The terrain maps are the LTM Manager's work
//! and are built beforehand.
//!
//! Run with `CARGO_TARGET_DIR=/work/target-planning cargo bench -p tca-gait-planner`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point2, Point3};
use tca_gait_planner::{GaitMaps, GaitParams, GaitPlanner, synthetic};
use tca_lrp::{LegRecoveryPlanner, LrpParams, TerrainGrid};
use tca_robot::{CarriagePose, Course, ElbowBranch, LegKinematics, LegParams};

fn bench(c: &mut Criterion) {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let (body_y, goal_y) = (1.0, 9.5);
    let gait = GaitPlanner::new(LegParams::default(), GaitParams::default()).unwrap();
    let lrp = LegRecoveryPlanner::new(LegParams::default(), LrpParams::default()).unwrap();
    let region = gait.region(body_y, goal_y).unwrap();
    let poly = gait.map_polygon(&region);
    let (lo, hi) = (
        Point2::new(poly[0].x_m, poly[0].y_m),
        Point2::new(poly[2].x_m, poly[2].y_m),
    );
    let footfall = synthetic::footfall_map(&terrain, lo, hi, 0.1, 0.15).unwrap();
    let elevation = synthetic::elevation_map(&terrain, lo, hi, 0.1).unwrap();
    let lrp_map = TerrainGrid::elevation_from_height_field(
        &terrain,
        Point2::new(0.0, body_y - 2.9),
        Point2::new(6.0, body_y + 2.9),
        0.05,
    )
    .unwrap();
    let start = LegKinematics::new(&LegParams::default())
        .inverse_world(
            &CarriagePose::level(body_y),
            &Point3::new(3.8, 0.6, 0.0),
            ElbowBranch::Positive,
        )
        .unwrap();

    let cs = lrp.cspace(&lrp_map, body_y).unwrap();
    let reach = lrp.reachability(&cs, &start).unwrap();
    let reachable = |p: Point2<f64>| reach.reaches(p);
    let maps = GaitMaps {
        footfall: &footfall,
        elevation: &elevation,
        reachable: &reachable,
    };

    let mut g = c.benchmark_group("course 3 step");
    g.bench_function("gait plan", |b| {
        b.iter(|| gait.plan(black_box(body_y), goal_y, &maps).unwrap())
    });
    g.bench_function("gait plan and leg trajectory", |b| {
        b.iter(|| {
            // The LRP builds its configuration space once per step and answers both the
            // reachability query and the recoverLeg goal from it.
            let cs = lrp.cspace(black_box(&lrp_map), body_y).unwrap();
            let reach = lrp.reachability(&cs, &start).unwrap();
            let reachable = |p: Point2<f64>| reach.reaches(p);
            let step = gait
                .plan(
                    body_y,
                    goal_y,
                    &GaitMaps {
                        footfall: &footfall,
                        elevation: &elevation,
                        reachable: &reachable,
                    },
                )
                .unwrap();
            lrp.plan_in(&cs, &start, &step.footfall).unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
