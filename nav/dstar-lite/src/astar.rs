//! A* from scratch: the baseline for the incremental planner.

use std::collections::BinaryHeap;

use crate::key::{Entry, Key};
use crate::{Cell, CostGrid, Path, PlanError, octile};

/// The minimum-cost path from `start` to `goal` by A* with the octile heuristic, searched
/// from scratch. `start` may itself be untraversable (the robot may stand in a cell later
/// found dangerous); no other untraversable cell is entered.
pub fn astar(grid: &CostGrid, start: Cell, goal: Cell) -> Result<Path, PlanError> {
    grid.check(start)?;
    grid.check(goal)?;
    let (s, t) = (grid.index(start), grid.index(goal));
    let n = grid.len();
    let mut g = vec![f64::INFINITY; n];
    let mut parent = vec![usize::MAX; n];
    let mut closed = vec![false; n];
    let mut open = BinaryHeap::new();
    g[s] = 0.0;
    open.push(Entry {
        key: Key(octile(start, goal), 0.0),
        vertex: s,
    });
    let mut expansions = 0u64;
    while let Some(Entry { vertex: u, .. }) = open.pop() {
        if closed[u] {
            continue;
        }
        closed[u] = true;
        expansions += 1;
        if u == t {
            break;
        }
        for (v, len) in grid.neighbours(u) {
            if closed[v] {
                continue;
            }
            let cand = g[u] + grid.enter_cost(v, len);
            if cand < g[v] {
                g[v] = cand;
                parent[v] = u;
                // Ties broken toward the larger g (nearer the goal), as usual for A*.
                open.push(Entry {
                    key: Key(cand + octile(grid.cell(v), goal), -cand),
                    vertex: v,
                });
            }
        }
    }
    if !g[t].is_finite() {
        return Err(PlanError::NoPath { start, goal });
    }
    let mut cells = vec![goal];
    let mut v = t;
    while v != s {
        v = parent[v];
        cells.push(grid.cell(v));
    }
    cells.reverse();
    Ok(Path {
        cost: grid.path_cost(&cells),
        cells,
        expansions,
    })
}
