//! The roadmap's local planner made pluggable, so that its A* joins can run elsewhere: on
//! worker processes that each own one part of CG-space, as PolyBot's modules did (Eldershaw
//! and Yim, §4.2).
//!
//! - [`JoinQuery`]: one A* search between two cells inside their block.
//! - [`Joiner`]: runs a batch of them; [`LocalJoiner`] in the planner's own [`CgSpace`], a
//!   bus client on workers (the `tca-cg-space-bus` crate).
//! - [`roadmap_batched`] and [`plan_route_batched`]: the tree-building roadmap drawing its
//!   points in batches and handing every join a batch needs to the joiner at once; the
//!   answers are applied in a fixed order, so for one seed the route does not depend on who
//!   ran the searches or in what order they finished.
//! - [`Partition`]: which of N workers owns a query: the grid cut into N strips of whole
//!   regions along x, a query going to the strip holding its block's centre. A worker then
//!   only ever touches its strip and a block's half-width either side ([`Partition::reach`]).
//! - [`fingerprint`]: a digest of a space's robot tables, grid and foot map, so that a worker
//!   set up for another robot or terrain refuses queries instead of answering them wrongly.

use std::collections::{HashMap, VecDeque};
use std::ops::Range;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::astar::{Block, astar};
use crate::error::CgError;
use crate::grid::{CgCell, CgGrid};
use crate::route::{Route, RouteParams, flood_fallback, route_ends};
use crate::space::{CgSpace, REGION_CELLS};

/// One A* search of the roadmap: from `from` to `to` over valid cells inside the block about
/// them (their bounding box widened by `margin` cells, every heading; see [`Block::about`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct JoinQuery {
    /// Where the search starts.
    pub from: CgCell,
    /// Where it must end.
    pub to: CgCell,
    /// Cells the block reaches beyond the two cells' bounding box.
    pub margin: i32,
}

impl JoinQuery {
    /// A query between two cells.
    pub const fn new(from: CgCell, to: CgCell, margin: i32) -> Self {
        JoinQuery { from, to, margin }
    }

    /// The block the search is confined to.
    pub fn block(&self) -> Block {
        Block::about(self.from, self.to, self.margin)
    }

    /// Runs the search in `space`: the route, both ends included, or `None`.
    pub fn run(&self, space: &mut CgSpace) -> Option<Vec<CgCell>> {
        astar(space, self.from, self.to, self.block()).route
    }
}

/// The answers to a batch of queries, in the batch's order: each a route or `None`.
pub type Joins = Vec<Option<Vec<CgCell>>>;

/// A joiner could not answer a batch (its workers cannot be reached or replaced, or they
/// refused the batch).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("the roadmap's joins could not be run: {reason}")]
pub struct JoinError {
    /// What went wrong.
    pub reason: String,
}

impl JoinError {
    /// An error with the given reason.
    pub fn new(reason: impl Into<String>) -> Self {
        JoinError {
            reason: reason.into(),
        }
    }
}

/// The roadmap's local planner: runs a batch of A* searches and answers each, in order.
///
/// The planner's own space is given with every batch: a local joiner searches in it (sharing
/// the cells the planner has evaluated), a remote one reads from it what its workers must
/// also know (the cells marked invalid, the [`fingerprint`]). The answers must be those of
/// [`JoinQuery::run`] in that space; only where and when they are computed may differ.
pub trait Joiner {
    /// Answers `queries`, one entry per query in the same order.
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError>;
}

impl<J: Joiner + ?Sized> Joiner for &mut J {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        (**self).join(space, queries)
    }
}

impl<J: Joiner + ?Sized> Joiner for Box<J> {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        (**self).join(space, queries)
    }
}

/// Runs every query in the planner's own space, one after another.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LocalJoiner;

impl Joiner for LocalJoiner {
    fn join(&mut self, space: &mut CgSpace, queries: &[JoinQuery]) -> Result<Joins, JoinError> {
        Ok(queries.iter().map(|q| q.run(space)).collect())
    }
}

/// How the batched roadmap draws its points.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct BatchParams {
    /// Random draws (valid or not) per batch; every join the batch's valid points need is
    /// handed to the joiner in one call.
    pub draws_per_batch: usize,
}

impl Default for BatchParams {
    fn default() -> Self {
        BatchParams {
            draws_per_batch: 48,
        }
    }
}

