//! The batched roadmap over pluggable joiners: the same route whoever runs the searches, in
//! whatever order; a partition whose workers stay in their strips.

use crate::common;

use std::collections::HashSet;

use nalgebra::Point2;
use tca_cg_space::{
    BatchParams, BatchedRouteError, CgCell, CgError, CgParams, CgSpace, JoinError, JoinQuery,
    Joiner, Joins, LocalJoiner, Partition, RouteParams, fingerprint, plan_route,
    plan_route_batched,
};
use tca_legged_model::RobotModel;

fn ambler_space(terrain: &tca_robot::HeightField) -> CgSpace {
    let model = RobotModel::builtin("ambler").expect("the Ambler");
    CgSpace::for_model(&model, terrain, CgParams::default()).expect("a CG-space")
}

/// Stands for a set of workers: each query runs in the space of the strip that owns it
/// (each space capped to what its strip reaches), the batch's queries taken in reverse
/// order; records the columns each worker touched.
struct StripJoiner {
    partition: Partition,
    spaces: Vec<CgSpace>,
    touched: Vec<HashSet<i32>>,
    batches: usize,
}

impl Joiner for StripJoiner {
    fn join(&mut self, _space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        self.batches += 1;
        let mut out = vec![None; queries.len()];
        for (i, q) in queries.iter().enumerate().rev() {
            let k = self.partition.owner(q);
            let route = q.run(&mut self.spaces[k]);
            if let Some(r) = &route {
                self.touched[k].extend(r.iter().map(|c| c.ix));
            }
            out[i] = route;
        }
        Ok(out)
    }
}

fn cell(space: &CgSpace, x: f64, y: f64) -> CgCell {
    space
        .grid()
        .cell_of(Point2::new(x, y), 0.0)
        .expect("on the map")
}

#[test]
fn the_batched_route_is_the_same_whoever_joins() {
    let t = common::cliff(2.5);
    let mut space = ambler_space(&t);
    let (s, g) = (cell(&space, 4.0, 0.0), cell(&space, 24.0, 0.0));
    let params = RouteParams::default();
    let batch = BatchParams::default();
    let local = plan_route_batched(&mut space, &mut LocalJoiner, s, g, &params, &batch)
        .expect("a route by the ramp");
    assert!(local.draws > 0, "the roadmap ran");
    let grid = *space.grid();
    assert_eq!(local.cells.first(), Some(&s));
    assert_eq!(local.cells.last(), Some(&g));
    assert!(
        local
            .cells
            .windows(2)
            .all(|w| grid.steps_between(w[0], w[1]) == 1)
    );
    assert!(local.cells.iter().all(|&c| space.is_valid(c)));
    for c in &local.cells {
        let at = grid.centre(c.ix, c.iy);
        if (at.x - 14.0).abs() < 1.0 {
            assert!(at.y > 2.0, "the route crosses the cliff at {at:?}");
        }
    }

    // Three "workers", each with its own capped space.
    let partition = Partition::new(&grid, 3).expect("three strips");
    let fresh = ambler_space(&t);
    let spaces = (0..3)
        .map(|k| {
            fresh
                .clone()
                .with_region_cap(Some(partition.regions_in_reach(k, &params)))
        })
        .collect();
    let mut strips = StripJoiner {
        partition,
        spaces,
        touched: vec![HashSet::new(); 3],
        batches: 0,
    };
    let mut planner = ambler_space(&t);
    let remote = plan_route_batched(&mut planner, &mut strips, s, g, &params, &batch)
        .expect("a route by the ramp");
    assert_eq!(remote, local, "the route does not depend on the joiner");
    assert!(strips.batches > 1);
    for k in 0..3 {
        let reach = partition.reach(k, &params);
        assert!(
            strips.touched[k].iter().all(|ix| reach.contains(ix)),
            "worker {k} left its reach {reach:?}"
        );
        assert!(strips.spaces[k].regions_held() <= partition.regions_in_reach(k, &params));
        assert_eq!(fingerprint(&strips.spaces[k]), fingerprint(&planner));
    }

    // The sequential roadmap is unchanged by all this and finds a route of its own.
    let mut again = ambler_space(&t);
    let sequential = plan_route(&mut again, s, g, &params).expect("a route");
    assert_eq!(sequential.cells.first(), Some(&s));
    assert_eq!(sequential.cells.last(), Some(&g));
}

#[test]
fn a_different_terrain_has_a_different_fingerprint() {
    let a = ambler_space(&common::cliff(2.5));
    let b = ambler_space(&common::cliff(2.4));
    assert_ne!(fingerprint(&a), fingerprint(&b));
    assert_eq!(
        fingerprint(&a),
        fingerprint(&a.clone().with_region_cap(Some(3)))
    );
}

/// A joiner that runs every query locally and counts what it was given.
#[derive(Default)]
struct Counting {
    queries: usize,
    most_marked: usize,
}

impl Joiner for Counting {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        self.queries += queries.len();
        self.most_marked = self.most_marked.max(space.marked().len());
        LocalJoiner.join(space, queries)
    }
}

fn cliff_terrain() -> tca_robot::HeightField {
    tca_legged_courses::Course::builtin("cliff", 1)
        .expect("the cliff course")
        .terrain
}

