//! The navigation loop's rate on the bus against the same loop in one function, on the hill
//! course (seed 1, drift 1.25 %): the whole run to the goal each time, frames counted. The
//! ratio of the two, measured here in one run, is printed; criterion times both.

use std::sync::Arc;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use tca_nav_bus::{NavBase, NavSetup, run_on_bus};
use tca_nav_navigator::{
    Course, RunOptions, RunReport, WheeledBase, WheeledParams, hill_course, run, wheeled_params,
};

fn options(course: &Course) -> RunOptions {
    RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed: 1,
        max_frames: 1500,
    }
}

fn direct(course: &Course) -> RunReport {
    let mut base = WheeledBase::new(WheeledParams::PIONEER, &course.terrain, course.start);
    run(
        &course.terrain,
        &mut base,
        wheeled_params(),
        &options(course),
    )
    .expect("the run")
    .0
}

async fn on_bus(course: &Course, setup: &NavSetup) -> RunReport {
    run_on_bus(setup, &options(course), None)
        .await
        .expect("the run")
        .report
}

fn bench(c: &mut Criterion) {
    let course = hill_course().expect("the hill course");
    let setup = NavSetup {
        terrain: Arc::new(course.terrain.clone()),
        base: NavBase::Wheeled(WheeledParams::PIONEER),
        params: wheeled_params(),
        start: course.start,
        drift: 0.0125,
        seed: 1,
    };
    let rt = tokio::runtime::Runtime::new().expect("a runtime");
    // One timing of each, side by side, for the ratio.
    let t = Instant::now();
    let a = direct(&course);
    let direct_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let b = rt.block_on(on_bus(&course, &setup));
    let bus_s = t.elapsed().as_secs_f64();
    assert_eq!(a.frames, b.frames, "the same run");
    println!(
        "hill, {} frames: one function {:.3} s ({:.1} frames/s, loop_hz {:.1}); on the bus {:.3} s ({:.1} frames/s, loop_hz {:.1}); bus / one function = {:.3}",
        a.frames,
        direct_s,
        a.frames as f64 / direct_s,
        a.loop_hz,
        bus_s,
        b.frames as f64 / bus_s,
        b.loop_hz,
        bus_s / direct_s
    );
    let mut g = c.benchmark_group("navigation run, hill course");
    g.sample_size(10);
    g.bench_function("one function", |x| x.iter(|| direct(&course)));
    g.bench_function("modules on an in-process central", |x| {
        x.to_async(&rt).iter(|| on_bus(&course, &setup))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
