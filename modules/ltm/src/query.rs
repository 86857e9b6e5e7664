//! Region queries (§5.2.2) and their cache.
//!
//! A query's grid lies on the lattice of its resolution (see [`crate::region`]); each cell's
//! value is that of its mid-point: the elevation is interpolated bilinearly between the four
//! surrounding map cells when all four are known (otherwise the nearest map cell's state and
//! value are used), and the footfall cost and slope are evaluated for the foot centred there
//! ([`crate::footfall`]).
//!
//! # Cache
//!
//! Computed cells are kept per (elevation or foot, resolution) in tiles of 32 x 32 query
//! cells, so a later request for the same or an overlapping region at the same resolution
//! computes only the cells it has not seen before. Merging an image invalidates the tiles
//! within reach of the cells it changed (the foot's radius around them). When the cache holds
//! more than its limit of cells it is emptied.

use std::collections::HashMap;

use nalgebra::Point2;
use tca_single_leg_messages::{MapCell, MapGrid, MapKind};

use crate::cell::{Cell, CellState};
use crate::error::Result;
use crate::footfall::{FootEvaluator, FootParams, Footing};
use crate::patch::{Patch, lattice_index};
use crate::region::Region;
use crate::scroller::TileStore;

/// Query cells per cache tile side.
const CACHE_SIDE: i64 = 32;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct CacheKey {
    res_bits: u64,
    tx: i64,
    ty: i64,
}

#[derive(Debug, Clone)]
struct CacheTile<T> {
    cells: Vec<Option<T>>,
}

/// How much work the cache saved.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CacheStats {
    /// Cells computed.
    pub computed: u64,
    /// Cells served from the cache.
    pub reused: u64,
    /// Times the cache was emptied for being full.
    pub evictions: u64,
}

/// The cache of computed query cells.
#[derive(Debug)]
pub struct QueryCache {
    elevation: HashMap<CacheKey, CacheTile<Cell>>,
    foot: HashMap<CacheKey, CacheTile<Footing>>,
    max_cells: usize,
    stats: CacheStats,
}

impl QueryCache {
    /// A cache holding at most about `max_cells` cells.
    pub fn new(max_cells: usize) -> Self {
        Self {
            elevation: HashMap::new(),
            foot: HashMap::new(),
            max_cells,
            stats: CacheStats::default(),
        }
    }

    /// What the cache saved so far.
    pub fn stats(&self) -> CacheStats {
        self.stats
    }

    /// Cells held.
    pub fn cells(&self) -> usize {
        (self.elevation.len() + self.foot.len()) * (CACHE_SIDE * CACHE_SIDE) as usize
    }

    /// Empties the cache.
    pub fn clear(&mut self) {
        self.elevation.clear();
        self.foot.clear();
    }

    /// Drops the cached cells whose values may depend on map cells in the world rectangle
    /// `[min, max]` widened by `margin_m`.
    pub fn invalidate(&mut self, min: Point2<f64>, max: Point2<f64>, margin_m: f64) {
        let hit = |key: &CacheKey| {
            let res = f64::from_bits(key.res_bits);
            let side = CACHE_SIDE as f64 * res;
            let lo_x = (key.tx as f64 * CACHE_SIDE as f64 - 0.5) * res;
            let lo_y = (key.ty as f64 * CACHE_SIDE as f64 - 0.5) * res;
            let m = margin_m + res;
            lo_x < max.x + m
                && lo_x + side > min.x - m
                && lo_y < max.y + m
                && lo_y + side > min.y - m
        };
        self.elevation.retain(|k, _| !hit(k));
        self.foot.retain(|k, _| !hit(k));
    }
}

