//! The planner's speed: foothold selection for one leg and a whole plan across the
//! hexapod's walls course, against a baseline measured in the same run (one inverse
//! kinematics solution of the same leg, the unit of work a foothold choice repeats).

use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point2;
use tca_legged_courses::Course;
use tca_legged_model::RobotModel;
use tca_rrt::{Planner, RrtParams, select_foothold};

fn bench(c: &mut Criterion) {
    let model = Arc::new(RobotModel::builtin("hexapod").expect("the hexapod is built in"));
    let course = Course::builtin("hexapod-walls", 1).expect("the course is built in");
    let terrain = Arc::new(course.terrain.clone());
    let planner = Planner::new(model.clone(), terrain, RrtParams::default()).expect("planner");
    let robot = planner.robot();
    let posture = planner
        .posture_at(Point2::new(1.0, 0.0), 0.0)
        .expect("a posture at (1, 0)");
    let body = posture.body.isometry();
    let leg = 0;
    let neutral = model.legs()[leg].neutral();
    let target = body.inverse() * posture.feet[leg];
    c.bench_function("baseline: one inverse kinematics of a leg", |b| {
        b.iter(|| robot.leg_ik(leg, &target, &neutral))
    });
    c.bench_function("foothold selection for one leg", |b| {
        b.iter(|| {
            select_foothold(
                robot,
                planner.terrain(),
                planner.params(),
                &body,
                leg,
                &neutral,
            )
        })
    });
    let mut group = c.benchmark_group("plan");
    group.sample_size(10);
    group.bench_function("hexapod-walls, start to goal", |b| {
        b.iter(|| {
            planner
                .plan(
                    Point2::new(course.start.x_m, course.start.y_m),
                    course.start.yaw_rad,
                    course.goal,
                )
                .map(|p| p.postures.len())
                .expect("hexapod-walls (seed 1) is planned")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
