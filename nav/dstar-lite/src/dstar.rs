//! D* Lite (Koenig and Likhachev): an incremental search from the goal to the start.

use std::collections::BinaryHeap;

use crate::key::{Entry, Key};
use crate::{Cell, CostGrid, Path, PlanError, octile};

/// D* Lite over a [`CostGrid`], keeping its search between calls.
///
/// `g` of a vertex is its cost-to-goal as last expanded and `rhs` its one-step lookahead
/// (the best neighbour's `g` plus the move's cost); the open list holds the vertices
/// where the two differ. A change of danger touches only the moves into that cell, so
/// only its neighbours' `rhs` are recomputed; [`DStarLite::plan`] then expands vertices
/// until the start is consistent again. Moving the start raises the key modifier `km` by
/// the heuristic distance moved instead of re-keying the open list.
#[derive(Debug, Clone)]
pub struct DStarLite {
    grid: CostGrid,
    g: Vec<f64>,
    rhs: Vec<f64>,
    /// The key each vertex holds on the open list, if it is on it (heap entries whose key
    /// differs are stale and skipped).
    open_key: Vec<Option<Key>>,
    open: BinaryHeap<Entry>,
    km: f64,
    start: usize,
    last: usize,
    goal: usize,
    total_expansions: u64,
}

impl DStarLite {
    /// A planner over `grid` from `start` to `goal`; nothing is searched until
    /// [`plan`](Self::plan).
    pub fn new(grid: CostGrid, start: Cell, goal: Cell) -> Result<Self, PlanError> {
        grid.check(start)?;
        grid.check(goal)?;
        let n = grid.len();
        let (s, t) = (grid.index(start), grid.index(goal));
        let mut planner = Self {
            g: vec![f64::INFINITY; n],
            rhs: vec![f64::INFINITY; n],
            open_key: vec![None; n],
            open: BinaryHeap::new(),
            km: 0.0,
            start: s,
            last: s,
            goal: t,
            total_expansions: 0,
            grid,
        };
        planner.rhs[t] = 0.0;
        let k = planner.key(t);
        planner.push(t, k);
        Ok(planner)
    }

    /// The grid as the planner knows it.
    pub fn grid(&self) -> &CostGrid {
        &self.grid
    }

    /// The start cell.
    pub fn start(&self) -> Cell {
        self.grid.cell(self.start)
    }

    /// The goal cell.
    pub fn goal(&self) -> Cell {
        self.grid.cell(self.goal)
    }

    /// Vertices expanded since the planner was made.
    pub fn total_expansions(&self) -> u64 {
        self.total_expansions
    }

    /// Moves the start (the robot's cell) to `start`.
    pub fn move_start(&mut self, start: Cell) -> Result<(), PlanError> {
        self.grid.check(start)?;
        let s = self.grid.index(start);
        if s != self.start {
            self.start = s;
            self.km += octile(self.grid.cell(self.last), start);
            self.last = s;
        }
        Ok(())
    }

    /// Sets the danger of `cell`; returns whether it changed. The moves into `cell` change
    /// cost, so its neighbours are brought up to date on the open list.
    pub fn set_danger(&mut self, cell: Cell, danger: f64) -> Result<bool, PlanError> {
        if !self.grid.set_danger(cell, danger)? {
            return Ok(false);
        }
        let v = self.grid.index(cell);
        let preds: Vec<usize> = self.grid.neighbours(v).map(|(u, _)| u).collect();
        for u in preds {
            self.update_vertex(u);
        }
        Ok(true)
    }

