//! After a map update, D* Lite's repair against A* from scratch on the same changed map,
//! on a 100 x 100 m map at 0.1 m (1000 x 1000 cells) with a 50 m course.
//!
//! The scenario is the navigator's: the robot has planned across known rough ground
//! (random dangers and untraversable blobs), walked 1 m along its path, and its camera
//! finds a new untraversable blob across the path 0.5 to 1.5 m ahead. Both planners
//! then plan from the robot's cell on the changed map; their costs must agree. The node
//! counts and a time ratio measured here, in one run, are printed; criterion times both.

use std::time::Instant;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_nav_dstar_lite::{Cell, CostGrid, DStarLite, astar};

const N: usize = 1000; // 100 m at 0.1 m
const BETA: f64 = 2.0;

struct Scenario {
    planned: DStarLite,
    robot: Cell,
    blob: Vec<Cell>,
    goal: Cell,
}

fn scenario() -> Scenario {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let mut dangers: Vec<f64> = (0..N * N).map(|_| rng.random_range(0.0..0.4)).collect();
    for _ in 0..400 {
        let (cx, cy, r) = (
            rng.random_range(0..N) as isize,
            rng.random_range(0..N) as isize,
            rng.random_range(3..15) as isize,
        );
        for dy in -r..=r {
            for dx in -r..=r {
                let (x, y) = (cx + dx, cy + dy);
                if dx * dx + dy * dy <= r * r
                    && (0..N as isize).contains(&x)
                    && (0..N as isize).contains(&y)
                {
                    dangers[y as usize * N + x as usize] = f64::INFINITY;
                }
            }
        }
    }
    // A 50 m course: start and goal 500 cells apart; keep both cells clear.
    let (start, goal) = (Cell::new(250, 500), Cell::new(750, 500));
    for c in [start, goal] {
        dangers[c.iy * N + c.ix] = 0.0;
    }
    let grid = CostGrid::from_dangers(N, N, BETA, dangers).unwrap();
    let mut planned = DStarLite::new(grid, start, goal).unwrap();
    let path = planned.plan().expect("the course has a path");
    let robot = path.cells[10]; // about 1 m along
    planned.move_start(robot).unwrap();
    planned.plan().unwrap();
    let ahead = path.cells[20]; // 1 m ahead of the robot
    let blob = (-5isize..=5)
        .flat_map(|dy| (-5isize..=5).map(move |dx| (dx, dy)))
        .filter(|(dx, dy)| dx * dx + dy * dy <= 25)
        .map(|(dx, dy)| {
            Cell::new(
                (ahead.ix as isize + dx) as usize,
                (ahead.iy as isize + dy) as usize,
            )
        })
        .filter(|c| *c != robot && *c != goal)
        .collect();
    Scenario {
        planned,
        robot,
        blob,
        goal,
    }
}

fn replan(d: &mut DStarLite, blob: &[Cell]) -> tca_nav_dstar_lite::Path {
    for c in blob {
        d.set_danger(*c, f64::INFINITY).unwrap();
    }
    d.plan().unwrap()
}

fn bench(c: &mut Criterion) {
    let s = scenario();
    let mut changed = s.planned.grid().clone();
    for cell in &s.blob {
        changed.set_danger(*cell, f64::INFINITY).unwrap();
    }
    // Node counts and costs, one run each.
    let d = replan(&mut s.planned.clone(), &s.blob);
    let a = astar(&changed, s.robot, s.goal).unwrap();
    assert!(
        (d.cost - a.cost).abs() <= 1e-9 * a.cost,
        "costs differ: D* Lite {} A* {}",
        d.cost,
        a.cost
    );
    // Time ratio, measured here in the same run (the copy of the planned state is made and dropped outside the timing).
    let reps = 10;
    let mut t_d = 0.0;
    for _ in 0..reps {
        let mut copy = s.planned.clone();
        let t = Instant::now();
        std::hint::black_box(replan(&mut copy, &s.blob));
        t_d += t.elapsed().as_secs_f64();
        drop(copy);
    }
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(astar(&changed, s.robot, s.goal).unwrap());
    }
    let t_a = t.elapsed().as_secs_f64();
    println!(
        "replan on 1000 x 1000 (50 m course): D* Lite {} expansions, A* {} expansions: {:.1} x fewer; \
         time D* Lite {:.3} ms, A* {:.3} ms: {:.1} x faster; path cost {:.3} both",
        d.expansions,
        a.expansions,
        a.expansions as f64 / d.expansions.max(1) as f64,
        t_d / reps as f64 * 1e3,
        t_a / reps as f64 * 1e3,
        t_a / t_d,
        d.cost
    );
    let mut group = c.benchmark_group("replan_1000x1000");
    group.sample_size(10);
    group.bench_function("dstar_lite_repair", |b| {
        b.iter_batched(
            || s.planned.clone(),
            |mut d| {
                replan(&mut d, &s.blob);
                d
            },
            BatchSize::LargeInput,
        )
    });
    group.bench_function("astar_from_scratch", |b| {
        b.iter(|| astar(&changed, s.robot, s.goal).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
