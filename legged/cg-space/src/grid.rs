//! The CG-space grid: cells over the centre of gravity's world (x, y) and heading θ.

use std::f64::consts::TAU;

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::error::CgError;

/// One CG cell: column `ix` (world X), row `iy` (world Y) and heading bin `it`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct CgCell {
    /// Column, counted east from the grid's origin.
    pub ix: i32,
    /// Row, counted north from the grid's origin.
    pub iy: i32,
    /// Heading bin: heading `it * 2π / bins`, counter-clockwise from world +X.
    pub it: u16,
}

impl CgCell {
    /// A cell.
    pub const fn new(ix: i32, iy: i32, it: u16) -> Self {
        CgCell { ix, iy, it }
    }
}

/// The geometry of CG-space: square cells of `cell_m` over the map's rectangle, and
/// `theta_bins` heading bins (θ wraps at 2π).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CgGrid {
    /// World position of cell (0, 0)'s lower-left corner, metres.
    pub origin: Point2<f64>,
    /// Side of a cell, metres.
    pub cell_m: f64,
    /// Columns.
    pub nx: i32,
    /// Rows.
    pub ny: i32,
    /// Heading bins (1: the heading is fixed at 0).
    pub theta_bins: u16,
}

impl CgGrid {
    /// A grid of cells of `cell_m` covering the rectangle `min..max` (whole cells inside).
    pub fn covering(
        min: Point2<f64>,
        max: Point2<f64>,
        cell_m: f64,
        theta_bins: u16,
    ) -> Result<Self, CgError> {
        if !(cell_m.is_finite() && cell_m > 0.0) {
            return Err(CgError::BadParameter {
                what: "the CG cell size",
                value: cell_m,
                hint: "give a positive size in metres",
            });
        }
        if theta_bins == 0 {
            return Err(CgError::BadParameter {
                what: "the number of heading bins",
                value: 0.0,
                hint: "give 1 (no turning) or at least 8",
            });
        }
        let nx = ((max.x - min.x) / cell_m).floor();
        let ny = ((max.y - min.y) / cell_m).floor();
        if !(nx >= 1.0 && ny >= 1.0 && nx < 1e6 && ny < 1e6) {
            return Err(CgError::BadParameter {
                what: "the map's width in CG cells",
                value: nx.min(ny),
                hint: "the map must be at least one cell and at most a million cells across",
            });
        }
        Ok(CgGrid {
            origin: min,
            cell_m,
            nx: nx as i32,
            ny: ny as i32,
            theta_bins,
        })
    }

    /// Whether the cell's column and row lie in the grid (any heading bin below
    /// `theta_bins`).
    pub fn contains(&self, c: CgCell) -> bool {
        c.ix >= 0 && c.iy >= 0 && c.ix < self.nx && c.iy < self.ny && c.it < self.theta_bins
    }

    /// Whether column `ix`, row `iy` lie in the grid.
    pub fn contains_xy(&self, ix: i32, iy: i32) -> bool {
        ix >= 0 && iy >= 0 && ix < self.nx && iy < self.ny
    }

    /// The world position of a cell's centre, metres.
    pub fn centre(&self, ix: i32, iy: i32) -> Point2<f64> {
        Point2::new(
            self.origin.x + (f64::from(ix) + 0.5) * self.cell_m,
            self.origin.y + (f64::from(iy) + 0.5) * self.cell_m,
        )
    }

    /// Whether the square of half-side `margin_m` about a world point lies on the grid.
    pub fn holds_within(&self, p: Point2<f64>, margin_m: f64) -> bool {
        let hi = Point2::new(
            self.origin.x + f64::from(self.nx) * self.cell_m,
            self.origin.y + f64::from(self.ny) * self.cell_m,
        );
        p.x - margin_m >= self.origin.x
            && p.y - margin_m >= self.origin.y
            && p.x + margin_m <= hi.x
            && p.y + margin_m <= hi.y
    }

    /// The heading of bin `it`, radians in `[0, 2π)`.
    pub fn theta(&self, it: u16) -> f64 {
        f64::from(it) * TAU / f64::from(self.theta_bins)
    }

    /// The column and row holding a world point (possibly outside the grid).
    pub fn xy_of(&self, p: Point2<f64>) -> (i32, i32) {
        (
            ((p.x - self.origin.x) / self.cell_m).floor() as i32,
            ((p.y - self.origin.y) / self.cell_m).floor() as i32,
        )
    }

