//! Routes through CG-space: the tree-building probabilistic roadmap over A* in blocks, and a
//! bidirectional flood that proves a route cannot exist.

use std::collections::{HashMap, VecDeque};

use rustc_hash::FxHashMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::astar::{Block, astar, route_cost};
use crate::error::CgError;
use crate::grid::CgCell;
use crate::space::CgSpace;

/// How routes are planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RouteParams {
    /// Cells a block reaches beyond the bounding box of the two cells A* joins.
    pub block_margin: i32,
    /// Largest 6-neighbour distance between two roadmap points the planner tries to join.
    pub connect_steps: i32,
    /// Nearest points of one tree tried for each new point.
    pub tries_per_tree: usize,
    /// Most random points drawn (valid or not) before the roadmap gives up.
    pub max_draws: usize,
    /// Seed of the roadmap's draws.
    pub seed: u64,
    /// Cells the flood explores from each end before the roadmap starts; a flood that
    /// exhausts one end's region within this proves there is no route.
    pub flood_budget: usize,
    /// The longest stretch of a roadmap's route, in cells, that [`shortcut`] tries to
    /// replace by one A* search; 0 keeps the roadmap's route as it is. The batched
    /// roadmap ([`roadmap_batched`](crate::distribute::roadmap_batched)) does not cut.
    #[serde(default = "default_shortcut_cells")]
    pub shortcut_cells: usize,
}

fn default_shortcut_cells() -> usize {
    64
}

impl Default for RouteParams {
    fn default() -> Self {
        RouteParams {
            block_margin: 3,
            connect_steps: 24,
            tries_per_tree: 3,
            max_draws: 20_000,
            seed: 1,
            flood_budget: 2_000,
            shortcut_cells: default_shortcut_cells(),
        }
    }
}

/// A route and how it was found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Route {
    /// The cells from start to goal, each a 6-neighbour of the one before.
    pub cells: Vec<CgCell>,
    /// Roadmap points drawn (0 when the flood found the route).
    pub draws: usize,
    /// A* searches run.
    pub searches: usize,
    /// Roadmap points in the trees at the end.
    pub points: usize,
}

/// What a bidirectional flood found.
#[derive(Debug, Clone, PartialEq)]
pub enum Flood {
    /// The two floods met: a route.
    Met(Vec<CgCell>),
    /// One end's region was explored to its end: no route. `enclosed` is `start` or `goal`.
    Enclosed {
        /// Which end.
        enclosed: &'static str,
        /// Valid cells in its region.
        cells: usize,
    },
    /// The budget ran out first.
    Budget,
}

/// Breadth-first floods from both ends over valid cells, alternately one cell at a time,
/// up to `budget` cells each (`usize::MAX`: the whole map, so always decisive).
pub fn flood(space: &mut CgSpace, start: CgCell, goal: CgCell, budget: usize) -> Flood {
    let grid = *space.grid();
    let mut parent: [FxHashMap<CgCell, Option<CgCell>>; 2] =
        [FxHashMap::default(), FxHashMap::default()];
    let mut queue: [VecDeque<CgCell>; 2] = [VecDeque::new(), VecDeque::new()];
    let ends = [start, goal];
    for side in 0..2 {
        parent[side].insert(ends[side], None);
        queue[side].push_back(ends[side]);
    }
    let mut popped = [0usize; 2];
    loop {
        for side in 0..2 {
            let Some(c) = queue[side].pop_front() else {
                return Flood::Enclosed {
                    enclosed: if side == 0 { "start" } else { "goal" },
                    cells: parent[side].len(),
                };
            };
            popped[side] += 1;
            for n in grid.neighbours(c).collect::<Vec<_>>() {
                if parent[side].contains_key(&n) || !space.is_valid(n) {
                    continue;
                }
                parent[side].insert(n, Some(c));
                if parent[1 - side].contains_key(&n) {
                    let chain = |side: usize, from: CgCell| {
                        let mut out = vec![from];
                        let mut at = from;
                        while let Some(Some(p)) = parent[side].get(&at) {
                            out.push(*p);
                            at = *p;
                        }
                        out
                    };
                    let mut a = chain(0, n);
                    a.reverse();
                    let b = chain(1, n);
                    a.extend(b.into_iter().skip(1));
                    return Flood::Met(a);
                }
                queue[side].push_back(n);
            }
        }
        if popped[0] >= budget && popped[1] >= budget {
            return Flood::Budget;
        }
    }
}

