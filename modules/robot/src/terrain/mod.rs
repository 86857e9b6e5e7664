//! Terrain as a height field: heights sampled on a regular grid, bilinear in between.
//!
//! Heights are the [`Grid`] cells' values at the cell centres (world Z, metres). Between four
//! neighbouring samples the surface is the bilinear patch through them; outside the sampled
//! rectangle the surface continues the edge samples (clamped), except for ray casting, which
//! sees only the sampled rectangle.

mod raycast;

pub mod asc;

use nalgebra::{Point2, Vector3};

use crate::grid::{CellIndex, Grid, GridError};

pub use raycast::RayHit;

/// Why a height field could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TerrainError {
    /// The grid layout is not valid.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// Fewer than 2 x 2 samples: no surface between samples.
    #[error("a height field needs at least 2 x 2 samples, got {nx} x {ny}")]
    TooSmall {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
    /// The rectangle and resolution ask for too many samples.
    #[error(
        "a height field over {width_m} x {length_m} m at {resolution_m} m would need more than \
         {MAX_SAMPLES} samples; use a coarser resolution"
    )]
    TooLarge {
        /// Extent along X, metres.
        width_m: f64,
        /// Extent along Y, metres.
        length_m: f64,
        /// Resolution asked for, metres.
        resolution_m: f64,
    },
    /// A height is NaN or infinite.
    #[error("height at cell ({ix}, {iy}) is {value}, not a finite number")]
    NotFinite {
        /// Column.
        ix: usize,
        /// Row.
        iy: usize,
        /// The value.
        value: f64,
    },
}

/// A terrain surface: a grid of heights (world Z, metres) with bilinear interpolation, disc
/// queries for foot collision, and fast ray casting for the laser scanners.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightField {
    grid: Grid<f64>,
    min_m: f64,
    max_m: f64,
    mip: raycast::MaxMip,
}

impl HeightField {
    /// A height field from a grid of heights.
    pub fn from_grid(grid: Grid<f64>) -> Result<Self, TerrainError> {
        if grid.nx() < 2 || grid.ny() < 2 {
            return Err(TerrainError::TooSmall {
                nx: grid.nx(),
                ny: grid.ny(),
            });
        }
        let mut min_m = f64::INFINITY;
        let mut max_m = f64::NEG_INFINITY;
        for (c, &h) in grid.iter() {
            if !h.is_finite() {
                return Err(TerrainError::NotFinite {
                    ix: c.ix,
                    iy: c.iy,
                    value: h,
                });
            }
            min_m = min_m.min(h);
            max_m = max_m.max(h);
        }
        let mip = raycast::MaxMip::build(&grid);
        Ok(Self {
            grid,
            min_m,
            max_m,
            mip,
        })
    }

    /// A height field from row-major heights (`heights[iy * nx + ix]`), sample (0, 0) at
    /// `origin`.
    pub fn new(
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
        heights: Vec<f64>,
    ) -> Result<Self, TerrainError> {
        Self::from_grid(Grid::from_vec(origin, resolution_m, nx, ny, heights)?)
    }

    /// A level surface at `height_m` with samples covering `[min, max]` (rounded outward
    /// to whole cells).
    pub fn flat(
        min: Point2<f64>,
        max: Point2<f64>,
        resolution_m: f64,
        height_m: f64,
    ) -> Result<Self, TerrainError> {
        let (nx, ny) = samples_covering(min, max, resolution_m)?;
        Self::from_grid(Grid::filled(min, resolution_m, nx, ny, height_m)?)
    }

    /// The height samples.
    pub fn grid(&self) -> &Grid<f64> {
        &self.grid
    }

    /// Lowest sample, metres.
    pub fn min_height_m(&self) -> f64 {
        self.min_m
    }

    /// Highest sample, metres.
    pub fn max_height_m(&self) -> f64 {
        self.max_m
    }

    /// The sampled rectangle: (min corner, max corner) through the outermost samples.
    pub fn extent(&self) -> (Point2<f64>, Point2<f64>) {
        let o = self.grid.origin();
        let r = self.grid.resolution_m();
        (
            o,
            Point2::new(
                o.x + (self.grid.nx() - 1) as f64 * r,
                o.y + (self.grid.ny() - 1) as f64 * r,
            ),
        )
    }