/// Why a batched route could not be planned.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum BatchedRouteError {
    /// The planning itself failed (bad ends, no route, budget).
    #[error(transparent)]
    Plan(#[from] CgError),
    /// The joiner failed.
    #[error(transparent)]
    Join(#[from] JoinError),
}

/// [`plan_route`](crate::route::plan_route) with the roadmap of [`roadmap_batched`]: the ends
/// checked and the short flood first, then the batched roadmap, then (if it runs out of
/// draws) the whole-map flood, in the planner's own space.
pub fn plan_route_batched<J: Joiner + ?Sized>(
    space: &mut CgSpace,
    joiner: &mut J,
    start: CgCell,
    goal: CgCell,
    params: &RouteParams,
    batch: &BatchParams,
) -> Result<Route, BatchedRouteError> {
    if let Some(route) = route_ends(space, start, goal, params)? {
        return Ok(route);
    }
    if let Some(route) = roadmap_batched(space, joiner, start, goal, params, batch)? {
        return Ok(route);
    }
    Ok(flood_fallback(space, start, goal, params)?)
}

/// The roadmap points and trees: trees are lists of points, concatenated when joined.
struct Forest {
    points: Vec<CgCell>,
    tree_of: Vec<usize>,
    trees: Vec<Vec<usize>>,
    /// Joined pairs (p, q) with the route from point p to point q.
    edges: HashMap<(usize, usize), Vec<CgCell>>,
}

impl Forest {
    fn new(start: CgCell, goal: CgCell) -> Self {
        Forest {
            points: vec![start, goal],
            tree_of: vec![0, 1],
            trees: vec![vec![0], vec![1]],
            edges: HashMap::new(),
        }
    }

    fn add(&mut self, c: CgCell) -> usize {
        let p = self.points.len();
        self.points.push(c);
        self.tree_of.push(self.trees.len());
        self.trees.push(vec![p]);
        p
    }

    /// Up to `tries` points of `members` within `connect_steps` of point `p`, nearest first
    /// (ties by point number).
    fn nearest(
        &self,
        grid: &CgGrid,
        p: usize,
        members: &[usize],
        params: &RouteParams,
    ) -> Vec<usize> {
        let mut near: Vec<(i32, usize)> = members
            .iter()
            .map(|&q| (grid.steps_between(self.points[p], self.points[q]), q))
            .filter(|&(d, _)| d <= params.connect_steps)
            .collect();
        near.sort_unstable();
        near.into_iter()
            .take(params.tries_per_tree)
            .map(|(_, q)| q)
            .collect()
    }

    /// Joins point `p` to point `q` by `route` (from p to q): p's tree moves into q's.
    fn join(&mut self, p: usize, q: usize, route: Vec<CgCell>) {
        self.edges.insert((p, q), route);
        let (keep, gone) = (self.tree_of[q], self.tree_of[p]);
        let moved = std::mem::take(&mut self.trees[gone]);
        for &m in &moved {
            self.tree_of[m] = keep;
        }
        self.trees[keep].extend(moved);
    }

    /// The route from the start (point 0) to the goal (point 1) along the edges, if joined.
    fn route(&self) -> Option<Vec<CgCell>> {
        let mut adjacency: HashMap<usize, Vec<usize>> = HashMap::new();
        let mut pairs: Vec<&(usize, usize)> = self.edges.keys().collect();
        pairs.sort_unstable();
        for &&(a, b) in &pairs {
            adjacency.entry(a).or_default().push(b);
            adjacency.entry(b).or_default().push(a);
        }
        let mut prev: HashMap<usize, usize> = HashMap::from([(0, 0)]);
        let mut queue = VecDeque::from([0usize]);
        while let Some(a) = queue.pop_front() {
            if a == 1 {
                break;
            }
            for &b in adjacency.get(&a).into_iter().flatten() {
                if let std::collections::hash_map::Entry::Vacant(e) = prev.entry(b) {
                    e.insert(a);
                    queue.push_back(b);
                }
            }
        }
        let mut chain = vec![1usize];
        while *chain.last()? != 0 {
            let p = *prev.get(chain.last()?)?;
            chain.push(p);
        }
        chain.reverse();
        let mut cells = vec![self.points[0]];
        for w in chain.windows(2) {
            let leg: Vec<CgCell> = match self.edges.get(&(w[0], w[1])) {
                Some(r) => r.clone(),
                None => self
                    .edges
                    .get(&(w[1], w[0]))?
                    .iter()
                    .rev()
                    .copied()
                    .collect(),
            };
            cells.extend(leg.into_iter().skip(1));
        }
        Some(cells)
    }
}

/// One query of a round, for the point it joins and the group of candidates it belongs to.
struct Ask {
    p: usize,
    q: usize,
}

/// Joins each of the `fresh` points (in order) to the trees it is not part of: all the
/// searches asked at once, the answers applied in the order of points, then of trees, then of
/// candidates (nearest first). Against each tree that existed before the round, a point tries
/// its nearest `tries_per_tree` members; against the fresh points before it, each one alone.
/// A candidate group whose tree the point has joined meanwhile is passed over.
fn round<J: Joiner + ?Sized>(
    forest: &mut Forest,
    space: &mut CgSpace,
    joiner: &mut J,
    fresh: &[usize],
    params: &RouteParams,
    searches: &mut usize,
) -> Result<(), JoinError> {
    let grid = *space.grid();
    let fresh_trees: Vec<usize> = fresh.iter().map(|&p| forest.tree_of[p]).collect();
    let old_trees: Vec<usize> = (0..forest.trees.len())
        .filter(|&t| !forest.trees[t].is_empty() && !fresh_trees.contains(&t))
        .collect();
    let mut asks: Vec<Ask> = Vec::new();
    // Per fresh point, its candidate groups: ranges into `asks`.
    let mut groups: Vec<Vec<Range<usize>>> = Vec::with_capacity(fresh.len());
    for (i, &p) in fresh.iter().enumerate() {
        let mut mine = Vec::new();
        let targets = old_trees
            .iter()
            .map(|&t| forest.trees[t].as_slice())
            .chain(fresh[..i].iter().map(std::slice::from_ref));
        for members in targets {
            let near = forest.nearest(&grid, p, members, params);
            if near.is_empty() {
                continue;
            }
            let first = asks.len();
            asks.extend(near.into_iter().map(|q| Ask { p, q }));
            mine.push(first..asks.len());
        }
        groups.push(mine);
    }
    if asks.is_empty() {
        return Ok(());
    }
    let queries: Vec<JoinQuery> = asks
        .iter()
        .map(|a| JoinQuery::new(forest.points[a.p], forest.points[a.q], params.block_margin))
        .collect();
    *searches += queries.len();
    let mut answers = joiner.join(space, &queries)?;
    if answers.len() != queries.len() {
        return Err(JoinError::new(format!(
            "{} answers to {} queries",
            answers.len(),
            queries.len()
        )));
    }
    for (i, &p) in fresh.iter().enumerate() {
        for group in &groups[i] {
            let target = forest.tree_of[asks[group.start].q];
            if forest.tree_of[p] == target {
                continue;
            }
            for k in group.clone() {
                if let Some(route) = answers[k].take() {
                    forest.join(p, asks[k].q, route);
                    break;
                }
            }
        }
    }
    Ok(())
}

/// The tree-building roadmap of [`roadmap`](crate::route::roadmap) with its joins run by
/// `joiner`, in batches: the same random draws (same seed, same sequence), taken
/// `draws_per_batch` at a time; the valid ones become points, and every search joining them
/// to the trees (and to each other) goes to the joiner in one call. A point tries, as in the
/// sequential roadmap, the nearest few members of each tree within `connect_steps`; the
/// answers are applied in a fixed order, so the outcome depends only on the seed and the
/// space, never on the joiner. Speculative: all of a tree's candidates are searched, where
/// the sequential roadmap stops at the first that joins. The route is made of the joins'
/// own routes (no search is run again). `Ok(None)` if start and goal were not joined within
/// `max_draws` draws.
pub fn roadmap_batched<J: Joiner + ?Sized>(
    space: &mut CgSpace,
    joiner: &mut J,
    start: CgCell,
    goal: CgCell,
    params: &RouteParams,
    batch: &BatchParams,
) -> Result<Option<Route>, JoinError> {
    let grid = *space.grid();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut forest = Forest::new(start, goal);
    let mut searches = 0;
    round(&mut forest, space, joiner, &[0], params, &mut searches)?;
    let per_batch = batch.draws_per_batch.max(1);
    let mut draws = 0;
    while forest.tree_of[0] != forest.tree_of[1] {
        if draws >= params.max_draws {
            return Ok(None);
        }
        let mut fresh = Vec::new();
        for _ in 0..per_batch.min(params.max_draws - draws) {
            draws += 1;
            let c = CgCell::new(
                rng.random_range(0..grid.nx),
                rng.random_range(0..grid.ny),
                rng.random_range(0..grid.theta_bins),
            );
            if space.is_valid(c) {
                fresh.push(forest.add(c));
            }
        }
        round(&mut forest, space, joiner, &fresh, params, &mut searches)?;
    }
    let Some(cells) = forest.route() else {
        return Err(JoinError::new(
            "the start's and the goal's trees are one but no chain of joins links them",
        ));
    };
    Ok(Some(Route {
        cells,
        draws,
        searches,
        points: forest.points.len(),
    }))
}

/// Which of N workers owns which queries: the grid's columns of regions
/// ([`REGION_CELLS`] cells wide) cut into N contiguous strips along x, as even as whole
/// regions allow (worker k has region columns `k·R/N .. (k+1)·R/N` of `R`); a query belongs to
/// the strip holding its block's centre (the middle of its two cells' columns).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Partition {
    /// Columns of the grid.
    pub nx: i32,
    /// Rows of the grid.
    pub ny: i32,
    /// Workers.
    pub workers: usize,
}

