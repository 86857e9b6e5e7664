//! The planner's view of the terrain: heights from a [`HeightField`], a foothold quality
//! for every cell (the footfall evaluation's slope and roughness summed over the cell's
//! 3 x 3 neighbourhood), and a robust plane fit of the ground under the body.

use std::sync::Arc;

use nalgebra::{Matrix3, Point2, Vector3};
use tca_free_gait::{GridView, TerrainView};
use tca_robot::HeightField;

/// The terrain with its foothold qualities, computed once for the whole map.
#[derive(Debug, Clone)]
pub struct Terrain {
    view: GridView,
    /// Quality of each cell alone (lower is better, infinity forbidden), row-major.
    single: Vec<f64>,
    /// The sum of `single` over each cell's 3 x 3 neighbourhood.
    summed: Vec<f64>,
    /// The highest sample of each block of `BLOCK` x `BLOCK` samples, row-major.
    block_max: Vec<f64>,
    /// Blocks along X.
    blocks_x: usize,
}

/// Samples along each side of a block of the coarse maximum grid.
const BLOCK: usize = 4;

impl Terrain {
    /// The terrain of a height field for a foot of `foot_radius_m`: every cell's footfall
    /// cost (how far the ground under the foot strays from its tangent plane, in foot
    /// radii, plus the slope's tangent; steeper than 35° or rougher than 0.3 foot radii is
    /// forbidden) and its 3 x 3 neighbourhood sum.
    pub fn new(terrain: Arc<HeightField>, foot_radius_m: f64) -> Terrain {
        let view = GridView::new(terrain);
        let grid = view.terrain().grid();
        let (nx, ny) = (grid.nx(), grid.ny());
        let mut single = vec![f64::INFINITY; nx * ny];
        for iy in 0..ny {
            for ix in 0..nx {
                let p = grid.cell_center(tca_robot::grid::CellIndex::new(ix, iy));
                single[iy * nx + ix] = view
                    .foothold_cost(p, foot_radius_m)
                    .unwrap_or(f64::INFINITY);
            }
        }
        let mut summed = vec![f64::INFINITY; nx * ny];
        for iy in 1..ny.saturating_sub(1) {
            for ix in 1..nx.saturating_sub(1) {
                let mut s = 0.0;
                for dy in [-1i64, 0, 1] {
                    for dx in [-1i64, 0, 1] {
                        let j = (iy as i64 + dy) as usize * nx + (ix as i64 + dx) as usize;
                        s += single[j];
                    }
                }
                summed[iy * nx + ix] = s;
            }
        }
        let heights = view.terrain().grid().cells();
        let (bx, by) = (nx.div_ceil(BLOCK), ny.div_ceil(BLOCK));
        let mut block_max = vec![f64::NEG_INFINITY; bx * by];
        for iy in 0..ny {
            for ix in 0..nx {
                let b = &mut block_max[(iy / BLOCK) * bx + ix / BLOCK];
                *b = b.max(heights[iy * nx + ix]);
            }
        }
        Terrain {
            view,
            single,
            summed,
            block_max,
            blocks_x: bx,
        }
    }

    /// The height field.
    pub fn height_field(&self) -> &HeightField {
        self.view.terrain()
    }

    /// Cell size, metres.
    pub fn resolution_m(&self) -> f64 {
        self.height_field().grid().resolution_m()
    }

    /// The sampled rectangle (min corner, max corner).
    pub fn extent(&self) -> (Point2<f64>, Point2<f64>) {
        self.height_field().extent()
    }

    /// Whether a point lies inside the map with `margin` to spare.
    pub fn inside(&self, p: Point2<f64>, margin: f64) -> bool {
        let (lo, hi) = self.extent();
        p.x.is_finite()
            && p.y.is_finite()
            && p.x - margin >= lo.x
            && p.x + margin <= hi.x
            && p.y - margin >= lo.y
            && p.y + margin <= hi.y
    }

    /// The ground's height at a point, metres (edge-clamped outside the map).
    pub fn height(&self, p: Point2<f64>) -> f64 {
        self.height_field().height_at(p.x, p.y)
    }