/// Plans a route from `start` to `goal`: a flood of `flood_budget` cells from each end first
/// (which settles small or enclosed problems), then the tree-building roadmap: each valid
/// random point is joined by A* only to trees it is not already part of, the trees kept as
/// lists that are concatenated when joined, until the start's and the goal's trees are one.
/// If the roadmap draws all its points without joining them, a whole-map flood decides: a
/// route, or proof that there is none. So the answer always comes in bounded time.
pub fn plan_route(
    space: &mut CgSpace,
    start: CgCell,
    goal: CgCell,
    params: &RouteParams,
) -> Result<Route, CgError> {
    if let Some(route) = route_ends(space, start, goal, params)? {
        return Ok(route);
    }
    if let Some(mut route) = roadmap(space, start, goal, params) {
        route.cells = shortcut(space, &route.cells, params);
        return Ok(route);
    }
    flood_fallback(space, start, goal, params)
}

/// What every route planner does before its roadmap: both ends checked, the trivial route,
/// and the flood of `flood_budget` cells from each end, which finds short routes and proves
/// enclosed ends unreachable. `Ok(None)`: the roadmap is needed.
pub(crate) fn route_ends(
    space: &mut CgSpace,
    start: CgCell,
    goal: CgCell,
    params: &RouteParams,
) -> Result<Option<Route>, CgError> {
    for (what, c) in [("start", start), ("goal", goal)] {
        if !space.is_valid(c) {
            return Err(CgError::InvalidEndpoint {
                what,
                ix: c.ix,
                iy: c.iy,
                it: c.it,
                reason: space.verdict(c).describe(),
            });
        }
    }
    if start == goal {
        return Ok(Some(Route {
            cells: vec![start],
            draws: 0,
            searches: 0,
            points: 1,
        }));
    }
    match flood(space, start, goal, params.flood_budget) {
        Flood::Met(cells) => Ok(Some(Route {
            cells,
            draws: 0,
            searches: 0,
            points: 2,
        })),
        Flood::Enclosed { enclosed, cells } => Err(CgError::Unreachable {
            enclosed,
            explored: cells,
        }),
        Flood::Budget => Ok(None),
    }
}

/// What every route planner does when its roadmap ran out of draws: a whole-map flood
/// decides, a route or proof that there is none.
pub(crate) fn flood_fallback(
    space: &mut CgSpace,
    start: CgCell,
    goal: CgCell,
    params: &RouteParams,
) -> Result<Route, CgError> {
    match flood(space, start, goal, usize::MAX) {
        Flood::Met(cells) => Ok(Route {
            cells,
            draws: params.max_draws,
            searches: 0,
            points: 2,
        }),
        Flood::Enclosed { enclosed, cells } => Err(CgError::Unreachable {
            enclosed,
            explored: cells,
        }),
        Flood::Budget => Err(CgError::BudgetExhausted {
            detail: "the whole-map flood stopped early".into(),
        }),
    }
}

