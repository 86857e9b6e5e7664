//! Valid foot cells: where the ground under a CG-grid cell is within the robot's traction
//! limit, and how high the ground in it stands.

use tca_robot::{CellIndex, HeightField};

use crate::grid::CgGrid;

/// Per cell of a [`CgGrid`] (x and y only): the highest ground in it and whether a foot keeps
/// traction there.
#[derive(Debug, Clone, PartialEq)]
pub struct FootMap {
    nx: i32,
    ny: i32,
    height: Vec<f64>,
    slope: Vec<f64>,
    valid: Vec<bool>,
}

impl FootMap {
    /// Evaluates every cell of `grid` on `terrain`: a cell's slope is the steepest between
    /// neighbouring height samples in it (and on its edges), its height the highest sample;
    /// it is valid when the slope is at most `traction_slope_rad`.
    pub fn build(grid: &CgGrid, terrain: &HeightField, traction_slope_rad: f64) -> Self {
        let g = terrain.grid();
        let res = g.resolution_m();
        let o = g.origin();
        let limit = traction_slope_rad.tan();
        let n = grid.nx as usize * grid.ny as usize;
        let (mut height, mut slope, mut valid) = (vec![0.0; n], vec![0.0; n], vec![false; n]);
        let (gnx, gny) = (g.nx() as i64, g.ny() as i64);
        for iy in 0..grid.ny {
            for ix in 0..grid.nx {
                let lo = grid.centre(ix, iy)
                    - nalgebra::Vector2::new(grid.cell_m / 2.0, grid.cell_m / 2.0);
                let hi = lo + nalgebra::Vector2::new(grid.cell_m, grid.cell_m);
                let sx0 = ((lo.x - o.x) / res).floor() as i64;
                let sy0 = ((lo.y - o.y) / res).floor() as i64;
                let sx1 = ((hi.x - o.x) / res).ceil() as i64;
                let sy1 = ((hi.y - o.y) / res).ceil() as i64;
                let sample = |x: i64, y: i64| -> f64 {
                    let x = x.clamp(0, gnx - 1) as usize;
                    let y = y.clamp(0, gny - 1) as usize;
                    terrain.sample(CellIndex::new(x, y)).unwrap_or(f64::NAN)
                };
                let (mut top, mut steep) = (f64::NEG_INFINITY, 0.0f64);
                for sy in sy0..=sy1 {
                    for sx in sx0..=sx1 {
                        let h = sample(sx, sy);
                        top = top.max(h);
                        if sx < sx1 {
                            steep = steep.max((sample(sx + 1, sy) - h).abs() / res);
                        }
                        if sy < sy1 {
                            steep = steep.max((sample(sx, sy + 1) - h).abs() / res);
                        }
                    }
                }
                let inside = sx0 >= 0 && sy0 >= 0 && sx1 < gnx && sy1 < gny;
                let i = (iy * grid.nx + ix) as usize;
                height[i] = top;
                slope[i] = steep.atan();
                valid[i] = inside && top.is_finite() && steep <= limit;
            }
        }
        FootMap {
            nx: grid.nx,
            ny: grid.ny,
            height,
            slope,
            valid,
        }
    }

    fn index(&self, ix: i32, iy: i32) -> Option<usize> {
        (ix >= 0 && iy >= 0 && ix < self.nx && iy < self.ny).then(|| (iy * self.nx + ix) as usize)
    }

    /// Whether a foot keeps traction in the cell (false outside the map).
    pub fn valid(&self, ix: i32, iy: i32) -> bool {
        self.index(ix, iy).is_some_and(|i| self.valid[i])
    }

    /// The highest ground in the cell, metres.
    pub fn height(&self, ix: i32, iy: i32) -> Option<f64> {
        self.index(ix, iy).map(|i| self.height[i])
    }

    /// The steepest slope in the cell, radians.
    pub fn slope(&self, ix: i32, iy: i32) -> Option<f64> {
        self.index(ix, iy).map(|i| self.slope[i])
    }

    /// Marks a cell invalid (a foothold found unusable by other means).
    pub fn forbid(&mut self, ix: i32, iy: i32) {
        if let Some(i) = self.index(ix, iy) {
            self.valid[i] = false;
        }
    }

    /// How many cells are valid.
    pub fn valid_count(&self) -> usize {
        self.valid.iter().filter(|v| **v).count()
    }
}
