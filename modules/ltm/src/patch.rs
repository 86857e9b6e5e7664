//! The map lattice and rectangular patches of it.
//!
//! Every map of one resolution shares one world-aligned lattice: cell `(i, j)` (signed
//! integers) is centred at `(i * resolution, j * resolution)` and covers half a cell either
//! side. Maps built from different images therefore line up cell for cell and merge without
//! resampling. A [`Patch`] is a dense rectangle of that lattice.

use nalgebra::Point2;

use crate::cell::Cell;

/// The lattice index of the cell containing a world coordinate.
pub fn lattice_index(coordinate_m: f64, resolution_m: f64) -> i64 {
    (coordinate_m / resolution_m + 0.5).floor() as i64
}

/// A dense rectangle of map cells on the lattice of `resolution_m`: cells `i0 .. i0 + nx`
/// by `j0 .. j0 + ny`, row-major by `j`.
#[derive(Debug, Clone, PartialEq)]
pub struct Patch {
    /// Lattice index of the first column.
    pub i0: i64,
    /// Lattice index of the first row.
    pub j0: i64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Cell size, metres.
    pub resolution_m: f64,
    /// `nx * ny` cells.
    pub cells: Vec<Cell>,
}

impl Patch {
    /// A patch of unknown cells.
    pub fn unknown(i0: i64, j0: i64, nx: usize, ny: usize, resolution_m: f64) -> Self {
        Self {
            i0,
            j0,
            nx,
            ny,
            resolution_m,
            cells: vec![Cell::UNKNOWN; nx * ny],
        }
    }

    /// The cell at lattice `(i, j)`; unknown outside the patch.
    pub fn get(&self, i: i64, j: i64) -> Cell {
        self.index(i, j)
            .and_then(|k| self.cells.get(k))
            .copied()
            .unwrap_or(Cell::UNKNOWN)
    }

    /// The cell at lattice `(i, j)`, mutably; `None` outside the patch.
    pub fn get_mut(&mut self, i: i64, j: i64) -> Option<&mut Cell> {
        let k = self.index(i, j)?;
        self.cells.get_mut(k)
    }

    /// Row-major index of lattice `(i, j)`, if inside.
    pub fn index(&self, i: i64, j: i64) -> Option<usize> {
        let di = usize::try_from(i.checked_sub(self.i0)?).ok()?;
        let dj = usize::try_from(j.checked_sub(self.j0)?).ok()?;
        (di < self.nx && dj < self.ny).then(|| dj * self.nx + di)
    }

    /// World centre of lattice cell `(i, j)`.
    pub fn center(&self, i: i64, j: i64) -> Point2<f64> {
        Point2::new(i as f64 * self.resolution_m, j as f64 * self.resolution_m)
    }

    /// The cell containing a world point (unknown outside the patch).
    pub fn at(&self, p: Point2<f64>) -> Cell {
        self.get(
            lattice_index(p.x, self.resolution_m),
            lattice_index(p.y, self.resolution_m),
        )
    }

    /// World rectangle `(min, max)` covered by the patch's cells.
    pub fn bounds(&self) -> (Point2<f64>, Point2<f64>) {
        let r = self.resolution_m;
        (
            Point2::new((self.i0 as f64 - 0.5) * r, (self.j0 as f64 - 0.5) * r),
            Point2::new(
                (self.i0 as f64 + self.nx as f64 - 0.5) * r,
                (self.j0 as f64 + self.ny as f64 - 0.5) * r,
            ),
        )
    }

    /// Iterates `(i, j, cell)` over the patch.
    pub fn iter(&self) -> impl Iterator<Item = (i64, i64, &Cell)> + '_ {
        let nx = self.nx.max(1);
        self.cells
            .iter()
            .enumerate()
            .map(move |(k, c)| (self.i0 + (k % nx) as i64, self.j0 + (k / nx) as i64, c))
    }

    /// Cells of each state: (unknown, occluded, known).
    pub fn counts(&self) -> (usize, usize, usize) {
        use crate::cell::CellState::*;
        self.cells
            .iter()
            .fold((0, 0, 0), |(u, o, k), c| match c.state {
                Unknown => (u + 1, o, k),
                Occluded => (u, o + 1, k),
                Known => (u, o, k + 1),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_cells_contain_their_half_cells() {
        assert_eq!(lattice_index(0.0, 0.1), 0);
        assert_eq!(lattice_index(0.049, 0.1), 0);
        assert_eq!(lattice_index(0.051, 0.1), 1);
        assert_eq!(lattice_index(-0.051, 0.1), -1);
        assert_eq!(lattice_index(-0.049, 0.1), 0);
    }

    #[test]
    fn patch_indexing_is_bounded() {
        let mut p = Patch::unknown(-3, 5, 4, 2, 0.5);
        *p.get_mut(-3, 5).unwrap() = Cell::known(1.0, 0.1);
        *p.get_mut(0, 6).unwrap() = Cell::occluded(2.0);
        assert!(p.get_mut(1, 6).is_none());
        assert!(p.get_mut(-4, 5).is_none());
        assert_eq!(p.get(0, 6), Cell::occluded(2.0));
        assert_eq!(p.get(i64::MIN, i64::MAX), Cell::UNKNOWN);
        assert_eq!(p.at(Point2::new(-1.6, 2.4)), Cell::known(1.0, 0.1));
        assert_eq!(p.counts(), (6, 1, 1));
        let (lo, hi) = p.bounds();
        assert_eq!((lo.x, lo.y, hi.x, hi.y), (-1.75, 2.25, 0.25, 3.25));
    }
}