    /// Repairs the search after the changes since the last call and returns the path of
    /// minimum cost from the start to the goal, or [`PlanError::NoPath`].
    pub fn plan(&mut self) -> Result<Path, PlanError> {
        let expansions = self.compute_shortest_path();
        let (start, goal) = (self.start(), self.goal());
        if !self.rhs[self.start].is_finite() {
            return Err(PlanError::NoPath { start, goal });
        }
        let mut cells = vec![start];
        let mut u = self.start;
        let limit = self.grid.len();
        while u != self.goal {
            let next = self
                .grid
                .neighbours(u)
                .map(|(v, len)| (v, self.grid.enter_cost(v, len) + self.g[v]))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match next {
                Some((v, c)) if c.is_finite() && cells.len() <= limit => {
                    cells.push(self.grid.cell(v));
                    u = v;
                }
                _ => return Err(PlanError::NoPath { start, goal }),
            }
        }
        Ok(Path {
            cost: self.grid.path_cost(&cells),
            cells,
            expansions,
        })
    }

    fn h(&self, v: usize) -> f64 {
        octile(self.grid.cell(self.start), self.grid.cell(v))
    }

    fn key(&self, v: usize) -> Key {
        let m = self.g[v].min(self.rhs[v]);
        Key(m + self.h(v) + self.km, m)
    }

    fn push(&mut self, v: usize, key: Key) {
        self.open_key[v] = Some(key);
        self.open.push(Entry { key, vertex: v });
    }

    /// The smallest live key on the open list, dropping stale heap entries.
    fn top(&mut self) -> Option<Entry> {
        while let Some(e) = self.open.peek() {
            if self.open_key[e.vertex] == Some(e.key) {
                return Some(*e);
            }
            self.open.pop();
        }
        None
    }

    fn best_rhs(&self, u: usize) -> f64 {
        self.grid
            .neighbours(u)
            .map(|(v, len)| self.grid.enter_cost(v, len) + self.g[v])
            .fold(f64::INFINITY, f64::min)
    }

    fn update_vertex(&mut self, u: usize) {
        if u != self.goal {
            self.rhs[u] = self.best_rhs(u);
        }
        if self.g[u] != self.rhs[u] {
            let k = self.key(u);
            if self.open_key[u] != Some(k) {
                self.push(u, k);
            }
        } else {
            self.open_key[u] = None;
        }
    }

    fn compute_shortest_path(&mut self) -> u64 {
        let mut expansions = 0u64;
        while let Some(top) = self.top() {
            let start_key = self.key(self.start);
            if !(top.key.lt(&start_key) || self.rhs[self.start] > self.g[self.start]) {
                break;
            }
            let u = top.vertex;
            let k_new = self.key(u);
            if top.key.lt(&k_new) {
                self.open.pop();
                self.push(u, k_new);
                continue;
            }
            self.open.pop();
            self.open_key[u] = None;
            expansions += 1;
            let preds: Vec<usize> = self.grid.neighbours(u).map(|(p, _)| p).collect();
            if self.g[u] > self.rhs[u] {
                self.g[u] = self.rhs[u];
                let gu = self.g[u];
                for p in preds {
                    if p != self.goal {
                        // The move p -> u has the length between them and enters u.
                        let len = move_len(&self.grid, p, u);
                        let c = self.grid.enter_cost(u, len) + gu;
                        if c < self.rhs[p] {
                            self.rhs[p] = c;
                        }
                    }
                    self.update_vertex_keep_rhs(p);
                }
            } else {
                self.g[u] = f64::INFINITY;
                self.update_vertex(u);
                for p in preds {
                    self.update_vertex(p);
                }
            }
        }
        self.total_expansions += expansions;
        expansions
    }

    /// Like [`update_vertex`](Self::update_vertex) but with `rhs` already brought up to date.
    fn update_vertex_keep_rhs(&mut self, u: usize) {
        if self.g[u] != self.rhs[u] {
            let k = self.key(u);
            if self.open_key[u] != Some(k) {
                self.push(u, k);
            }
        } else {
            self.open_key[u] = None;
        }
    }
}

fn move_len(grid: &CostGrid, a: usize, b: usize) -> f64 {
    let (ca, cb) = (grid.cell(a), grid.cell(b));
    if ca.ix != cb.ix && ca.iy != cb.iy {
        std::f64::consts::SQRT_2
    } else {
        1.0
    }
}
