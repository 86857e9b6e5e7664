//! A generic regular grid over the world XY plane, shared by terrain, maps and planners.
//!
//! Cell `(ix, iy)` is centred at `origin + (ix * resolution, iy * resolution)` and covers a
//! square of side `resolution` around its centre. Cells are stored row-major: index
//! `iy * nx + ix`, so a row is a line of constant Y and rows go toward +Y.

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

/// Index of one cell of a [`Grid`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct CellIndex {
    /// Column (along world X).
    pub ix: usize,
    /// Row (along world Y).
    pub iy: usize,
}

impl CellIndex {
    /// A cell index.
    pub fn new(ix: usize, iy: usize) -> Self {
        Self { ix, iy }
    }
}

/// Why a grid could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// Resolution zero, negative or not finite.
    #[error("grid resolution {0} m is not valid; give a finite resolution greater than zero")]
    BadResolution(f64),
    /// Origin not finite.
    #[error("grid origin ({0}, {1}) is not finite")]
    BadOrigin(f64, f64),
    /// No cells, or more than the address space allows.
    #[error("grid size {nx} x {ny} is not valid; both must be at least 1")]
    BadSize {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
    /// The cell vector's length differs from `nx * ny`.
    #[error("grid of {nx} x {ny} needs {expected} cells but {got} were given")]
    LengthMismatch {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
        /// `nx * ny`.
        expected: usize,
        /// Length given.
        got: usize,
    },
}

/// A regular grid of `T` over the world XY plane (see the module docs for the layout).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Grid<T> {
    origin: Point2<f64>,
    resolution_m: f64,
    nx: usize,
    ny: usize,
    cells: Vec<T>,
}