#[test]
fn footfall_plans_take_their_routes_from_the_joiner() {
    let t = cliff_terrain();
    let mut space = ambler_space(&t);
    let grid = *space.grid();
    let mut params = tca_cg_space::PlanParams::default();
    // A short flood, so that the roadmap (and so the joiner) finds the route.
    params.route.flood_budget = 50;
    let (from, to) = (Point2::new(4.0, 0.0), Point2::new(24.0, 0.0));
    let mut routes = tca_cg_space::JoinedRoutes {
        joiner: Counting::default(),
        batch: BatchParams::default(),
    };
    let p = tca_cg_space::plan_with(
        &mut space,
        (from, 0.0),
        (to, 0.0),
        None,
        &params,
        None,
        &mut routes,
    )
    .expect("a plan by the ramp");
    assert!(routes.joiner.queries > 0, "the joiner was never asked");
    // The first route is the batched roadmap's, as planned in a fresh space.
    let mut fresh = ambler_space(&t);
    let (s, g) = (
        grid.cell_of(from, 0.0).expect("start"),
        grid.cell_of(to, 0.0).expect("goal"),
    );
    let alone = plan_route_batched(
        &mut fresh,
        &mut LocalJoiner,
        s,
        g,
        &params.route,
        &BatchParams::default(),
    )
    .expect("a route");
    assert_eq!(p.first_route.cells, alone.cells);
    // Where the plan crosses the cliff's line it is on the ramp, and it ends at the goal.
    for c in &p.feet.route {
        let at = grid.centre(c.ix, c.iy);
        if (at.x - 14.0).abs() < 1.0 {
            assert!(at.y > 2.0, "the route crosses the cliff at {at:?}");
        }
    }
    assert_eq!(p.feet.route.last(), Some(&g));
    assert!(!p.feet.steps.is_empty());
    // Every replanned route saw the cells marked before it.
    if !p.marked.is_empty() {
        assert!(p.routes > 1);
        assert!(routes.joiner.most_marked > 0);
    }
}

/// A joiner whose workers are gone.
struct Gone;

impl Joiner for Gone {
    fn join(&mut self, _: &mut CgSpace, _: &[JoinQuery]) -> Result<Joins, JoinError> {
        Err(JoinError::new(
            "worker 2 died and could not be started again",
        ))
    }
}

#[test]
fn a_joiner_that_fails_fails_the_plan_with_its_reason() {
    let t = cliff_terrain();
    let mut space = ambler_space(&t);
    let mut params = tca_cg_space::PlanParams::default();
    params.route.flood_budget = 50;
    let e = tca_cg_space::plan_with(
        &mut space,
        (Point2::new(4.0, 0.0), 0.0),
        (Point2::new(24.0, 0.0), 0.0),
        None,
        &params,
        None,
        &mut tca_cg_space::JoinedRoutes {
            joiner: Gone,
            batch: BatchParams::default(),
        },
    )
    .expect_err("no route without the joins");
    assert!(
        matches!(&e, tca_cg_space::CgError::Joins { reason } if reason.contains("worker 2 died")),
        "{e}"
    );
}

/// A joiner that answers every query locally and counts its batches.
struct Batches(usize);

impl Joiner for Batches {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        self.0 += 1;
        LocalJoiner.join(space, queries)
    }
}

#[test]
fn an_enclosed_goal_is_reported_by_the_flood_before_any_join() {
    // The goal in the walled yard, and a flood budget that takes in the whole yard.
    let t = common::walled_yard();
    let mut space = ambler_space(&t);
    let (s, g) = (cell(&space, 5.0, 0.0), cell(&space, 20.0, 0.0));
    let params = RouteParams {
        flood_budget: 20_000,
        ..RouteParams::default()
    };
    let mut joiner = Batches(0);
    let r = plan_route_batched(
        &mut space,
        &mut joiner,
        s,
        g,
        &params,
        &BatchParams::default(),
    );
    assert!(
        matches!(
            r,
            Err(BatchedRouteError::Plan(CgError::Unreachable {
                enclosed: "goal",
                ..
            }))
        ),
        "{r:?}"
    );
    assert_eq!(joiner.0, 0, "no worker was asked");
}

#[test]
fn a_short_route_is_the_floods_whoever_joins() {
    // Open ground, the goal a few metres off: the flood meets within its budget.
    let t = common::terrain(0.0, 20.0, -5.0, 5.0, 0.1, |_, _| 0.0);
    let mut space = ambler_space(&t);
    let (s, g) = (cell(&space, 4.0, 0.0), cell(&space, 6.0, 0.0));
    let params = RouteParams::default();
    let alone = plan_route(&mut ambler_space(&t), s, g, &params).expect("a route");
    assert_eq!(alone.draws, 0, "the flood found it");
    let mut joiner = Batches(0);
    let batched = plan_route_batched(
        &mut space,
        &mut joiner,
        s,
        g,
        &params,
        &BatchParams::default(),
    )
    .expect("a route");
    assert_eq!(batched, alone);
    assert_eq!(joiner.0, 0, "no worker was asked");
}
