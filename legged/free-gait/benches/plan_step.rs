//! Planning time of one free-gait step for the Ambler on the rough and boulder courses,
//! against one inverse-kinematics solve in the same run.

use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point2;
use tca_free_gait::{FreeGait, GaitParams, GaitState, GridView, stand};
use tca_legged_courses::Course;
use tca_legged_model::{IkOptions, RobotModel};

/// States along a walk of the course (each planned step applied as planned), to plan from.
fn states(
    gait: &FreeGait,
    view: &GridView,
    start: GaitState,
    goal: Point2<f64>,
    n: usize,
) -> Vec<GaitState> {
    let mut out = vec![start];
    while out.len() < n {
        let Ok(plan) = gait.plan_step(out.last().expect("a state"), view, goal) else {
            break;
        };
        out.push(plan.end);
    }
    out
}

fn bench(c: &mut Criterion) {
    let model = Arc::new(RobotModel::builtin("ambler").expect("the Ambler"));
    let gait = FreeGait::new(model.clone(), GaitParams::for_model(&model));
    let leg = &model.legs()[0];
    let foot = leg.foot_position(&leg.neutral()).expect("foot");
    c.bench_function("baseline: one IK solve (Ambler leg)", |b| {
        b.iter(|| leg.inverse_kinematics(&foot, &IkOptions::default()))
    });
    for name in ["rough", "boulders"] {
        let course = Course::builtin(name, 1).expect("course");
        let view = GridView::new(Arc::new(course.terrain));
        let start = stand(
            &model,
            &view,
            course.start.x_m,
            course.start.y_m,
            course.start.yaw_rad,
        )
        .expect("stands");
        let walk = states(&gait, &view, start, course.goal, 40);
        let mut k = 0;
        c.bench_function(
            &format!("plan_step: Ambler on {name} (40 states along the walk)"),
            |b| {
                b.iter(|| {
                    k = (k + 1) % walk.len();
                    gait.plan_step(&walk[k], &view, course.goal)
                })
            },
        );
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
