//! A route for the Ambler across a 96 x 96 m map with the roadmap's joins on 1 worker and on
//! 5 workers, in-process over the bus, each worker under the same region cap (what one strip
//! of five needs, a fraction of the map's regions), in the same run; then the same without
//! caps, which leaves only the parallelism. CG-space is built lazily from nothing for every
//! plan (the workers' and the planner's own), the robot's tables once.
//!
//! Besides criterion's report, prints the medians of runs taken in turn (`CG_BENCH_ROUNDS`,
//! default 5), their ratio (5 workers' time / 1 worker's), and how many of the machine's
//! cores the process kept busy while planning (its CPU time over the wall time).
//!
//! `CG_BENCH_DRAWS=N` sets the roadmap's draws per batch (default 48).
//!
//! `CG_BENCH_WRITE_TERRAIN=FILE.asc` also writes the terrain, for the same plan on worker
//! processes: `tca plan cgspace --robot ambler --terrain FILE.asc --from 4,48 --to 92,48
//! --workers 5 --region-cap 120 --route-only --json` (and `--workers 1`).

use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point2;
use tca_cg_space::{
    BatchParams, CgCell, CgParams, CgRobot, CgSpace, JoinError, JoinQuery, Joiner, Joins,
    Partition, Route, RouteParams, plan_route_batched,
};
use tca_cg_space_bus::{DistributedJoiner, InProcessWorkers, JoinStats, JoinerOptions};
use tca_legged_model::RobotModel;
use tca_module::{Connector, Module};
use tca_robot::HeightField;

/// 96 x 96 m of rolling ground with scattered steep rocks and three walls 4 m tall across
/// most of the way that the route must go round (open to the south, the north, the south).
fn terrain() -> HeightField {
    let res = 0.1;
    let n = 961;
    let mut h = Vec::with_capacity(n * n);
    for iy in 0..n {
        for ix in 0..n {
            let (x, y) = (ix as f64 * res, iy as f64 * res);
            let mut z = 0.3 * (x / 3.0).sin() * (y / 4.0).cos();
            if ((x * 0.7).sin() * (y * 0.9).cos()).abs() > 0.995 {
                z += 0.5;
            }
            let side = (n - 1) as f64 * res;
            let wall = (1..=3).any(|k| {
                let wx = side * f64::from(k) / 4.0;
                (wx..wx + 1.0).contains(&x)
                    && if k % 2 == 1 {
                        y > side * 0.22
                    } else {
                        y < side * 0.78
                    }
            });
            if wall {
                z = 4.0;
            }
            h.push(z);
        }
    }
    HeightField::new(Point2::new(0.0, 0.0), res, n, n, h).expect("a terrain")
}

/// A joiner timed: the wall-clock time spent waiting for its batches.
struct Timed<J> {
    inner: J,
    waited: Duration,
}

impl<J: Joiner> Joiner for Timed<J> {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        let began = Instant::now();
        let r = self.inner.join(space, queries);
        self.waited += began.elapsed();
        r
    }
}

/// The CPU time this process has used, from `/proc/self/stat` (Linux; clock ticks of
/// 10 ms), or `None` where it cannot be read.
fn cpu_used() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command's closing parenthesis: state is the 3rd field, utime the
    // 14th and stime the 15th.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    Some(Duration::from_millis(ticks * 10))
}

/// One measured plan.
struct Run {
    took: Duration,
    /// CPU time of the whole process (planner, central, workers) during the plan.
    cpu: Option<Duration>,
    waited: Duration,
    route: Route,
    stats: JoinStats,
}

struct Setup {
    robot: Arc<CgRobot>,
    terrain: HeightField,
    start: CgCell,
    goal: CgCell,
    cap: usize,
    runtime: tokio::runtime::Runtime,
    connector: Connector,
    _central: tca_central::RunningCentral,
}

impl Setup {
    fn space(&self) -> CgSpace {
        CgSpace::new(self.robot.clone(), &self.terrain).expect("a space")
    }

    /// One plan with `workers` workers under `cap`: the time of the plan alone (workers
    /// started before, stopped after), the route and what the joiner did.
    fn plan(&self, workers: usize, cap: Option<usize>) -> Run {
        let mut space = self.space();
        let joiner = self.runtime.block_on(async {
            let planner = Module::builder(format!("bench-planner-{workers}"))
                .connect(&self.connector)
                .await
                .expect("the planner connects");
            let factory = InProcessWorkers::new(self.connector.clone(), &space, cap);
            DistributedJoiner::start(planner, workers, factory, JoinerOptions::default())
                .await
                .expect("workers")
        });
        let mut joiner = Timed {
            inner: joiner,
            waited: Duration::ZERO,
        };
        let cpu_before = cpu_used();
        let began = Instant::now();
        let route = plan_route_batched(
            &mut space,
            &mut joiner,
            self.start,
            self.goal,
            &RouteParams::default(),
            &batch_params(),
        )
        .expect("a route");
        let took = began.elapsed();
        let cpu = cpu_used()
            .zip(cpu_before)
            .map(|(after, before)| after - before);
        let stats = self.runtime.block_on(joiner.inner.shutdown());
        Run {
            took,
            cpu,
            waited: joiner.waited,
            route,
            stats,
        }
    }
}

