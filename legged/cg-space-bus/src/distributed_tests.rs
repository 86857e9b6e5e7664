//! The roadmap's joins on in-process workers over the bus: the same route as planned
//! locally, a worker that dies mid-plan replaced, a worker set up for another terrain
//! refusing.

use std::sync::Arc;
use std::time::Duration;

use crate::{
    DistributedJoiner, InProcessWorkers, JoinBatch, JoinerOptions, Worker, WorkerError,
    WorkerFactory, WorkerHandle, join_registration, worker_name,
};
use futures::future::BoxFuture;
use nalgebra::Point2;
use tca_cg_space::{
    BatchParams, BatchedRouteError, CgCell, CgParams, CgRobot, CgSpace, JoinError, JoinQuery,
    Joiner, Joins, LocalJoiner, Partition, Route, RouteParams, plan_route_batched,
};
use tca_legged_courses::Course;
use tca_legged_model::RobotModel;
use tca_module::{Connector, Module};
use tca_testkit::within_for;

/// The Ambler's CG-space on the cliff course built from `seed`, and its start and goal cells.
fn cliff(seed: u64) -> (CgSpace, CgCell, CgCell) {
    let course = Course::builtin("cliff", seed).expect("the cliff course");
    let model = RobotModel::builtin("ambler").expect("the Ambler");
    let robot = CgRobot::new(
        &model,
        course.terrain.grid().resolution_m(),
        CgParams::default(),
    )
    .expect("tables");
    let space = CgSpace::new(Arc::new(robot), &course.terrain).expect("a space");
    let grid = *space.grid();
    let s = grid
        .cell_of(
            Point2::new(course.start.x_m, course.start.y_m),
            course.start.yaw_rad,
        )
        .expect("start on the map");
    let g = grid
        .cell_of(course.goal, course.start.yaw_rad)
        .expect("goal on the map");
    (space, s, g)
}

fn local_route(seed: u64, batch: &BatchParams) -> Route {
    let (mut space, s, g) = cliff(seed);
    plan_route_batched(
        &mut space,
        &mut LocalJoiner,
        s,
        g,
        &RouteParams::default(),
        batch,
    )
    .expect("a local route")
}

async fn central() -> (tca_central::RunningCentral, Connector) {
    tca_testkit::central::in_process_central().await
}

/// The largest cap any of `workers` strips needs.
fn cap_for(space: &CgSpace, workers: usize) -> usize {
    let p = Partition::new(space.grid(), workers).expect("a partition");
    (0..workers)
        .map(|k| p.regions_in_reach(k, &RouteParams::default()))
        .max()
        .unwrap_or(1)
}

