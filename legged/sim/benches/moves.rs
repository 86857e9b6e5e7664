//! What a move costs: an Ambler swing of 0.5 m and a body move of 0.3 m, against one
//! evaluation of the robot's collision shapes measured in the same run (the figures to
//! compare are the ratios).

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point2, Vector3};
use tca_legged_model::{IkOptions, RobotModel};
use tca_legged_sim::{LeggedSim, SimParams, StartPose};
use tca_robot::HeightField;

fn setup() -> LeggedSim {
    let model = Arc::new(RobotModel::builtin("ambler").expect("ambler"));
    let terrain = Arc::new(
        HeightField::flat(Point2::new(-10.0, -10.0), Point2::new(10.0, 10.0), 0.1, 0.0)
            .expect("flat"),
    );
    let params = SimParams::for_model(&model);
    let start = StartPose {
        x_m: 0.0,
        y_m: 0.0,
        yaw_rad: 0.0,
    };
    LeggedSim::new(model, terrain, start, params).expect("stands")
}

/// Up 0.3 m, forward 0.5 m, down to 5 cm below the ground (a transition swing).
fn swing(sim: &LeggedSim) -> Vec<Vec<f64>> {
    let leg = &sim.model().legs()[0];
    let mut q = sim.posture()[0].clone();
    let foot = leg.foot_position(&q).expect("foot");
    [
        Vector3::new(0.0, 0.0, 0.3),
        Vector3::new(0.5, 0.0, 0.3),
        Vector3::new(0.5, 0.0, -0.05),
    ]
    .iter()
    .map(|d| {
        q = leg
            .inverse_kinematics(&(foot + d), &IkOptions::starting_at(&q))
            .expect("reachable")
            .joints;
        q.clone()
    })
    .collect()
}

fn bench(c: &mut Criterion) {
    let sim = setup();
    let mut group = c.benchmark_group("legged_sim");
    group.bench_function("baseline_collision_shapes", |b| {
        b.iter(|| {
            black_box(
                sim.model()
                    .collision_shapes(black_box(sim.posture()))
                    .expect("shapes"),
            )
        })
    });
    let waypoints = swing(&sim);
    group.bench_function("ambler_swing_0.5m", |b| {
        b.iter_batched(
            || sim.clone(),
            |mut s| {
                let r = s.leg_move("left_front", &waypoints, true).expect("swing");
                black_box(r.duration_s)
            },
            criterion::BatchSize::SmallInput,
        )
    });
    let mut target = sim.body();
    target.translation.vector.x += 0.3;
    group.bench_function("ambler_body_move_0.3m", |b| {
        b.iter_batched(
            || sim.clone(),
            |mut s| {
                let r = s.body_move(&target).expect("body move");
                black_box(r.duration_s)
            },
            criterion::BatchSize::SmallInput,
        )
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