impl<T> Grid<T> {
    /// A grid from row-major cells (`cells[iy * nx + ix]`).
    pub fn from_vec(
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
        cells: Vec<T>,
    ) -> Result<Self, GridError> {
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(GridError::BadResolution(resolution_m));
        }
        if !(origin.x.is_finite() && origin.y.is_finite()) {
            return Err(GridError::BadOrigin(origin.x, origin.y));
        }
        let expected = nx
            .checked_mul(ny)
            .filter(|&n| n > 0)
            .ok_or(GridError::BadSize { nx, ny })?;
        if cells.len() != expected {
            return Err(GridError::LengthMismatch {
                nx,
                ny,
                expected,
                got: cells.len(),
            });
        }
        Ok(Self {
            origin,
            resolution_m,
            nx,
            ny,
            cells,
        })
    }

    /// A grid whose cells are computed from their index and centre.
    pub fn from_fn(
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
        mut f: impl FnMut(CellIndex, Point2<f64>) -> T,
    ) -> Result<Self, GridError> {
        let n = nx.checked_mul(ny).ok_or(GridError::BadSize { nx, ny })?;
        let mut cells = Vec::with_capacity(n);
        for iy in 0..ny {
            for ix in 0..nx {
                let c = CellIndex { ix, iy };
                let centre = Point2::new(
                    origin.x + ix as f64 * resolution_m,
                    origin.y + iy as f64 * resolution_m,
                );
                cells.push(f(c, centre));
            }
        }
        Self::from_vec(origin, resolution_m, nx, ny, cells)
    }

    /// A grid with every cell set to `value`.
    pub fn filled(
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
        value: T,
    ) -> Result<Self, GridError>
    where
        T: Clone,
    {
        let n = nx.checked_mul(ny).ok_or(GridError::BadSize { nx, ny })?;
        Self::from_vec(origin, resolution_m, nx, ny, vec![value; n])
    }

    /// World XY of the centre of cell (0, 0).
    pub fn origin(&self) -> Point2<f64> {
        self.origin
    }

    /// Side of a cell, metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Number of columns (along X).
    pub fn nx(&self) -> usize {
        self.nx
    }

    /// Number of rows (along Y).
    pub fn ny(&self) -> usize {
        self.ny
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Always false: a grid has at least one cell.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The cells, row-major.
    pub fn cells(&self) -> &[T] {
        &self.cells
    }

    /// The cells, row-major, mutable.
    pub fn cells_mut(&mut self) -> &mut [T] {
        &mut self.cells
    }

    /// The row-major vector of cells.
    pub fn into_cells(self) -> Vec<T> {
        self.cells
    }

    /// Row-major index of a cell, if it is in the grid.
    pub fn index_of(&self, c: CellIndex) -> Option<usize> {
        (c.ix < self.nx && c.iy < self.ny).then(|| c.iy * self.nx + c.ix)
    }

    /// The cell at a row-major index.
    pub fn cell_of_index(&self, index: usize) -> Option<CellIndex> {
        (index < self.cells.len()).then(|| CellIndex {
            ix: index % self.nx,
            iy: index / self.nx,
        })
    }

    /// The value of a cell, if it is in the grid.
    pub fn get(&self, c: CellIndex) -> Option<&T> {
        self.index_of(c).and_then(|i| self.cells.get(i))
    }

    /// The value of a cell, mutable, if it is in the grid.
    pub fn get_mut(&mut self, c: CellIndex) -> Option<&mut T> {
        self.index_of(c).and_then(|i| self.cells.get_mut(i))
    }

    /// World XY of a cell's centre (also for indices past the edge).
    pub fn cell_center(&self, c: CellIndex) -> Point2<f64> {
        Point2::new(
            self.origin.x + c.ix as f64 * self.resolution_m,
            self.origin.y + c.iy as f64 * self.resolution_m,
        )
    }

    /// Continuous cell coordinates of a world point: cell centres are at whole numbers.
    pub fn world_to_grid(&self, p: Point2<f64>) -> (f64, f64) {
        (
            (p.x - self.origin.x) / self.resolution_m,
            (p.y - self.origin.y) / self.resolution_m,
        )
    }

    /// The cell containing a world point, if inside the grid.
    pub fn cell_at(&self, p: Point2<f64>) -> Option<CellIndex> {
        let (gx, gy) = self.world_to_grid(p);
        let (fx, fy) = ((gx + 0.5).floor(), (gy + 0.5).floor());
        if fx >= 0.0 && fy >= 0.0 && fx < self.nx as f64 && fy < self.ny as f64 {
            Some(CellIndex {
                ix: fx as usize,
                iy: fy as usize,
            })
        } else {
            None
        }
    }

    /// The cell nearest to a world point, clamped to the grid.
    pub fn nearest_cell(&self, p: Point2<f64>) -> CellIndex {
        let (gx, gy) = self.world_to_grid(p);
        let clamp = |g: f64, n: usize| {
            let r = (g + 0.5).floor();
            if r.is_nan() || r < 0.0 {
                0
            } else {
                (r as usize).min(n - 1)
            }
        };
        CellIndex {
            ix: clamp(gx, self.nx),
            iy: clamp(gy, self.ny),
        }
    }

    /// World rectangle covered by the cells: (min corner, max corner).
    pub fn bounds(&self) -> (Point2<f64>, Point2<f64>) {
        let half = 0.5 * self.resolution_m;
        (
            Point2::new(self.origin.x - half, self.origin.y - half),
            Point2::new(
                self.origin.x + (self.nx as f64 - 0.5) * self.resolution_m,
                self.origin.y + (self.ny as f64 - 0.5) * self.resolution_m,
            ),
        )
    }

    /// Inclusive index ranges `(ix_min..=ix_max, iy_min..=iy_max)` of the cells whose centres
    /// lie in the world rectangle `[min, max]`, or `None` if there are none.
    pub fn cell_range(
        &self,
        min: Point2<f64>,
        max: Point2<f64>,
    ) -> Option<(
        std::ops::RangeInclusive<usize>,
        std::ops::RangeInclusive<usize>,
    )> {
        let (gx0, gy0) = self.world_to_grid(min);
        let (gx1, gy1) = self.world_to_grid(max);
        let lo = |g: f64| g.ceil().max(0.0);
        let hi = |g: f64, n: usize| g.floor().min(n as f64 - 1.0);
        let (x0, x1, y0, y1) = (lo(gx0), hi(gx1, self.nx), lo(gy0), hi(gy1, self.ny));
        if !(x0 <= x1 && y0 <= y1) {
            return None;
        }
        Some((x0 as usize..=x1 as usize, y0 as usize..=y1 as usize))
    }

    /// Every cell with its index, row by row.
    pub fn iter(&self) -> impl Iterator<Item = (CellIndex, &T)> + '_ {
        let nx = self.nx;
        self.cells.iter().enumerate().map(move |(i, v)| {
            (
                CellIndex {
                    ix: i % nx,
                    iy: i / nx,
                },
                v,
            )
        })
    }

    /// Every cell with its index, mutable, row by row.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (CellIndex, &mut T)> + '_ {
        let nx = self.nx;
        self.cells.iter_mut().enumerate().map(move |(i, v)| {
            (
                CellIndex {
                    ix: i % nx,
                    iy: i / nx,
                },
                v,
            )
        })
    }

    /// A grid of the same layout with every cell mapped.
    pub fn map<U>(&self, mut f: impl FnMut(&T) -> U) -> Grid<U> {
        Grid {
            origin: self.origin,
            resolution_m: self.resolution_m,
            nx: self.nx,
            ny: self.ny,
            cells: self.cells.iter().map(&mut f).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_and_world_agree() {
        let g = Grid::from_fn(Point2::new(1.0, 2.0), 0.5, 4, 3, |c, _| c.ix + 10 * c.iy).unwrap();
        assert_eq!(g.get(CellIndex::new(3, 2)), Some(&23));
        assert_eq!(g.get(CellIndex::new(4, 0)), None);
        assert_eq!(g.cell_center(CellIndex::new(3, 2)), Point2::new(2.5, 3.0));
        assert_eq!(g.cell_at(Point2::new(2.6, 3.1)), Some(CellIndex::new(3, 2)));
        assert_eq!(g.cell_at(Point2::new(0.74, 2.0)), None);
        assert_eq!(
            g.cell_at(Point2::new(0.76, 2.0)),
            Some(CellIndex::new(0, 0))
        );
        assert_eq!(
            g.nearest_cell(Point2::new(-9.0, 99.0)),
            CellIndex::new(0, 2)
        );
        let (lo, hi) = g.bounds();
        assert_eq!((lo, hi), (Point2::new(0.75, 1.75), Point2::new(2.75, 3.25)));
        let (xr, yr) = g
            .cell_range(Point2::new(1.2, 2.0), Point2::new(9.0, 2.6))
            .unwrap();
        assert_eq!((xr, yr), (1..=3, 0..=1));
        assert!(
            g.cell_range(Point2::new(5.0, 5.0), Point2::new(6.0, 6.0))
                .is_none()
        );
        assert_eq!(
            g.iter().nth(5).map(|(c, v)| (c, *v)),
            Some((CellIndex::new(1, 1), 11))
        );
        assert_eq!(g.index_of(CellIndex::new(1, 1)), Some(5));
        assert_eq!(g.cell_of_index(5), Some(CellIndex::new(1, 1)));
        assert_eq!(g.map(|v| v * 2).get(CellIndex::new(1, 1)), Some(&22));
    }

    #[test]
    fn bad_layouts_are_refused() {
        assert!(matches!(
            Grid::<u8>::filled(Point2::origin(), 0.0, 2, 2, 0),
            Err(GridError::BadResolution(_))
        ));
        assert!(matches!(
            Grid::<u8>::filled(Point2::origin(), 1.0, 0, 2, 0),
            Err(GridError::BadSize { .. })
        ));
        assert!(matches!(
            Grid::from_vec(Point2::origin(), 1.0, 2, 2, vec![1, 2, 3]),
            Err(GridError::LengthMismatch {
                expected: 4,
                got: 3,
                ..
            })
        ));
        assert!(matches!(
            Grid::<u8>::filled(Point2::new(f64::NAN, 0.0), 1.0, 2, 2, 0),
            Err(GridError::BadOrigin(..))
        ));
    }
}