    /// Patch containing grid coordinates (clamped) and the local coordinates in it.
    fn patch_at(&self, x: f64, y: f64) -> (usize, usize, f64, f64) {
        let (gx, gy) = self.grid.world_to_grid(Point2::new(x, y));
        let clamp = |g: f64, n: usize| -> (usize, f64) {
            let g = if g.is_nan() {
                0.0
            } else {
                g.clamp(0.0, (n - 1) as f64)
            };
            // Truncation is the floor here (g >= 0) and much cheaper than `floor`.
            let i = (g as usize).min(n - 2);
            (i, g - i as f64)
        };
        let (ix, u) = clamp(gx, self.grid.nx());
        let (iy, v) = clamp(gy, self.grid.ny());
        (ix, iy, u, v)
    }

    fn corners(&self, ix: usize, iy: usize) -> [f64; 4] {
        let nx = self.grid.nx();
        let h = self.grid.cells();
        let i = iy * nx + ix;
        // ix <= nx - 2 and iy <= ny - 2 by construction of patch_at and the ray caster.
        [h[i], h[i + 1], h[i + nx], h[i + nx + 1]]
    }

    /// Height of the surface at world (x, y), metres (bilinear; edge-clamped outside).
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        let (ix, iy, u, v) = self.patch_at(x, y);
        let [h00, h10, h01, h11] = self.corners(ix, iy);
        let a = h00 + (h10 - h00) * u;
        let b = h01 + (h11 - h01) * u;
        a + (b - a) * v
    }

    /// Upward unit normal of the surface at world (x, y).
    pub fn normal_at(&self, x: f64, y: f64) -> Vector3<f64> {
        let (ix, iy, u, v) = self.patch_at(x, y);
        self.patch_normal(ix, iy, u, v)
    }

    fn patch_normal(&self, ix: usize, iy: usize, u: f64, v: f64) -> Vector3<f64> {
        let [h00, h10, h01, h11] = self.corners(ix, iy);
        let r = self.grid.resolution_m();
        let dhdx = ((h10 - h00) * (1.0 - v) + (h11 - h01) * v) / r;
        let dhdy = ((h01 - h00) * (1.0 - u) + (h11 - h10) * u) / r;
        Vector3::new(-dhdx, -dhdy, 1.0).normalize()
    }

    /// Highest point of the surface over a disc (the foot's footprint), metres.
    ///
    /// Inside a bilinear patch the surface has no strict interior maximum, so the maximum
    /// over the disc is at a sample inside it or on its rim; the rim is sampled at half the
    /// grid resolution, which bounds the error by the surface's rise over a quarter cell.
    pub fn max_height_in_disc(&self, center: Point2<f64>, radius_m: f64) -> f64 {
        let mut best = self.height_at(center.x, center.y);
        if radius_m.is_nan() || radius_m <= 0.0 || !radius_m.is_finite() {
            return best;
        }
        let r = self.grid.resolution_m();
        let r2 = radius_m * radius_m;
        let lo = Point2::new(center.x - radius_m, center.y - radius_m);
        let hi = Point2::new(center.x + radius_m, center.y + radius_m);
        if let Some((xs, ys)) = self.grid.cell_range(lo, hi) {
            let nx = self.grid.nx();
            let h = self.grid.cells();
            for iy in ys {
                let cy = self.grid.origin().y + iy as f64 * r - center.y;
                let row = iy * nx;
                for ix in xs.clone() {
                    let cx = self.grid.origin().x + ix as f64 * r - center.x;
                    if cx * cx + cy * cy <= r2
                        && let Some(&v) = h.get(row + ix)
                    {
                        best = best.max(v);
                    }
                }
            }
        }
        // The rim: sample it every half cell. Between two samples the surface can rise
        // above both by at most the local slope times half the arc, and never above the
        // highest sample around the arc; only arcs whose bound beats the best so far are
        // searched (golden section), so a steep face or a box corner clipped by the rim
        // is found to a fraction of a millimetre while flat ground costs no search.
        let n = ((std::f64::consts::TAU * radius_m / (0.5 * r)).ceil() as usize).clamp(16, 4096);
        let step = std::f64::consts::TAU / n as f64;
        let rim = |a: f64| {
            let (s, c) = a.sin_cos();
            self.height_at(center.x + radius_m * c, center.y + radius_m * s)
        };
        // Rim directions by rotating a unit vector (no trigonometry per sample).
        let (turn_s, turn_c) = step.sin_cos();
        let (half_s, half_c) = (0.5 * step).sin_cos();
        let mut heights = Vec::with_capacity(n);
        let mut mids = Vec::with_capacity(n);
        let (mut c, mut s) = (1.0_f64, 0.0_f64);
        for _ in 0..n {
            heights.push(self.height_at(center.x + radius_m * c, center.y + radius_m * s));
            let (mc, ms) = (c * half_c - s * half_s, s * half_c + c * half_s);
            mids.push(Point2::new(
                center.x + radius_m * mc,
                center.y + radius_m * ms,
            ));
            (c, s) = (c * turn_c - s * turn_s, s * turn_c + c * turn_s);
        }
        for &h in &heights {
            best = best.max(h);
        }
        let half_arc = 0.5 * radius_m * step;
        for k in 0..n {
            let (h0, h1) = (heights[k], heights[(k + 1) % n]);
            let (top, bottom) = self.samples_around(mids[k]);
            let slope = std::f64::consts::SQRT_2 * (top - bottom) / r;
            let bound = top.min(h0.max(h1) + slope * half_arc);
            if bound > best + RIM_TOLERANCE_M {
                best = best.max(golden_max(&rim, step * k as f64, step * (k + 1) as f64));
            }
        }
        best
    }

    /// Highest and lowest of the 3 x 3 samples around the sample nearest to `p`: bounds of
    /// the surface within a cell of that sample.
    fn samples_around(&self, p: Point2<f64>) -> (f64, f64) {
        let (nx, ny) = (self.grid.nx(), self.grid.ny());
        let (gx, gy) = self.grid.world_to_grid(p);
        let nearest = |g: f64, n: usize| {
            if g + 0.5 >= 0.0 {
                ((g + 0.5) as usize).min(n - 1)
            } else {
                0
            }
        };
        let c = CellIndex::new(nearest(gx, nx), nearest(gy, ny));
        let h = self.grid.cells();
        let (mut top, mut bottom) = (f64::NEG_INFINITY, f64::INFINITY);
        for iy in c.iy.saturating_sub(1)..=(c.iy + 1).min(ny - 1) {
            for ix in c.ix.saturating_sub(1)..=(c.ix + 1).min(nx - 1) {
                if let Some(&v) = h.get(iy * nx + ix) {
                    top = top.max(v);
                    bottom = bottom.min(v);
                }
            }
        }
        (top, bottom)
    }

    /// Height of sample `c`, if in the grid.
    pub fn sample(&self, c: CellIndex) -> Option<f64> {
        self.grid.get(c).copied()
    }
}

