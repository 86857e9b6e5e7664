//! A route and its footfalls for the Ambler across a 40 x 40 m map (CG-space built lazily
//! from nothing each time, the robot's tables built once), against one inverse-kinematics
//! solve in the same run. Before the measured runs (the default roadmap seed), one plan per
//! roadmap seed 1..=8 is timed and printed: how long planning takes depends on where the
//! foot-level search sticks, which the random roadmap decides.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point2;
use tca_cg_space::{CgParams, CgRobot, CgSpace, PlanParams, plan};
use tca_legged_model::{IkOptions, RobotModel};
use tca_robot::HeightField;

/// 40 x 40 m of rolling ground with scattered steep rocks and one wall to go round.
fn terrain() -> HeightField {
    let res = 0.1;
    let n = 401;
    let mut h = Vec::with_capacity(n * n);
    for iy in 0..n {
        for ix in 0..n {
            let (x, y) = (ix as f64 * res, iy as f64 * res);
            let mut z = 0.3 * (x / 3.0).sin() * (y / 4.0).cos();
            let rock = ((x * 0.7).sin() * (y * 0.9).cos()).abs() > 0.995;
            if rock {
                z += 0.5;
            }
            if (19.0..20.0).contains(&x) && (5.0..30.0).contains(&y) {
                z = 4.0;
            }
            h.push(z);
        }
    }
    HeightField::new(Point2::new(0.0, 0.0), res, n, n, h).expect("a terrain")
}

fn bench(c: &mut Criterion) {
    let model = RobotModel::builtin("ambler").expect("the Ambler");
    let t = terrain();
    let robot = Arc::new(CgRobot::new(&model, 0.1, CgParams::default()).expect("tables"));
    let plan_with_seed = |seed: u64| {
        let mut params = PlanParams::default();
        params.route.seed = seed;
        let mut space = CgSpace::new(robot.clone(), &t).expect("a space");
        plan(
            &mut space,
            (Point2::new(4.0, 20.0), 0.0),
            (Point2::new(36.0, 20.0), 0.0),
            None,
            &params,
        )
        .expect("a plan")
    };
    let default_seed = PlanParams::default().route.seed;
    let run = || plan_with_seed(default_seed);
    let describe = |p: &tca_cg_space::Plan| {
        format!(
            "route {} cells, {} foot moves, {} replans, {} routes",
            p.feet.route.len(),
            p.feet.foot_moves(),
            p.marked.len(),
            p.routes
        )
    };
    eprintln!(
        "Ambler 40 x 40 m, seed {default_seed}: {}",
        describe(&run())
    );
    let mut times = Vec::new();
    for seed in 1..=8 {
        let start = Instant::now();
        let p = plan_with_seed(seed);
        let took = start.elapsed().as_secs_f64();
        times.push(took);
        eprintln!("  roadmap seed {seed}: {took:.3} s, {}", describe(&p));
    }
    times.sort_by(f64::total_cmp);
    eprintln!(
        "  seeds 1..=8: median {:.3} s, {:.3}-{:.3} s, {} of 8 under 1 s",
        (times[3] + times[4]) / 2.0,
        times[0],
        times[7],
        times.iter().filter(|&&t| t < 1.0).count()
    );
    let mut group = c.benchmark_group("cg_plan");
    group.sample_size(10);
    group.bench_function("ambler_40x40_route_and_footfalls", |b| {
        b.iter(|| black_box(run()))
    });
    let leg = model.leg("left_front").expect("a leg");
    let target =
        leg.foot_position(&leg.neutral()).expect("a foot") + nalgebra::Vector3::new(0.2, 0.1, -0.3);
    group.bench_function("baseline_one_ik_solve", |b| {
        b.iter(|| black_box(leg.inverse_kinematics(&target, &IkOptions::default())))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