/// Answers a region query of `kind` from the map in `store`, using and filling `cache`.
pub fn answer(
    region: &Region,
    kind: MapKind,
    store: &TileStore,
    cache: &mut QueryCache,
    foot: &FootParams,
) -> Result<MapGrid> {
    let layout = region.layout();
    let res = region.resolution_m();
    let mut cells = vec![MapCell::Unknown; layout.nx * layout.ny];
    if cache.cells() > cache.max_cells {
        cache.clear();
        cache.stats.evictions += 1;
    }
    let foot_kind = matches!(kind, MapKind::Footfall | MapKind::Slope);
    let margin = if foot_kind {
        foot.radius_m.max(1.5 * store.resolution_m()) + store.resolution_m()
    } else {
        store.resolution_m()
    };
    let mut evaluator = FootEvaluator::new();
    let (i_end, j_end) = (layout.i0 + layout.nx as i64, layout.j0 + layout.ny as i64);
    for ty in layout.j0.div_euclid(CACHE_SIDE)..=(j_end - 1).div_euclid(CACHE_SIDE) {
        for tx in layout.i0.div_euclid(CACHE_SIDE)..=(i_end - 1).div_euclid(CACHE_SIDE) {
            let key = CacheKey {
                res_bits: res.to_bits(),
                tx,
                ty,
            };
            let (ia, ib) = (
                (tx * CACHE_SIDE).max(layout.i0),
                ((tx + 1) * CACHE_SIDE).min(i_end),
            );
            let (ja, jb) = (
                (ty * CACHE_SIDE).max(layout.j0),
                ((ty + 1) * CACHE_SIDE).min(j_end),
            );
            // The cells of this tile the polygon needs.
            let wanted: Vec<(i64, i64)> = (ja..jb)
                .flat_map(|j| (ia..ib).map(move |i| (i, j)))
                .filter(|&(i, j)| region.contains(region.center(i, j)))
                .collect();
            if wanted.is_empty() {
                continue;
            }
            let local = |i: i64, j: i64| {
                ((j - ty * CACHE_SIDE) * CACHE_SIDE + (i - tx * CACHE_SIDE)) as usize
            };
            let out =
                |i: i64, j: i64| (j - layout.j0) as usize * layout.nx + (i - layout.i0) as usize;
            let base = |store: &TileStore| -> Result<Patch> {
                let lo = region.center(ia, ja);
                let hi = region.center(ib - 1, jb - 1);
                let r = store.resolution_m();
                let (bi0, bj0) = (
                    lattice_index(lo.x - margin, r),
                    lattice_index(lo.y - margin, r),
                );
                let (bi1, bj1) = (
                    lattice_index(hi.x + margin, r),
                    lattice_index(hi.y + margin, r),
                );
                store.extract(bi0, bj0, (bi1 - bi0 + 1) as usize, (bj1 - bj0 + 1) as usize)
            };
            if foot_kind {
                let tile = cache.foot.entry(key).or_insert_with(empty_tile);
                let mut patch: Option<Patch> = None;
                for &(i, j) in &wanted {
                    let slot = &mut tile.cells[local(i, j)];
                    let footing = match slot {
                        Some(f) => {
                            cache.stats.reused += 1;
                            *f
                        }
                        None => {
                            if patch.is_none() {
                                patch = Some(base(store)?);
                            }
                            let Some(p) = patch.as_ref() else { continue };
                            let f = evaluator.evaluate(p, region.center(i, j), foot);
                            cache.stats.computed += 1;
                            *slot = Some(f);
                            f
                        }
                    };
                    cells[out(i, j)] = footing_cell(footing, kind);
                }
            } else {
                let tile = cache.elevation.entry(key).or_insert_with(empty_tile);
                let mut patch: Option<Patch> = None;
                for &(i, j) in &wanted {
                    let slot = &mut tile.cells[local(i, j)];
                    let cell = match slot {
                        Some(c) => {
                            cache.stats.reused += 1;
                            *c
                        }
                        None => {
                            if patch.is_none() {
                                patch = Some(base(store)?);
                            }
                            let Some(p) = patch.as_ref() else { continue };
                            let c = sample_elevation(p, region.center(i, j));
                            cache.stats.computed += 1;
                            *slot = Some(c);
                            c
                        }
                    };
                    cells[out(i, j)] = cell.to_wire();
                }
            }
        }
    }
    Ok(MapGrid {
        kind,
        origin_x_m: layout.i0 as f64 * res,
        origin_y_m: layout.j0 as f64 * res,
        resolution_m: res,
        nx: layout.nx as u32,
        ny: layout.ny as u32,
        cells,
    })
}

fn empty_tile<T: Clone>() -> CacheTile<T> {
    CacheTile {
        cells: vec![None; (CACHE_SIDE * CACHE_SIDE) as usize],
    }
}

fn footing_cell(f: Footing, kind: MapKind) -> MapCell {
    match f {
        Footing::Unknown => MapCell::Unknown,
        Footing::Occluded { max_elevation_m } => MapCell::Occluded { max_elevation_m },
        Footing::Known {
            cost_m,
            slope_rad,
            sigma_m,
        } => MapCell::Known {
            value: if kind == MapKind::Slope {
                slope_rad as f32
            } else {
                cost_m as f32
            },
            sigma_m: sigma_m as f32,
        },
    }
}

/// The elevation at a point: bilinear between the four surrounding cells when all are known,
/// else the nearest cell.
pub fn sample_elevation(patch: &Patch, p: Point2<f64>) -> Cell {
    let res = patch.resolution_m;
    let nearest = patch.at(p);
    if nearest.state != CellState::Known {
        return nearest;
    }
    let (gx, gy) = (p.x / res, p.y / res);
    let (fi, fj) = (gx.floor(), gy.floor());
    let (tx, ty) = ((gx - fi) as f32, (gy - fj) as f32);
    let (i, j) = (fi as i64, fj as i64);
    let c = [
        patch.get(i, j),
        patch.get(i + 1, j),
        patch.get(i, j + 1),
        patch.get(i + 1, j + 1),
    ];
    if c.iter().any(|c| c.state != CellState::Known) {
        return nearest;
    }
    let mix = |f: fn(&Cell) -> f32| {
        let bottom = f(&c[0]) * (1.0 - tx) + f(&c[1]) * tx;
        let top = f(&c[2]) * (1.0 - tx) + f(&c[3]) * tx;
        bottom * (1.0 - ty) + top * ty
    };
    Cell::known(mix(|c| c.elevation_m), mix(|c| c.sigma_m))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_interpolates_known_cells_and_keeps_others() {
        let mut p = Patch::unknown(0, 0, 3, 3, 1.0);
        for (k, c) in p.cells.iter_mut().enumerate() {
            *c = Cell::known(k as f32, 0.1);
        }
        let s = sample_elevation(&p, Point2::new(0.5, 0.5));
        assert!((s.elevation_m - 2.0).abs() < 1e-6, "{s:?}");
        assert_eq!(
            sample_elevation(&p, Point2::new(1.0, 1.0)),
            Cell::known(4.0, 0.1)
        );
        *p.get_mut(1, 1).unwrap() = Cell::occluded(9.0);
        assert_eq!(
            sample_elevation(&p, Point2::new(1.1, 0.9)),
            Cell::occluded(9.0)
        );
        // Next to an occluded cell: the nearest known cell's value.
        assert_eq!(
            sample_elevation(&p, Point2::new(0.4, 0.4)),
            Cell::known(0.0, 0.1)
        );
    }
}
