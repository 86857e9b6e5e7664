//! The danger grid both planners search.

use crate::PlanError;

/// One cell of a [`CostGrid`]: column `ix` (along world X), row `iy` (along world Y).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// Column.
    pub ix: usize,
    /// Row.
    pub iy: usize,
}

impl Cell {
    /// A cell.
    pub fn new(ix: usize, iy: usize) -> Self {
        Self { ix, iy }
    }
}

/// The octile distance between two cells, in cells: the length of the shortest
/// 8-connected path on an open grid.
pub fn octile(a: Cell, b: Cell) -> f64 {
    let dx = a.ix.abs_diff(b.ix) as f64;
    let dy = a.iy.abs_diff(b.iy) as f64;
    let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
    hi + (std::f64::consts::SQRT_2 - 1.0) * lo
}

/// The eight neighbour offsets, with their lengths in cells.
pub(crate) const NEIGHBOURS: [(isize, isize, f64); 8] = [
    (1, 0, 1.0),
    (-1, 0, 1.0),
    (0, 1, 1.0),
    (0, -1, 1.0),
    (1, 1, std::f64::consts::SQRT_2),
    (1, -1, std::f64::consts::SQRT_2),
    (-1, 1, std::f64::consts::SQRT_2),
    (-1, -1, std::f64::consts::SQRT_2),
];

/// A grid of danger values (`[0, 1]` for traversable cells, `∞` for untraversable ones;
/// values above 1 are allowed and cost accordingly) and the weight `beta` of danger
/// against length.
#[derive(Debug, Clone, PartialEq)]
pub struct CostGrid {
    nx: usize,
    ny: usize,
    beta: f64,
    danger: Vec<f64>,
}

impl CostGrid {
    /// A grid with every cell of danger `danger`.
    pub fn filled(nx: usize, ny: usize, beta: f64, danger: f64) -> Result<Self, PlanError> {
        let n = nx
            .checked_mul(ny)
            .filter(|&n| n > 0)
            .ok_or(PlanError::EmptyGrid { nx, ny })?;
        Self::from_dangers(nx, ny, beta, vec![danger; n])
    }

    /// A grid from row-major dangers (`danger[iy * nx + ix]`).
    pub fn from_dangers(
        nx: usize,
        ny: usize,
        beta: f64,
        danger: Vec<f64>,
    ) -> Result<Self, PlanError> {
        let expected = nx
            .checked_mul(ny)
            .filter(|&n| n > 0)
            .ok_or(PlanError::EmptyGrid { nx, ny })?;
        if danger.len() != expected {
            return Err(PlanError::LengthMismatch {
                nx,
                ny,
                expected,
                got: danger.len(),
            });
        }
        if !(beta.is_finite() && beta >= 0.0) {
            return Err(PlanError::BadBeta(beta));
        }
        if let Some(i) = danger.iter().position(|d| !valid_danger(*d)) {
            return Err(PlanError::BadDanger {
                cell: Cell::new(i % nx, i / nx),
                value: danger[i],
            });
        }
        Ok(Self {
            nx,
            ny,
            beta,
            danger,
        })
    }

    /// Columns.
    pub fn nx(&self) -> usize {
        self.nx
    }

    /// Rows.
    pub fn ny(&self) -> usize {
        self.ny
    }

    /// The weight of danger against length.
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// Whether `cell` lies in the grid.
    pub fn contains(&self, cell: Cell) -> bool {
        cell.ix < self.nx && cell.iy < self.ny
    }

    /// `cell` if it lies in the grid, else the error saying it does not.
    pub fn check(&self, cell: Cell) -> Result<Cell, PlanError> {
        if self.contains(cell) {
            Ok(cell)
        } else {
            Err(PlanError::OutOfGrid {
                cell,
                nx: self.nx,
                ny: self.ny,
            })
        }
    }

    /// The danger of `cell` (`∞` outside the grid).
    pub fn danger(&self, cell: Cell) -> f64 {
        if self.contains(cell) {
            self.danger[self.index(cell)]
        } else {
            f64::INFINITY
        }
    }

    /// Sets the danger of `cell`; returns whether it changed.
    pub fn set_danger(&mut self, cell: Cell, danger: f64) -> Result<bool, PlanError> {
        self.check(cell)?;
        if !valid_danger(danger) {
            return Err(PlanError::BadDanger {
                cell,
                value: danger,
            });
        }
        let i = self.index(cell);
        let changed = self.danger[i] != danger;
        self.danger[i] = danger;
        Ok(changed)
    }

    /// The cost of moving from `from` to its neighbour `to`: length + beta * danger(to),
    /// `∞` if `to` is untraversable.
    pub fn edge_cost(&self, from: Cell, to: Cell) -> f64 {
        let d = self.danger(to);
        if d.is_infinite() {
            return f64::INFINITY;
        }
        let diagonal = from.ix != to.ix && from.iy != to.iy;
        let len = if diagonal {
            std::f64::consts::SQRT_2
        } else {
            1.0
        };
        len + self.beta * d
    }

    /// The cost of a path given as consecutive neighbouring cells.
    pub fn path_cost(&self, cells: &[Cell]) -> f64 {
        cells.windows(2).map(|w| self.edge_cost(w[0], w[1])).sum()
    }

    pub(crate) fn len(&self) -> usize {
        self.danger.len()
    }

    pub(crate) fn index(&self, cell: Cell) -> usize {
        cell.iy * self.nx + cell.ix
    }

    pub(crate) fn cell(&self, index: usize) -> Cell {
        Cell::new(index % self.nx, index / self.nx)
    }

    /// The neighbours of vertex `i` with the length of the move to each.
    pub(crate) fn neighbours(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (x, y) = ((i % self.nx) as isize, (i / self.nx) as isize);
        NEIGHBOURS.iter().filter_map(move |&(dx, dy, len)| {
            let (nx, ny) = (x + dx, y + dy);
            (nx >= 0 && ny >= 0 && (nx as usize) < self.nx && (ny as usize) < self.ny)
                .then(|| (ny as usize * self.nx + nx as usize, len))
        })
    }

    /// Cost of entering vertex `to` by a move of length `len`.
    pub(crate) fn enter_cost(&self, to: usize, len: f64) -> f64 {
        let d = self.danger[to];
        if d.is_infinite() {
            f64::INFINITY
        } else {
            len + self.beta * d
        }
    }
}

fn valid_danger(d: f64) -> bool {
    d >= 0.0 // false for NaN; true for +∞
}