    /// The highest ground within a disc, metres, or a little more: the highest sample of
    /// the cells that the disc's bounding square touches (the surface is bilinear between
    /// samples, so it never rises above them); for discs wider than two cells, the highest
    /// of the coarse blocks of samples the square touches. Edge-clamped outside the map.
    pub fn max_in_disc(&self, c: Point2<f64>, r: f64) -> f64 {
        let grid = self.height_field().grid();
        let res = grid.resolution_m();
        let r = if r.is_finite() { r.max(0.0) } else { 0.0 };
        if r == 0.0 {
            return self.height(c);
        }
        let (gx, gy) = grid.world_to_grid(c);
        let (nx, ny) = (grid.nx(), grid.ny());
        let span = |g: f64, n: usize| {
            let lo = (g - r / res).floor().clamp(0.0, (n - 1) as f64) as usize;
            let hi = (g + r / res).ceil().clamp(0.0, (n - 1) as f64) as usize;
            (lo, hi)
        };
        let (x0, x1) = span(gx, nx);
        let (y0, y1) = span(gy, ny);
        let mut best = f64::NEG_INFINITY;
        if r <= 2.0 * res {
            let h = grid.cells();
            for iy in y0..=y1 {
                for &v in &h[iy * nx + x0..=iy * nx + x1] {
                    best = best.max(v);
                }
            }
        } else {
            for by in y0 / BLOCK..=y1 / BLOCK {
                for bx in x0 / BLOCK..=x1 / BLOCK {
                    best = best.max(self.block_max[by * self.blocks_x + bx]);
                }
            }
        }
        best
    }

    /// The 3 x 3 summed foothold quality of the cell containing `p` (lower is better);
    /// infinity for a forbidden cell or one next to a forbidden cell, or outside the map.
    pub fn foothold_quality(&self, p: Point2<f64>) -> f64 {
        self.cell(p).map_or(f64::INFINITY, |k| self.summed[k])
    }

    /// The quality of the cell containing `p` alone.
    pub fn cell_quality(&self, p: Point2<f64>) -> f64 {
        self.cell(p).map_or(f64::INFINITY, |k| self.single[k])
    }

    fn cell(&self, p: Point2<f64>) -> Option<usize> {
        let grid = self.height_field().grid();
        grid.cell_at(p).map(|c| c.iy * grid.nx() + c.ix)
    }

    /// The cell centres within `radius` of `c`, nearest first.
    pub fn cells_near(&self, c: Point2<f64>, radius: f64) -> Vec<Point2<f64>> {
        let grid = self.height_field().grid();
        let r = grid.resolution_m();
        let n = (radius / r).ceil() as i64;
        let centre = grid.nearest_cell(c);
        let mut out = Vec::new();
        for dy in -n..=n {
            for dx in -n..=n {
                let (ix, iy) = (centre.ix as i64 + dx, centre.iy as i64 + dy);
                if ix < 0 || iy < 0 || ix >= grid.nx() as i64 || iy >= grid.ny() as i64 {
                    continue;
                }
                let p = grid.cell_center(tca_robot::grid::CellIndex::new(ix as usize, iy as usize));
                if (p - c).norm() <= radius + 1e-9 {
                    out.push(p);
                }
            }
        }
        out.sort_by(|a, b| (a - c).norm().total_cmp(&(b - c).norm()));
        out
    }
}

/// A plane `z = height + slope_u * u + slope_v * v` over local coordinates `(u, v)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneFit {
    /// Height at the origin of the local coordinates, metres.
    pub height_m: f64,
    /// Rise per metre along `u`.
    pub slope_u: f64,
    /// Rise per metre along `v`.
    pub slope_v: f64,
}