/// The tree-building roadmap alone; `None` if the trees of start and goal were not joined
/// within `max_draws` draws.
pub fn roadmap(
    space: &mut CgSpace,
    start: CgCell,
    goal: CgCell,
    params: &RouteParams,
) -> Option<Route> {
    let grid = *space.grid();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut points = vec![start, goal];
    // tree_of[point] is the index of its tree in `trees`; trees are lists of points.
    let mut tree_of = vec![0usize, 1];
    let mut trees: Vec<Vec<usize>> = vec![vec![0], vec![1]];
    let mut edges: Vec<(usize, usize)> = Vec::new();
    let mut searches = 0;
    let try_join = |space: &mut CgSpace,
                    points: &Vec<CgCell>,
                    tree_of: &mut Vec<usize>,
                    trees: &mut Vec<Vec<usize>>,
                    edges: &mut Vec<(usize, usize)>,
                    searches: &mut usize,
                    p: usize| {
        let ids: Vec<usize> = (0..trees.len()).filter(|&t| !trees[t].is_empty()).collect();
        for t in ids {
            if tree_of[p] == t {
                continue;
            }
            let mut near: Vec<(i32, usize)> = trees[t]
                .iter()
                .map(|&q| (grid.steps_between(points[p], points[q]), q))
                .filter(|&(d, _)| d <= params.connect_steps)
                .collect();
            near.sort_unstable();
            for &(_, q) in near.iter().take(params.tries_per_tree) {
                *searches += 1;
                let block = Block::about(points[p], points[q], params.block_margin);
                if astar(space, points[p], points[q], block).route.is_some() {
                    edges.push((p, q));
                    let (keep, gone) = (t, tree_of[p]);
                    let moved = std::mem::take(&mut trees[gone]);
                    for &m in &moved {
                        tree_of[m] = keep;
                    }
                    trees[keep].extend(moved);
                    break;
                }
            }
        }
    };
    try_join(
        space,
        &points,
        &mut tree_of,
        &mut trees,
        &mut edges,
        &mut searches,
        0,
    );
    let mut draws = 0;
    while tree_of[0] != tree_of[1] {
        if draws >= params.max_draws {
            return None;
        }
        draws += 1;
        let c = CgCell::new(
            rng.random_range(0..grid.nx),
            rng.random_range(0..grid.ny),
            rng.random_range(0..grid.theta_bins),
        );
        if !space.is_valid(c) {
            continue;
        }
        let p = points.len();
        points.push(c);
        tree_of.push(trees.len());
        trees.push(vec![p]);
        try_join(
            space,
            &points,
            &mut tree_of,
            &mut trees,
            &mut edges,
            &mut searches,
            p,
        );
    }
    // The joined trees form a tree over the edges: find the chain from start to goal and
    // recreate each edge's path with A*.
    let mut adjacency: HashMap<usize, Vec<usize>> = HashMap::new();
    for &(a, b) in &edges {
        adjacency.entry(a).or_default().push(b);
        adjacency.entry(b).or_default().push(a);
    }
    let mut prev: HashMap<usize, usize> = HashMap::new();
    let mut queue = VecDeque::from([0usize]);
    prev.insert(0, 0);
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
    let mut cells = vec![start];
    for w in chain.windows(2) {
        let (a, b) = (points[w[0]], points[w[1]]);
        searches += 1;
        let leg = astar(space, a, b, Block::about(a, b, params.block_margin)).route?;
        cells.extend(leg.into_iter().skip(1));
    }
    Some(Route {
        cells,
        draws,
        searches,
        points: points.len(),
    })
}

/// The shortest span of route cells [`shortcut`] tries to cut.
const SHORTEST_CUT: usize = 4;

/// A roadmap's route with its detours cut: from each cell reached, A* (in the block about
/// the two cells) to the route cell `params.shortcut_cells` further on, or half as far, and
/// so on down to a few cells, and the first that is cheaper than the stretch it replaces
/// (see [`route_cost`](crate::astar::route_cost)) takes its place; where none is, the route
/// goes on as it was for a few cells. The roadmap's route passes through its randomly drawn
/// points, each at a random heading; this leaves the ones that were on the way. Every cell
/// of the result is valid, and the result costs no more than the route given.
pub fn shortcut(space: &mut CgSpace, cells: &[CgCell], params: &RouteParams) -> Vec<CgCell> {
    let Some(&first) = cells.first() else {
        return Vec::new();
    };
    let last = cells.len() - 1;
    let mut out = vec![first];
    let mut i = 0;
    while i < last {
        let mut span = params.shortcut_cells.min(last - i);
        let mut cut = None;
        while span >= SHORTEST_CUT {
            let (a, b) = (cells[i], cells[i + span]);
            let found = astar(space, a, b, Block::about(a, b, params.block_margin)).route;
            if let Some(r) = found.filter(|r| route_cost(r) < route_cost(&cells[i..=i + span])) {
                cut = Some((i + span, r));
                break;
            }
            span /= 2;
        }
        match cut {
            Some((j, r)) => {
                out.extend_from_slice(&r[1..]);
                i = j;
            }
            None => {
                let j = (i + SHORTEST_CUT).min(last);
                out.extend_from_slice(&cells[i + 1..=j]);
                i = j;
            }
        }
    }
    out
}