/// Plans on a blocking thread (the joiner blocks while the workers search).
async fn plan<J: Joiner + Send + 'static>(
    mut space: CgSpace,
    mut joiner: J,
    s: CgCell,
    g: CgCell,
    batch: BatchParams,
) -> (Result<Route, BatchedRouteError>, J, CgSpace) {
    tokio::task::spawn_blocking(move || {
        let r = plan_route_batched(
            &mut space,
            &mut joiner,
            s,
            g,
            &RouteParams::default(),
            &batch,
        );
        (r, joiner, space)
    })
    .await
    .expect("the planning thread")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn three_workers_give_the_local_route() {
    let local = local_route(1, &BatchParams::default());
    let (space, s, g) = cliff(1);
    let (_central, connector) = central().await;
    let planner = Module::builder("cgspace-planner")
        .connect(&connector)
        .await
        .expect("the planner connects");
    let cap = cap_for(&space, 3);
    let workers = InProcessWorkers::new(connector.clone(), &space, Some(cap));
    let joiner = DistributedJoiner::start(planner, 3, workers, JoinerOptions::default())
        .await
        .expect("three workers");
    let (route, joiner, planner_space) = within_for(
        Duration::from_secs(60),
        "the distributed plan",
        plan(space, joiner, s, g, BatchParams::default()),
    )
    .await;
    let route = route.expect("a distributed route");
    assert_eq!(route, local, "the same route as the local joiner's");
    // By the ramp: where the route crosses the cliff's line it is on the ramp's side.
    let grid = *planner_space.grid();
    for c in &route.cells {
        let at = grid.centre(c.ix, c.iy);
        if (at.x - 14.0).abs() < 1.0 {
            assert!(at.y > 2.0, "the route crosses the cliff at {at:?}");
        }
    }
    let stats = joiner.shutdown().await;
    eprintln!(
        "route: {} cells, {} draws, {} searches; {stats:?}",
        route.cells.len(),
        route.draws,
        route.searches
    );
    assert_eq!(stats.replacements, 0);
    assert!(stats.batches > 1, "{stats:?}");
    assert_eq!(stats.queries as usize, route.searches);
    assert!(
        stats.queries_per_worker.iter().all(|&q| q > 0),
        "every strip joined something: {stats:?}"
    );
    for w in &stats.workers {
        assert!(w.regions_held <= cap as u64, "{w:?} over the cap {cap}");
        assert!(w.cells_evaluated > 0);
    }
}

/// Forwards to a distributed joiner; at batch `kill_at`, closes the worker owning most of
/// the batch's queries as the batch goes out.
struct Killer {
    inner: DistributedJoiner,
    workers: InProcessWorkers,
    batches: usize,
    kill_at: usize,
    killed: Option<usize>,
    runtime: tokio::runtime::Handle,
}

impl Joiner for Killer {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        self.batches += 1;
        if self.batches == self.kill_at {
            let p = Partition::new(space.grid(), self.inner.workers()).expect("a partition");
            let mut counts = vec![0usize; self.inner.workers()];
            for q in queries {
                counts[p.owner(q)] += 1;
            }
            let k = (0..counts.len())
                .max_by_key(|&k| counts[k])
                .expect("workers");
            let module = self.workers.module(k).expect("worker started");
            self.runtime.spawn(async move { module.close().await });
            self.killed = Some(k);
        }
        self.inner.join(space, queries)
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_killed_mid_plan_is_replaced() {
    // Small batches, so that the plan takes several and the death falls in the middle.
    let batch = BatchParams {
        draws_per_batch: 12,
    };
    let local = local_route(1, &batch);
    let (space, s, g) = cliff(1);
    let (_central, connector) = central().await;
    let planner = Module::builder("cgspace-planner")
        .connect(&connector)
        .await
        .expect("the planner connects");
    let workers = InProcessWorkers::new(connector.clone(), &space, Some(cap_for(&space, 3)));
    let inner = DistributedJoiner::start(planner, 3, workers.clone(), JoinerOptions::default())
        .await
        .expect("three workers");
    let killer = Killer {
        inner,
        workers: workers.clone(),
        batches: 0,
        kill_at: 3,
        killed: None,
        runtime: tokio::runtime::Handle::current(),
    };
    let (route, killer, _) = within_for(
        Duration::from_secs(60),
        "the plan with a death",
        plan(space, killer, s, g, batch),
    )
    .await;
    let route = route.expect("a route despite the death");
    assert_eq!(route, local, "the same route");
    let k = killer.killed.expect("a worker was killed");
    let replacement = workers.module(k).expect("a replacement");
    assert!(!replacement.is_closed(), "worker {k} runs again");
    let stats = killer.inner.shutdown().await;
    eprintln!(
        "killed worker {k} at batch 3 of {}: {stats:?}",
        killer.batches
    );
    assert_eq!(stats.replacements, 1, "{stats:?}");
}

/// Starts real workers, except that worker 1's first start crashes (drops its link) as soon
/// as it is given joins.
struct CrashOnce {
    real: InProcessWorkers,
    connector: Connector,
    crashed: std::sync::atomic::AtomicBool,
}

struct Crasher(Module);

impl WorkerHandle for Crasher {
    fn stop(self: Box<Self>) -> BoxFuture<'static, ()> {
        Box::pin(async move { self.0.abort_link() })
    }
}

impl WorkerFactory for CrashOnce {
    fn start(&self, index: usize) -> BoxFuture<'_, Result<Box<dyn WorkerHandle>, JoinError>> {
        Box::pin(async move {
            if index != 1 || self.crashed.swap(true, std::sync::atomic::Ordering::SeqCst) {
                return self.real.start(index).await;
            }
            let module = Module::builder(worker_name(1))
                .handle_raw(
                    join_registration(1).expect("a registration"),
                    |ctx, _| async move {
                        ctx.module().abort_link();
                        std::future::pending::<()>().await;
                        Ok(Vec::new())
                    },
                )
                .connect(&self.connector)
                .await
                .map_err(|e| JoinError::new(e.to_string()))?;
            Ok(Box::new(Crasher(module)) as Box<dyn WorkerHandle>)
        })
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_crashing_while_it_searches_is_replaced_and_asked_again() {
    let local = local_route(1, &BatchParams::default());
    let (space, s, g) = cliff(1);
    let (_central, connector) = central().await;
    let planner = Module::builder("cgspace-planner")
        .connect(&connector)
        .await
        .expect("the planner connects");
    let factory = CrashOnce {
        real: InProcessWorkers::new(connector.clone(), &space, Some(cap_for(&space, 3))),
        connector: connector.clone(),
        crashed: std::sync::atomic::AtomicBool::new(false),
    };
    let joiner = DistributedJoiner::start(planner, 3, factory, JoinerOptions::default())
        .await
        .expect("three workers");
    let (route, joiner, _) = within_for(
        Duration::from_secs(60),
        "the plan with a crash",
        plan(space, joiner, s, g, BatchParams::default()),
    )
    .await;
    assert_eq!(route.expect("a route despite the crash"), local);
    let stats = joiner.shutdown().await;
    assert_eq!(stats.replacements, 1, "{stats:?}");
    assert!(stats.resent >= 1, "worker 1's share sent again: {stats:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_for_another_terrain_refuses() {
    let (space, s, g) = cliff(1);
    let (other, _, _) = cliff(2);
    let (_central, connector) = central().await;
    let planner = Module::builder("cgspace-planner")
        .connect(&connector)
        .await
        .expect("the planner connects");
    let workers = InProcessWorkers::new(connector.clone(), &other, None);
    let joiner = DistributedJoiner::start(planner, 1, workers, JoinerOptions::default())
        .await
        .expect("one worker");
    let (route, joiner, _) = within_for(
        Duration::from_secs(60),
        "a refused plan",
        plan(space, joiner, s, g, BatchParams::default()),
    )
    .await;
    let e = route.expect_err("refused").to_string();
    assert!(e.contains("fingerprint") && e.contains("worker 0"), "{e}");
    assert_eq!(joiner.shutdown().await.replacements, 0);
}

#[test]
fn a_worker_checks_what_it_is_asked() {
    let (space, s, _) = cliff(1);
    let print = tca_cg_space::fingerprint(&space);
    let grid = *space.grid();
    let p = Partition::new(&grid, 3).unwrap();
    let mut worker = Worker::new(0, space, Some(4));
    let batch = |queries: Vec<JoinQuery>, workers: u32| JoinBatch {
        fingerprint: print,
        workers,
        marked: vec![],
        queries,
    };
    // Its own query is answered.
    let near = CgCell::new(s.ix + 2, s.iy, s.it);
    assert_eq!(p.owner(&JoinQuery::new(s, near, 3)), 0);
    let r = worker
        .answer(&batch(vec![JoinQuery::new(s, near, 3)], 3))
        .expect("answered");
    assert_eq!(r.routes[0].as_ref().map(Vec::len), Some(3));
    assert!(r.counters.regions_held <= 4);
    // Another strip's, a cell off the map, a huge margin, a bad worker count: refused.
    let far = CgCell::new(grid.nx - 2, s.iy, 0);
    let far2 = CgCell::new(grid.nx - 1, s.iy, 0);
    let refusals = [
        batch(vec![JoinQuery::new(far, far2, 3)], 3),
        batch(vec![JoinQuery::new(s, CgCell::new(-1, 0, 0), 3)], 3),
        batch(vec![JoinQuery::new(s, near, 1 << 30)], 3),
        batch(vec![JoinQuery::new(s, near, 3)], 0),
        batch(vec![JoinQuery::new(s, near, 3)], 1000),
    ];
    for b in &refusals {
        let e = worker.answer(b).expect_err("refused");
        assert!(
            matches!(e, WorkerError::Query { .. } | WorkerError::Workers { .. }),
            "{e}"
        );
    }
    let mut wrong = batch(vec![], 3);
    wrong.fingerprint ^= 1;
    assert!(matches!(
        worker.answer(&wrong),
        Err(WorkerError::Fingerprint { .. })
    ));
    // A marked cell is avoided, and forgotten when a new planning's marks do not hold it.
    let mut marked = batch(vec![JoinQuery::new(s, near, 0)], 3);
    marked.marked = vec![CgCell::new(s.ix + 1, s.iy, s.it)];
    let r = worker.answer(&marked).unwrap();
    assert!(r.routes[0].as_ref().is_none_or(|c| c.len() > 3));
    let r = worker
        .answer(&batch(vec![JoinQuery::new(s, near, 0)], 3))
        .unwrap();
    assert_eq!(r.routes[0].as_ref().map(Vec::len), Some(3));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_foot_cell_forbidden_after_the_start_is_noticed() {
    let (mut space, s, g) = cliff(1);
    let (_central, connector) = central().await;
    let planner = Module::builder("cgspace-planner")
        .connect(&connector)
        .await
        .expect("the planner connects");
    let workers = InProcessWorkers::new(connector.clone(), &space, None);
    let mut joiner = DistributedJoiner::start(planner, 2, workers, JoinerOptions::default())
        .await
        .expect("two workers");
    let near = CgCell::new(s.ix + 3, s.iy, s.it);
    let q = [JoinQuery::new(s, near, 3)];
    let answers = tokio::task::block_in_place(|| joiner.join(&mut space, &q)).expect("joined");
    assert_eq!(answers[0].as_ref().map(Vec::len), Some(4));
    // The planner's foot map changes: the workers' spaces are no longer its own.
    let (fx, fy) = (g.ix, g.iy);
    assert!(space.foot().valid(fx, fy));
    space.forbid_foot(fx, fy);
    let e = tokio::task::block_in_place(|| joiner.join(&mut space, &q)).expect_err("refused");
    assert!(e.to_string().contains("fingerprint"), "{e}");
    joiner.shutdown().await;
}