/// How much above the best value found an unsearched rim arc may be, metres.
const RIM_TOLERANCE_M: f64 = 2e-4;

/// Largest value of `f` on `[lo, hi]` found by a golden-section search (exact for a function
/// with one local maximum there; otherwise a local maximum).
fn golden_max(f: &impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    const INV_PHI: f64 = 0.618_033_988_749_895;
    let mut a = hi - INV_PHI * (hi - lo);
    let mut b = lo + INV_PHI * (hi - lo);
    let (mut fa, mut fb) = (f(a), f(b));
    for _ in 0..24 {
        if fa < fb {
            lo = a;
            (a, fa) = (b, fb);
            b = lo + INV_PHI * (hi - lo);
            fb = f(b);
        } else {
            hi = b;
            (b, fb) = (a, fa);
            a = hi - INV_PHI * (hi - lo);
            fa = f(a);
        }
    }
    fa.max(fb).max(f(lo)).max(f(hi))
}

/// Most samples [`HeightField::flat`] and course rendering will allocate.
pub const MAX_SAMPLES: usize = 100_000_000;

/// Number of samples (nx, ny) at `resolution_m` covering `[min, max]` with sample 0 at `min`.
pub(crate) fn samples_covering(
    min: Point2<f64>,
    max: Point2<f64>,
    resolution_m: f64,
) -> Result<(usize, usize), TerrainError> {
    if !(resolution_m.is_finite() && resolution_m > 0.0) {
        return Err(GridError::BadResolution(resolution_m).into());
    }
    let count = |lo: f64, hi: f64| ((hi - lo) / resolution_m - 1e-9).ceil().max(1.0) + 1.0;
    let (nx, ny) = (count(min.x, max.x), count(min.y, max.y));
    if !(nx.is_finite() && ny.is_finite()) || nx * ny > MAX_SAMPLES as f64 {
        return Err(TerrainError::TooLarge {
            width_m: max.x - min.x,
            length_m: max.y - min.y,
            resolution_m,
        });
    }
    Ok((nx as usize, ny as usize))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> HeightField {
        // h = 0.1 x + 0.2 y on a 1 m grid, 5 x 4 samples.
        HeightField::from_grid(
            Grid::from_fn(Point2::new(0.0, 0.0), 1.0, 5, 4, |_, p| {
                0.1 * p.x + 0.2 * p.y
            })
            .unwrap(),
        )
        .unwrap()
    }

    #[test]
    fn bilinear_reproduces_a_plane_and_clamps_outside() {
        let t = ramp();
        assert!((t.height_at(2.3, 1.7) - (0.23 + 0.34)).abs() < 1e-12);
        assert!((t.height_at(-5.0, 1.0) - 0.2).abs() < 1e-12);
        assert!((t.height_at(10.0, 10.0) - (0.4 + 0.6)).abs() < 1e-12);
        let n = t.normal_at(1.5, 1.5);
        let expect = Vector3::new(-0.1, -0.2, 1.0).normalize();
        assert!((n - expect).norm() < 1e-12);
        assert_eq!((t.min_height_m(), t.max_height_m()), (0.0, 1.0));
    }

    #[test]
    fn disc_maximum_sees_a_single_high_sample_and_the_rim() {
        let mut g = Grid::filled(Point2::origin(), 0.02, 50, 50, 0.0).unwrap();
        *g.get_mut(CellIndex::new(25, 25)).unwrap() = 0.3;
        let t = HeightField::from_grid(g).unwrap();
        // Sample at (0.5, 0.5): inside a disc of 0.15 m radius centred 0.14 m away.
        assert!((t.max_height_in_disc(Point2::new(0.36, 0.5), 0.15) - 0.3).abs() < 1e-12);
        // Centred 0.16 m away: only the rim reaches the bump's slope (which ends at 0.52).
        assert_eq!(t.max_height_in_disc(Point2::new(0.5, 0.69), 0.15), 0.0);
        let rim = t.max_height_in_disc(Point2::new(0.5, 0.655), 0.15);
        assert!(rim > 0.0 && rim < 0.3, "{rim}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// The disc maximum matches a dense search (every sample inside plus 20 000 rim
        /// points) on terrain with spikes and box-like steps.
        #[test]
        fn disc_maximum_matches_a_dense_search(seed in 0u64..10_000, cx in 0.3f64..0.7, cy in 0.3f64..0.7) {
            let g = Grid::from_fn(Point2::origin(), 0.02, 51, 51, |c, _| {
                let k = (c.ix as u64 * 7919 + c.iy as u64 * 104_729 + seed * 31) % 1000;
                if k < 15 { 0.7 } else { 0.01 * (k % 7) as f64 }
            })
            .unwrap();
            let t = HeightField::from_grid(g).unwrap();
            let center = Point2::new(cx, cy);
            let fast = t.max_height_in_disc(center, 0.15);
            let mut dense = t.height_at(cx, cy);
            for (c, &h) in t.grid().iter() {
                if (t.grid().cell_center(c) - center).norm() <= 0.15 {
                    dense = dense.max(h);
                }
            }
            for k in 0..20_000 {
                let a = std::f64::consts::TAU * k as f64 / 20_000.0;
                dense = dense.max(t.height_at(cx + 0.15 * a.cos(), cy + 0.15 * a.sin()));
            }
            // The dense rim is itself off by up to ~0.8 mm on the 35:1 spike flanks.
            proptest::prop_assert!((fast - dense).abs() <= 1e-3, "fast {fast}, dense {dense}");
        }
    }

    #[test]
    fn refuses_bad_heights() {
        let err = HeightField::new(Point2::origin(), 1.0, 2, 2, vec![0.0, f64::NAN, 0.0, 0.0])
            .unwrap_err();
        assert!(matches!(err, TerrainError::NotFinite { ix: 1, iy: 0, .. }));
        assert!(matches!(
            HeightField::new(Point2::origin(), 1.0, 1, 2, vec![0.0, 0.0]),
            Err(TerrainError::TooSmall { .. })
        ));
    }

    #[test]
    fn flat_covers_the_rectangle() {
        let t = HeightField::flat(Point2::origin(), Point2::new(6.0, 11.0), 0.02, 0.0).unwrap();
        assert_eq!((t.grid().nx(), t.grid().ny()), (301, 551));
        let (lo, hi) = t.extent();
        assert!((hi.x - 6.0).abs() < 1e-9 && (hi.y - 11.0).abs() < 1e-9 && lo == Point2::origin());
    }
}
