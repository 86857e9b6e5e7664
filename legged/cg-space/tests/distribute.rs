//! The batched roadmap over pluggable joiners: the same route whoever runs the searches, in
//! whatever order; a partition whose workers stay in their strips.

mod common;

use std::collections::HashSet;

use nalgebra::Point2;
use tca_cg_space::{
    BatchParams, CgCell, CgParams, CgSpace, JoinError, JoinQuery, Joiner, Joins, LocalJoiner,
    Partition, RouteParams, fingerprint, plan_route, plan_route_batched,
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
