//! The footfall, filtered footfall and clear-region maps (§6.2.1, §8.2), from the LTM
//! Manager's footfall statistic (metres of deviation from a plane under the foot).

use tca_lrp::TerrainGrid;
use tca_robot::Grid;

use crate::params::FootfallParams;
use crate::region::StepRegion;

/// A map sampled at the region's cell centres, padded by `pad` cells on every side.
pub(crate) struct Padded<T> {
    nx: usize,
    pad: usize,
    values: Vec<T>,
}

impl<T: Copy> Padded<T> {
    /// Samples `f(map value at the centre)` over the padded grid.
    pub(crate) fn sample(
        region: &StepRegion,
        map: &TerrainGrid,
        pad: usize,
        f: impl Fn(tca_lrp::MapValue) -> T,
    ) -> Self {
        let g = &region.layout;
        let (nx, ny) = (g.nx() + 2 * pad, g.ny() + 2 * pad);
        let r = g.resolution_m();
        let o = g.origin();
        let mut values = Vec::with_capacity(nx * ny);
        for iy in 0..ny {
            for ix in 0..nx {
                let p = nalgebra::Point2::new(
                    o.x + (ix as f64 - pad as f64) * r,
                    o.y + (iy as f64 - pad as f64) * r,
                );
                values.push(f(map.value_at(p)));
            }
        }
        Self { nx, pad, values }
    }

    /// The same layout with every value mapped.
    pub(crate) fn map<U>(&self, f: impl Fn(T) -> U) -> Padded<U> {
        Padded {
            nx: self.nx,
            pad: self.pad,
            values: self.values.iter().map(|&v| f(v)).collect(),
        }
    }

    /// The value at region cell `(ix, iy)` offset by `(dx, dy)` cells (within the padding).
    pub(crate) fn at(&self, ix: usize, iy: usize, dx: isize, dy: isize) -> Option<T> {
        let x = (ix + self.pad).checked_add_signed(dx)?;
        let y = (iy + self.pad).checked_add_signed(dy)?;
        if x >= self.nx {
            return None;
        }
        self.values.get(y * self.nx + x).copied()
    }
}

/// Cell offsets within `radius_m` on a grid of `resolution_m`, with their distances.
pub(crate) fn offsets_within(radius_m: f64, resolution_m: f64) -> Vec<(isize, isize, f64)> {
    let n = (radius_m / resolution_m + 1e-9).floor() as isize;
    let mut out = Vec::new();
    for dy in -n..=n {
        for dx in -n..=n {
            let d = resolution_m * (dx as f64).hypot(dy as f64);
            if d <= radius_m + 1e-9 {
                out.push((dx, dy, d));
            }
        }
    }
    out
}

/// The graded footfall cost at every cell (0 flat .. 1 at `worst_m` and above); `None`
/// where the statistic is unknown.
pub(crate) fn footfall_cost(
    region: &StepRegion,
    statistic: &Padded<Option<f64>>,
    params: &FootfallParams,
) -> Grid<Option<f64>> {
    let mut g = region.grid_of(None);
    let nx = region.layout.nx();
    for (i, v) in g.cells_mut().iter_mut().enumerate() {
        *v = statistic
            .at(i % nx, i / nx, 0, 0)
            .flatten()
            .map(|s| (s.max(0.0) / params.worst_m).min(1.0));
    }
    g
}

/// The filtered footfall map: the greatest footfall cost within `radius_m`, each weighted
/// by `scale / (scale + distance)`; unknown neighbours cost 1.
pub(crate) fn filtered_footfall(
    region: &StepRegion,
    statistic: &Padded<Option<f64>>,
    worst_m: f64,
    radius_m: f64,
    distance_scale_m: f64,
) -> Grid<f64> {
    let offsets: Vec<(isize, isize, f64)> = offsets_within(radius_m, region.layout.resolution_m())
        .into_iter()
        .map(|(dx, dy, d)| (dx, dy, distance_scale_m / (distance_scale_m + d)))
        .collect();
    // The cost of every padded cell once (unknown costs 1), then a weighted maximum.
    let costs = statistic.map(|v| match v {
        Some(s) => (s.max(0.0) / worst_m).min(1.0),
        None => 1.0,
    });
    let nx = region.layout.nx();
    let mut g = region.grid_of(0.0);
    for (i, v) in g.cells_mut().iter_mut().enumerate() {
        let (ix, iy) = (i % nx, i / nx);
        let mut top: f64 = 0.0;
        for &(dx, dy, w) in &offsets {
            top = top.max(costs.at(ix, iy, dx, dy).unwrap_or(1.0) * w);
        }
        *v = top;
    }
    g
}

/// The clear-region map: `true` where every footfall statistic within
/// `clear_radius - foot_radius` is known and at most `clear_max_m` (so the union of the
/// flat foot discs covers the clear disc) and the elevation within the clear radius is known.
pub(crate) fn clear_region(
    region: &StepRegion,
    statistic: &Padded<Option<f64>>,
    elevation_known: &Padded<bool>,
    params: &FootfallParams,
    foot_radius_m: f64,
) -> Grid<bool> {
    let res = region.layout.resolution_m();
    let clear_radius = 0.5 * params.clear_diameter_m;
    let flat = offsets_within((clear_radius - foot_radius_m).max(0.0), res);
    let seen = offsets_within(clear_radius, res);
    let nx = region.layout.nx();
    let mut g = region.grid_of(false);
    for (i, v) in g.cells_mut().iter_mut().enumerate() {
        let (ix, iy) = (i % nx, i / nx);
        *v = flat.iter().all(|&(dx, dy, _)| {
            statistic
                .at(ix, iy, dx, dy)
                .flatten()
                .is_some_and(|s| s <= params.clear_max_m)
        }) && seen
            .iter()
            .all(|&(dx, dy, _)| elevation_known.at(ix, iy, dx, dy).unwrap_or(false));
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_form_a_disc() {
        let o = offsets_within(0.2, 0.1);
        assert_eq!(o.len(), 13);
        assert!(o.iter().all(|&(_, _, d)| d <= 0.2 + 1e-9));
        assert_eq!(offsets_within(0.0, 0.1).len(), 1);
    }
}