/// A robust least-squares plane through samples `(u, v, z)`: iteratively reweighted least
/// squares with Tukey's biweight (tuning 4.685 times a scale from the median absolute
/// residual), starting from the ordinary fit. Outliers such as a stone or the top of a
/// wall that covers a small part of the samples pull the fit little. `None` with fewer
/// than three samples or when they lie on a line.
pub fn robust_plane(samples: &[(f64, f64, f64)]) -> Option<PlaneFit> {
    if samples.len() < 3 {
        return None;
    }
    let mut weights = vec![1.0; samples.len()];
    let mut fit = weighted_plane(samples, &weights)?;
    let mut residuals = vec![0.0; samples.len()];
    for _ in 0..8 {
        for (r, &(u, v, z)) in residuals.iter_mut().zip(samples) {
            *r = z - (fit.height_m + fit.slope_u * u + fit.slope_v * v);
        }
        let mut abs: Vec<f64> = residuals.iter().map(|r| r.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let mad = abs[abs.len() / 2];
        let scale = (mad / 0.6745).max(1e-4);
        let c = 4.685 * scale;
        for (w, r) in weights.iter_mut().zip(&residuals) {
            let t = r / c;
            *w = if t.abs() < 1.0 {
                (1.0 - t * t).powi(2)
            } else {
                0.0
            };
        }
        match weighted_plane(samples, &weights) {
            Some(next) => fit = next,
            None => break,
        }
    }
    Some(fit)
}

fn weighted_plane(samples: &[(f64, f64, f64)], weights: &[f64]) -> Option<PlaneFit> {
    let mut m = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for (&(u, v, z), &w) in samples.iter().zip(weights) {
        let row = Vector3::new(1.0, u, v);
        m += row * row.transpose() * w;
        rhs += row * (z * w);
    }
    let coef = m.lu().solve(&rhs)?;
    coef.iter().all(|c| c.is_finite()).then_some(PlaneFit {
        height_m: coef.x,
        slope_u: coef.y,
        slope_v: coef.z,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn field(f: impl Fn(f64, f64) -> f64) -> Arc<HeightField> {
        let (nx, ny, r) = (60, 40, 0.02);
        let mut h = Vec::new();
        for iy in 0..ny {
            for ix in 0..nx {
                h.push(f(ix as f64 * r, iy as f64 * r));
            }
        }
        Arc::new(HeightField::new(Point2::origin(), r, nx, ny, h).unwrap())
    }

    #[test]
    fn flat_ground_is_a_good_foothold_and_a_step_edge_is_forbidden() {
        let t = Terrain::new(field(|x, _| if x > 0.6 { 0.1 } else { 0.0 }), 0.012);
        assert_eq!(t.foothold_quality(Point2::new(0.3, 0.4)), 0.0);
        assert!(t.foothold_quality(Point2::new(0.6, 0.4)).is_infinite());
        // Next to the edge the cell itself may be fine but its neighbourhood is not.
        assert!(t.foothold_quality(Point2::new(0.62, 0.4)).is_infinite());
        assert_eq!(t.foothold_quality(Point2::new(0.9, 0.4)), 0.0);
        assert!(t.foothold_quality(Point2::new(5.0, 0.4)).is_infinite());
    }

    proptest! {
        #[test]
        fn max_in_disc_is_never_below_the_ground_in_the_disc(x in 0.0..1.2f64, y in 0.0..0.8f64, r in 0.0..0.2f64, a in 0.0..6.3f64, s in 0.0..1.0f64) {
            let t = Terrain::new(field(|x, y| (7.0 * x).sin() * 0.05 + (5.0 * y).cos() * 0.03 + if x > 0.6 { 0.1 } else { 0.0 }), 0.012);
            let c = Point2::new(x, y);
            let p = c + nalgebra::Vector2::new(a.cos(), a.sin()) * (r * s);
            let m = t.max_in_disc(c, r);
            prop_assert!(m >= t.height(p) - 1e-12);
            // And never above the highest sample within two cells more of the disc.
            prop_assert!(m <= t.height_field().max_height_in_disc(c, r + 0.2) + 1e-12);
        }
    }

    #[test]
    fn a_slope_costs_more_than_level_ground() {
        let t = Terrain::new(field(|x, _| 0.3 * x), 0.012);
        let q = t.foothold_quality(Point2::new(0.5, 0.4));
        assert!((q - 9.0 * 0.3).abs() < 1e-6, "{q}");
    }

    #[test]
    fn robust_plane_ignores_a_stone() {
        let mut s = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                let (u, v) = (f64::from(i) * 0.02, f64::from(j) * 0.02);
                let stone = if i < 2 && j < 2 { 0.1 } else { 0.0 };
                s.push((u, v, 0.1 * u - 0.05 * v + 0.2 + stone));
            }
        }
        let f = robust_plane(&s).unwrap();
        assert!((f.slope_u - 0.1).abs() < 1e-3, "{f:?}");
        assert!((f.slope_v + 0.05).abs() < 1e-3, "{f:?}");
        assert!((f.height_m - 0.2).abs() < 1e-3, "{f:?}");
        assert!(robust_plane(&s[..2]).is_none());
    }

    proptest! {
        #[test]
        fn robust_plane_recovers_any_exact_plane(a in -1.0..1.0f64, b in -1.0..1.0f64, c in -1.0..1.0f64) {
            let mut s = Vec::new();
            for i in 0..6 {
                for j in 0..5 {
                    let (u, v) = (f64::from(i) * 0.05 - 0.1, f64::from(j) * 0.04 - 0.1);
                    s.push((u, v, a + b * u + c * v));
                }
            }
            let f = robust_plane(&s).unwrap();
            prop_assert!((f.height_m - a).abs() < 1e-6);
            prop_assert!((f.slope_u - b).abs() < 1e-6);
            prop_assert!((f.slope_v - c).abs() < 1e-6);
        }
    }
}