    /// The heading bin nearest a heading (any angle, wrapped).
    pub fn bin_of(&self, theta_rad: f64) -> u16 {
        let n = f64::from(self.theta_bins);
        let b = (theta_rad.rem_euclid(TAU) / TAU * n).round() as i64;
        (b.rem_euclid(i64::from(self.theta_bins))) as u16
    }

    /// The cell holding a pose, if it lies in the grid.
    pub fn cell_of(&self, p: Point2<f64>, theta_rad: f64) -> Option<CgCell> {
        let (ix, iy) = self.xy_of(p);
        let c = CgCell::new(ix, iy, self.bin_of(theta_rad));
        self.contains(c).then_some(c)
    }

    /// The six neighbours of a cell (±x, ±y, ±θ with θ wrapping) that lie in the grid; with
    /// one heading bin, four; with two, five.
    pub fn neighbours(&self, c: CgCell) -> impl Iterator<Item = CgCell> + '_ {
        let n = self.theta_bins;
        let mut out = [None; 6];
        out[0] = Some(CgCell::new(c.ix + 1, c.iy, c.it));
        out[1] = Some(CgCell::new(c.ix - 1, c.iy, c.it));
        out[2] = Some(CgCell::new(c.ix, c.iy + 1, c.it));
        out[3] = Some(CgCell::new(c.ix, c.iy - 1, c.it));
        if n > 1 {
            out[4] = Some(CgCell::new(c.ix, c.iy, (c.it + 1) % n));
            if n > 2 {
                out[5] = Some(CgCell::new(c.ix, c.iy, (c.it + n - 1) % n));
            }
        }
        out.into_iter().flatten().filter(move |&d| self.contains(d))
    }

    /// Heading bins between two bins the short way round.
    pub fn theta_steps(&self, a: u16, b: u16) -> i32 {
        let n = i32::from(self.theta_bins);
        let d = (i32::from(a) - i32::from(b)).rem_euclid(n);
        d.min(n - d)
    }

    /// The number of 6-neighbour moves between two cells when nothing is in the way.
    pub fn steps_between(&self, a: CgCell, b: CgCell) -> i32 {
        (a.ix - b.ix).abs() + (a.iy - b.iy).abs() + self.theta_steps(a.it, b.it)
    }

    /// All cells of the grid.
    pub fn cell_count(&self) -> usize {
        self.nx as usize * self.ny as usize * usize::from(self.theta_bins)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> CgGrid {
        CgGrid::covering(Point2::new(0.0, 0.0), Point2::new(10.0, 5.0), 0.5, 8).unwrap()
    }

    #[test]
    fn covering_counts_whole_cells_and_refuses_nonsense() {
        let g = grid();
        assert_eq!((g.nx, g.ny), (20, 10));
        assert!(CgGrid::covering(Point2::origin(), Point2::new(1.0, 1.0), 0.0, 8).is_err());
        assert!(CgGrid::covering(Point2::origin(), Point2::new(1.0, 1.0), 0.1, 0).is_err());
        assert!(CgGrid::covering(Point2::origin(), Point2::new(0.05, 1.0), 0.1, 1).is_err());
    }

    #[test]
    fn theta_wraps_in_the_neighbours() {
        let g = grid();
        let n: Vec<_> = g.neighbours(CgCell::new(0, 0, 0)).collect();
        assert_eq!(n.len(), 4);
        assert!(n.contains(&CgCell::new(0, 0, 7)));
        assert!(n.contains(&CgCell::new(0, 0, 1)));
        assert_eq!(g.theta_steps(0, 7), 1);
        assert_eq!(g.bin_of(-0.1), 0);
        assert_eq!(g.bin_of(std::f64::consts::PI), 4);
    }

    #[test]
    fn a_point_falls_in_its_cell() {
        let g = grid();
        let c = g.cell_of(Point2::new(2.3, 1.1), 0.0).unwrap();
        assert_eq!((c.ix, c.iy), (4, 2));
        let centre = g.centre(c.ix, c.iy);
        assert!((centre - Point2::new(2.25, 1.25)).norm() < 1e-12);
        assert!(g.cell_of(Point2::new(-0.1, 1.0), 0.0).is_none());
    }
}