fn setup() -> Setup {
    let model = RobotModel::builtin("ambler").expect("the Ambler");
    let terrain = terrain();
    if let Ok(path) = std::env::var("CG_BENCH_WRITE_TERRAIN") {
        tca_robot::terrain::asc::write_height_field(&path, &terrain).expect("the terrain written");
        eprintln!("the terrain is in {path}");
    }
    let robot = Arc::new(CgRobot::new(&model, 0.1, CgParams::default()).expect("tables"));
    let space = CgSpace::new(robot.clone(), &terrain).expect("a space");
    let grid = *space.grid();
    let side = f64::from(grid.nx) * grid.cell_m;
    let start = grid
        .cell_of(Point2::new(4.0, side / 2.0), 0.0)
        .expect("start");
    let goal = grid
        .cell_of(Point2::new(side - 4.0, side / 2.0), 0.0)
        .expect("goal");
    let five = Partition::new(&grid, 5).expect("five strips");
    let params = RouteParams::default();
    let cap = (0..5)
        .map(|k| five.regions_in_reach(k, &params))
        .max()
        .unwrap_or(1);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("a runtime");
    let central = runtime
        .block_on(tca_central::start(tca_central::StartOptions::default()))
        .expect("central");
    let connector = Connector::from(central.in_process());
    let regions = five.region_columns() * five.region_rows();
    eprintln!(
        "Ambler 96 x 96 m: grid {} x {} x {} cells of {:.2} m, {regions} regions; cap {cap} regions per worker ({:.0} % of the map)",
        grid.nx,
        grid.ny,
        grid.theta_bins,
        grid.cell_m,
        100.0 * cap as f64 / f64::from(regions)
    );
    Setup {
        robot,
        terrain,
        start,
        goal,
        cap,
        runtime,
        connector,
        _central: central,
    }
}

/// The roadmap's batches: the default, or `CG_BENCH_DRAWS` draws a batch.
fn batch_params() -> BatchParams {
    let mut params = BatchParams::default();
    if let Some(draws) = std::env::var("CG_BENCH_DRAWS")
        .ok()
        .and_then(|d| d.parse().ok())
    {
        params.draws_per_batch = draws;
    }
    params
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn bench(c: &mut Criterion) {
    let s = setup();
    // Runs in turn, for the ratio.
    let rounds: usize = std::env::var("CG_BENCH_ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(5)
        .max(1);
    for (what, cap) in [("capped", Some(s.cap)), ("uncapped", None)] {
        let (mut one, mut five) = (Vec::new(), Vec::new());
        // Wall and CPU time over every run of each configuration, for the cores kept busy.
        let mut busy = [(Duration::ZERO, Some(Duration::ZERO)); 2];
        let mut shown = false;
        for _ in 0..rounds {
            let a = s.plan(1, cap);
            let b = s.plan(5, cap);
            assert_eq!(a.route, b.route, "the same route on 1 and on 5 workers");
            if !shown {
                shown = true;
                let r = &a.route;
                eprintln!(
                    "{what}: route {} cells, {} draws, {} searches in {} batches",
                    r.cells.len(),
                    r.draws,
                    r.searches,
                    a.stats.batches,
                );
                for (n, run) in [(1, &a), (5, &b)] {
                    let busy: Vec<f64> = run
                        .stats
                        .workers
                        .iter()
                        .map(|w| w.busy_us as f64 / 1e6)
                        .collect();
                    eprintln!(
                        "  {n} worker(s): plan {:.3} s, of which waiting for joins {:.3} s; workers searching {:.3} s in all ({}); cells evaluated {}, regions materialised {}",
                        run.took.as_secs_f64(),
                        run.waited.as_secs_f64(),
                        busy.iter().sum::<f64>(),
                        busy.iter()
                            .map(|b| format!("{b:.3}"))
                            .collect::<Vec<_>>()
                            .join(" + "),
                        run.stats.cells_evaluated(),
                        run.stats.regions_materialised()
                    );
                }
            }
            for (i, run) in [&a, &b].into_iter().enumerate() {
                busy[i].0 += run.took;
                busy[i].1 = busy[i].1.zip(run.cpu).map(|(sum, cpu)| sum + cpu);
            }
            one.push(a.took);
            five.push(b.took);
        }
        let cores = |(wall, cpu): (Duration, Option<Duration>)| {
            cpu.map_or("unknown".to_string(), |cpu| {
                format!("{:.2}", cpu.as_secs_f64() / wall.as_secs_f64())
            })
        };
        eprintln!(
            "{what}: cores busy while planning (process CPU time / wall time, all runs): 1 worker {}, 5 workers {}",
            cores(busy[0]),
            cores(busy[1])
        );
        let (m1, m5) = (median(one), median(five));
        eprintln!(
            "{what}: median of {rounds}: 1 worker {:.3} s, 5 workers {:.3} s, ratio (5 workers / 1 worker) {:.3}",
            m1.as_secs_f64(),
            m5.as_secs_f64(),
            m5.as_secs_f64() / m1.as_secs_f64()
        );
    }
    let mut group = c.benchmark_group("cg_space_distributed");
    group.sample_size(10);
    for (name, workers, cap) in [
        ("ambler_96x96_route_1_worker_capped", 1, Some(s.cap)),
        ("ambler_96x96_route_5_workers_capped", 5, Some(s.cap)),
    ] {
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| black_box(s.plan(workers, cap)).took)
                    .sum()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
