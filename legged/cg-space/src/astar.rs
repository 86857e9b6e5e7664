//! A* through CG-space inside a block: the route planner's local planner.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use rustc_hash::FxHashMap;

use crate::grid::CgCell;
use crate::space::CgSpace;

/// The block an A* search between two cells is confined to: their bounding box in x and y
/// widened by `margin` cells on every side (clipped to the map), every heading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Block {
    /// Smallest column.
    pub x0: i32,
    /// Largest column.
    pub x1: i32,
    /// Smallest row.
    pub y0: i32,
    /// Largest row.
    pub y1: i32,
}

impl Block {
    /// The block about two cells.
    pub fn about(a: CgCell, b: CgCell, margin: i32) -> Self {
        Block {
            x0: a.ix.min(b.ix) - margin,
            x1: a.ix.max(b.ix) + margin,
            y0: a.iy.min(b.iy) - margin,
            y1: a.iy.max(b.iy) + margin,
        }
    }

    /// The whole map.
    pub fn whole(space: &CgSpace) -> Self {
        let g = space.grid();
        Block {
            x0: 0,
            x1: g.nx - 1,
            y0: 0,
            y1: g.ny - 1,
        }
    }

    /// Whether a cell's column and row lie in the block.
    pub fn contains(&self, c: CgCell) -> bool {
        c.ix >= self.x0 && c.ix <= self.x1 && c.iy >= self.y0 && c.iy <= self.y1
    }
}

/// What a turn of one heading bin costs, in moves of one cell in x or y. Turning the body
/// a whole bin with its feet planted asks far more of the legs than moving it one cell, and
/// the foot-level search gets stuck at turns more often than anywhere else: routes turn
/// only where it saves three moves or more.
pub const TURN_COST: i32 = 3;

/// The cost of the move between two 6-neighbours: 1 in x or y, [`TURN_COST`] in heading.
pub fn step_cost(a: CgCell, b: CgCell) -> i32 {
    if a.it == b.it { 1 } else { TURN_COST }
}

/// The cost of a route, move by move (see [`step_cost`]).
pub fn route_cost(cells: &[CgCell]) -> i32 {
    cells.windows(2).map(|w| step_cost(w[0], w[1])).sum()
}

/// What an A* search found.
#[derive(Debug, Clone, PartialEq)]
pub struct AStarResult {
    /// The route, both ends included, each cell a 6-neighbour of the one before; `None`
    /// when the block holds no route.
    pub route: Option<Vec<CgCell>>,
    /// Cells taken off the open list.
    pub expanded: usize,
}

/// A* from `from` to `to` over valid cells in `block` with 6-neighbour moves (θ wrapping),
/// each costing [`step_cost`]; the heuristic is the moves in x and y plus [`TURN_COST`] per
/// heading bin between the cells (admissible, so the route is the cheapest). Both ends must
/// be valid, or there is no route.
pub fn astar(space: &mut CgSpace, from: CgCell, to: CgCell, block: Block) -> AStarResult {
    let mut expanded = 0;
    if !(block.contains(from) && block.contains(to) && space.is_valid(from) && space.is_valid(to)) {
        return AStarResult {
            route: None,
            expanded,
        };
    }
    let grid = *space.grid();
    let cost_between = |a: CgCell, b: CgCell| {
        (a.ix - b.ix).abs() + (a.iy - b.iy).abs() + TURN_COST * grid.theta_steps(a.it, b.it)
    };
    let mut open = BinaryHeap::new();
    let mut best: FxHashMap<CgCell, (i32, Option<CgCell>)> = FxHashMap::default();
    best.insert(from, (0, None));
    open.push(Reverse((cost_between(from, to), Reverse(0), from)));
    while let Some(Reverse((_, Reverse(g), c))) = open.pop() {
        if best.get(&c).is_some_and(|&(bg, _)| bg < g) {
            continue;
        }
        expanded += 1;
        if c == to {
            let mut route = vec![c];
            let mut at = c;
            while let Some(&(_, Some(p))) = best.get(&at) {
                route.push(p);
                at = p;
            }
            route.reverse();
            return AStarResult {
                route: Some(route),
                expanded,
            };
        }
        let neighbours: Vec<CgCell> = grid.neighbours(c).filter(|n| block.contains(*n)).collect();
        for n in neighbours {
            let ng = g + step_cost(c, n);
            if best.get(&n).is_some_and(|&(bg, _)| bg <= ng) {
                continue;
            }
            if !space.is_valid(n) {
                continue;
            }
            best.insert(n, (ng, Some(c)));
            open.push(Reverse((ng + cost_between(n, to), Reverse(ng), n)));
        }
    }
    AStarResult {
        route: None,
        expanded,
    }
}