impl Partition {
    /// A partition of `grid` among `workers` workers: at least one, at most one per column of
    /// regions.
    pub fn new(grid: &CgGrid, workers: usize) -> Result<Self, CgError> {
        let columns = grid.nx.div_euclid(REGION_CELLS) + i32::from(grid.nx % REGION_CELLS != 0);
        if workers == 0 || workers > columns as usize {
            return Err(CgError::BadParameter {
                what: "the number of CG-space workers",
                value: workers as f64,
                hint: "give at least 1 and at most one worker per column of regions (16 cells) of the map",
            });
        }
        Ok(Partition {
            nx: grid.nx,
            ny: grid.ny,
            workers,
        })
    }

    /// Columns of regions across the grid.
    pub fn region_columns(&self) -> i32 {
        self.nx.div_euclid(REGION_CELLS) + i32::from(self.nx % REGION_CELLS != 0)
    }

    /// Rows of regions up the grid.
    pub fn region_rows(&self) -> i32 {
        self.ny.div_euclid(REGION_CELLS) + i32::from(self.ny % REGION_CELLS != 0)
    }

    fn first_region_column(&self, k: usize) -> i32 {
        (k as i64 * i64::from(self.region_columns()) / self.workers as i64) as i32
    }

    /// Worker `k`'s columns of regions.
    pub fn strip_regions(&self, k: usize) -> Range<i32> {
        let k = k.min(self.workers - 1);
        self.first_region_column(k)..self.first_region_column(k + 1)
    }

