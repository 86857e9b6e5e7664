//! How long a FootFall step takes to plan on the rock field, against one inverse
//! kinematics solve (the foot placed with its wheel upright) measured in the same run:
//! SBL with smoothing, and task-space A* with SBL as its fall-back, cycling over twenty
//! (leg, target) pairs drawn from the green cells as the campaign draws them; and one
//! leg's maps.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use tca_footfall::Scene;
use tca_footfall::campaign::draw_pairs;
use tca_footfall::maps::{MapParams, leg_maps};
use tca_footfall::plan::{PlanOptions, PlannerKind, StepPlanner};
use tca_footfall::reach::{FootGoal, ReachTolerance, place_foot, upright_axis};

fn benches(c: &mut Criterion) {
    let scene = Arc::new(Scene::rock_field(1).expect("the rover stands"));
    let options = PlanOptions::default();
    let planner = StepPlanner::new(scene.clone(), options.clone()).expect("a planner");
    let pairs = draw_pairs(&scene, &options.map, 20, 1).expect("green cells");
    for leg in 0..scene.model.legs().len() {
        planner
            .checker(leg, options.raise_m())
            .expect("the terrain meshes");
    }
    // Baseline: one solve, 10 cm from where the foot stands.
    let leg = &scene.model.legs()[0];
    let q0 = scene.posture[0].clone();
    let goal = FootGoal {
        centre: leg.foot_position(&q0).unwrap() + Vector3::new(0.1, 0.05, 0.0),
        axis: upright_axis(leg, -Vector3::z_axis()),
    };
    let tol = ReachTolerance::default();
    c.bench_function("baseline: one upright-foot IK solve", |b| {
        b.iter(|| black_box(place_foot(leg, black_box(&goal), &[&q0], &tol)))
    });
    for kind in [PlannerKind::Sbl, PlannerKind::Astar] {
        let mut o = options.clone();
        o.planner = kind;
        let mut k = 0;
        c.bench_function(
            &format!("plan a step ({}), 20 pairs in turn", kind.name()),
            |b| {
                b.iter(|| {
                    let (leg, target) = pairs[k % pairs.len()];
                    k += 1;
                    black_box(planner.plan_with(leg, target, &o).ok())
                })
            },
        );
    }
    let mut group = c.benchmark_group("maps");
    group.sample_size(10);
    group.bench_function("one leg's maps (5 cm cells)", |b| {
        b.iter(|| black_box(leg_maps(&scene, 0, &MapParams::default()).ok()))
    });
    group.finish();
}

criterion_group!(plan_step, benches);
criterion_main!(plan_step);
