//! The task-space A* planner: the foot's centre moves on a lattice of cells (20 cm by
//! default) laid from where the swing starts, from cell to neighbouring cell (26 of them),
//! the wheel kept upright; each cell's joint positions come from the inverse kinematics
//! started at its predecessor's. A wave front grows from the start by the length travelled
//! plus the straight distance left, until a cell within one cell of the goal connects to
//! it. The segment from a cell's predecessor is checked lazily, when the cell is taken
//! from the front.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::collision::{LegChecker, Phase};
use crate::maps::Evaluator;

/// The A* planner's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AstarParams {
    /// The lattice's cell, metres.
    pub cell_m: f64,
    /// Most cells taken from the front before giving up.
    pub max_expansions: usize,
}

impl Default for AstarParams {
    /// 20 cm cells, 400 expansions.
    fn default() -> Self {
        Self {
            cell_m: 0.20,
            max_expansions: 400,
        }
    }
}

/// What A* found.
#[derive(Debug, Clone, PartialEq)]
pub struct AstarOutcome {
    /// Joint positions from the start to the goal.
    pub path: Vec<Vec<f64>>,
    /// Cells taken from the front.
    pub expansions: usize,
}

#[derive(Debug, Clone)]
struct Cell {
    q: Vec<f64>,
    parent: Option<[i32; 3]>,
    g: f64,
    closed: bool,
}

#[derive(Debug, PartialEq)]
struct Open {
    f: f64,
    key: [i32; 3],
}

impl Eq for Open {}

impl Ord for Open {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .f
            .total_cmp(&self.f)
            .then_with(|| other.key.cmp(&self.key))
    }
}

impl PartialOrd for Open {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Plans the foot from joints `start` to joints `goal` (both collision-free, wheel
/// upright), placing the lattice's cells with `eval`'s inverse kinematics.
pub fn astar(
    checker: &LegChecker,
    eval: &Evaluator<'_>,
    start: &[f64],
    goal: &[f64],
    params: &AstarParams,
) -> Result<AstarOutcome, String> {
    if !(params.cell_m.is_finite() && params.cell_m > 0.0) {
        return Err(format!(
            "the A* cell is {} m; give a positive size",
            params.cell_m
        ));
    }
    let scene = checker.scene();
    let leg = checker.leg();
    let p0 = scene.foot_centre(leg, start);
    let pg = scene.foot_centre(leg, goal);
    let c = params.cell_m;
    let at = |k: [i32; 3]| p0 + Vector3::new(k[0] as f64, k[1] as f64, k[2] as f64) * c;
    let h = |p: &Point3<f64>| (pg - p).norm();
    let mut cells: HashMap<[i32; 3], Cell> = HashMap::new();
    let mut open = BinaryHeap::new();
    cells.insert(
        [0, 0, 0],
        Cell {
            q: start.to_vec(),
            parent: None,
            g: 0.0,
            closed: false,
        },
    );
    open.push(Open {
        f: h(&p0),
        key: [0, 0, 0],
    });
    let mut expansions = 0;
    while let Some(Open { key, .. }) = open.pop() {
        let Some(cell) = cells.get(&key) else {
            continue;
        };
        if cell.closed {
            continue;
        }
        // The segment from the predecessor, checked now that the cell is taken.
        if let Some(parent) = cell.parent {
            let from = cells[&parent].q.clone();
            if checker.segment(&from, &cell.q, Phase::Free).is_err() {
                cells.remove(&key);
                continue;
            }
        }
        expansions += 1;
        if expansions > params.max_expansions {
            break;
        }
        let (q, g) = {
            let cell = cells.get_mut(&key).expect("the cell was just read");
            cell.closed = true;
            (cell.q.clone(), cell.g)
        };
        let p = at(key);
        let near = (0..3).all(|i| (p[i] - pg[i]).abs() <= c + 1e-9);
        if near && checker.segment(&q, goal, Phase::Free).is_ok() {
            let mut path = vec![goal.to_vec(), q];
            let mut k = key;
            while let Some(parent) = cells[&k].parent {
                path.push(cells[&parent].q.clone());
                k = parent;
            }
            path.reverse();
            return Ok(AstarOutcome { path, expansions });
        }
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if dx == 0 && dy == 0 && dz == 0 {
                        continue;
                    }
                    let next = [key[0] + dx, key[1] + dy, key[2] + dz];
                    let pn = at(next);
                    let gn = g + (pn - p).norm();
                    if let Some(existing) = cells.get(&next)
                        && (existing.closed || existing.g <= gn)
                    {
                        continue;
                    }
                    let Some(qn) = eval.place(&pn, Some(&q)) else {
                        continue;
                    };
                    if checker.check(&qn, Phase::Free).is_some() {
                        continue;
                    }
                    cells.insert(
                        next,
                        Cell {
                            q: qn,
                            parent: Some(key),
                            g: gn,
                            closed: false,
                        },
                    );
                    open.push(Open {
                        f: gn + h(&pn),
                        key: next,
                    });
                }
            }
        }
    }
    Err(format!(
        "A* over {:.0} cm cells found no way after {expansions} cells",
        c * 100.0
    ))
}