    /// Worker `k`'s grid columns.
    pub fn strip(&self, k: usize) -> Range<i32> {
        let r = self.strip_regions(k);
        (r.start * REGION_CELLS)..(r.end * REGION_CELLS).min(self.nx)
    }

    /// The worker owning grid column `ix` (clamped to the grid).
    pub fn owner_of_column(&self, ix: i32) -> usize {
        let r = ix.clamp(0, self.nx - 1).div_euclid(REGION_CELLS);
        (0..self.workers)
            .find(|&k| self.strip_regions(k).contains(&r))
            .unwrap_or(self.workers - 1)
    }

    /// The worker owning a query: the strip holding its block's centre.
    pub fn owner(&self, q: &JoinQuery) -> usize {
        self.owner_of_column((q.from.ix + q.to.ix).div_euclid(2))
    }

    /// The grid columns worker `k`'s searches can touch when the roadmap joins points at
    /// most `params.connect_steps` apart with blocks of `params.block_margin`: its strip and
    /// a block's half-width either side, clipped to the grid.
    pub fn reach(&self, k: usize, params: &RouteParams) -> Range<i32> {
        let half = params.connect_steps.max(0) / 2 + params.block_margin.max(0) + 1;
        let s = self.strip(k);
        (s.start - half).max(0)..(s.end + half).min(self.nx)
    }

    /// How many regions worker `k`'s searches can touch ([`Partition::reach`] over every
    /// row): a region cap of this many never drops a region it will need again.
    pub fn regions_in_reach(&self, k: usize, params: &RouteParams) -> usize {
        let r = self.reach(k, params);
        if r.is_empty() {
            return 0;
        }
        let columns = (r.end - 1).div_euclid(REGION_CELLS) - r.start.div_euclid(REGION_CELLS) + 1;
        columns as usize * self.region_rows() as usize
    }
}

/// A 64-bit digest of what a space's answers depend on: the robot's tables (legs' range
/// cells, under-carriage, foot radii, parameters), the grid and the foot map. Two spaces
/// with the same fingerprint answer every query alike; a worker compares the planner's
/// fingerprint with its own before it answers. (A consistency check, not a cryptographic
/// hash: each word is mixed as in SplitMix64 and folded in FNV-1a fashion.)
pub fn fingerprint(space: &CgSpace) -> u64 {
    let mut h = Digest::new();
    let robot = space.robot();
    h.bytes(robot.name.as_bytes());
    h.u64(robot.leg_count() as u64);
    for r in &robot.foot_radius {
        h.f64(*r);
    }
    h.f64(robot.com.x);
    h.f64(robot.com.y);
    h.f64(robot.cell_m);
    h.f64(robot.params.traction_slope_rad);
    h.f64(robot.params.clearance_m);
    for t in &robot.headings {
        h.f64(t.theta);
        for leg in &t.legs {
            h.u64(leg.len() as u64);
            for c in leg {
                h.i64(i64::from(c.di));
                h.i64(i64::from(c.dj));
                h.f64(c.z_lo);
                h.f64(c.z_hi);
                h.u64(u64::from(c.quadrant));
            }
        }
        h.u64(t.under.len() as u64);
        for u in &t.under {
            h.i64(i64::from(u.di));
            h.i64(i64::from(u.dj));
            h.f64(u.depth);
        }
    }
    let g = space.grid();
    h.f64(g.origin.x);
    h.f64(g.origin.y);
    h.f64(g.cell_m);
    h.i64(i64::from(g.nx));
    h.i64(i64::from(g.ny));
    h.u64(u64::from(g.theta_bins));
    let foot = space.foot();
    for iy in 0..g.ny {
        for ix in 0..g.nx {
            h.u64(u64::from(foot.valid(ix, iy)));
            h.f64(foot.height(ix, iy).unwrap_or(f64::NAN));
        }
    }
    h.finish()
}

/// The digest's state: words mixed (SplitMix64's finaliser) and folded in (FNV-1a's step).
struct Digest(u64);

impl Digest {
    fn new() -> Self {
        Digest(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        for chunk in b.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.u64(u64::from_le_bytes(word));
        }
    }

    fn u64(&mut self, v: u64) {
        let mut z = v.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        self.0 = (self.0 ^ z).wrapping_mul(0x0000_0100_0000_01b3);
    }

    fn i64(&mut self, v: i64) {
        self.u64(v as u64);
    }

    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    fn grid(nx: i32) -> CgGrid {
        CgGrid::covering(
            Point2::new(0.0, 0.0),
            Point2::new(f64::from(nx) * 0.5, 10.0),
            0.5,
            8,
        )
        .unwrap()
    }

    #[test]
    fn strips_cover_the_grid_in_whole_regions() {
        let g = grid(200); // 13 region columns
        let p = Partition::new(&g, 5).unwrap();
        assert_eq!(p.region_columns(), 13);
        let mut next = 0;
        for k in 0..5 {
            let s = p.strip(k);
            assert_eq!(s.start, next);
            assert_eq!(s.start % REGION_CELLS, 0);
            assert!(!s.is_empty());
            next = s.end;
            for ix in s.clone() {
                assert_eq!(p.owner_of_column(ix), k);
            }
        }
        assert_eq!(next, 200);
        assert!(Partition::new(&g, 0).is_err());
        assert!(Partition::new(&g, 14).is_err());
        assert!(Partition::new(&g, 13).is_ok());
        let one = Partition::new(&g, 1).unwrap();
        assert_eq!(one.strip(0), 0..200);
        assert_eq!(one.owner_of_column(-5), 0);
        assert_eq!(one.owner_of_column(500), 0);
    }

    #[test]
    fn a_query_goes_to_its_blocks_centre_and_stays_in_reach() {
        let g = grid(200);
        let p = Partition::new(&g, 5).unwrap();
        let params = RouteParams::default();
        for a in (0..200).step_by(7) {
            for d in -params.connect_steps..=params.connect_steps {
                let b = (a + d).clamp(0, 199);
                let q = JoinQuery::new(CgCell::new(a, 3, 0), CgCell::new(b, 5, 1), 3);
                let k = p.owner(&q);
                let block = q.block();
                let reach = p.reach(k, &params);
                assert!(reach.start <= block.x0.max(0) && block.x1.min(199) < reach.end);
            }
        }
        assert!(p.regions_in_reach(0, &params) >= 3);
    }
}
