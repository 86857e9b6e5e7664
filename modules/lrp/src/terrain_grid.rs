//! Terrain maps as the planners see them: a [`Grid`] of [`MapValue`]s (known with an
//! uncertainty, occluded with an upper bound, or unknown), converted from and to the LTM
//! Manager's wire type [`MapGrid`], or built straight from a height field for tests and
//! offline runs.
//!
//! [`ObstacleHeights`] turns an elevation map into conservative obstacle heights: known
//! cells raised by their uncertainty, occluded cells at their greatest possible elevation,
//! unknown cells (and everything off the map) at a configurable height.

use nalgebra::Point2;
use tca_robot::{CellIndex, Grid, HeightField};
use tca_single_leg_messages::{MapCell, MapGrid, MapKind};

use crate::error::{PlanError, Result};

/// One cell of a terrain map, in the planners' units (f64).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MapValue {
    /// Never seen, or outside the region asked for.
    Unknown,
    /// Hidden from the scanner; the terrain is at most this high.
    Occluded {
        /// Greatest possible elevation, metres.
        max_elevation_m: f64,
    },
    /// Seen.
    Known {
        /// The map's value (elevation in metres, footfall cost, slope in radians).
        value: f64,
        /// Uncertainty of the elevation there (standard deviation), metres.
        sigma_m: f64,
    },
}

impl MapValue {
    /// From the wire cell; non-finite numbers become [`MapValue::Unknown`].
    pub fn from_cell(cell: &MapCell) -> Self {
        match *cell {
            MapCell::Unknown => MapValue::Unknown,
            MapCell::Occluded { max_elevation_m } if max_elevation_m.is_finite() => {
                MapValue::Occluded {
                    max_elevation_m: f64::from(max_elevation_m),
                }
            }
            MapCell::Known { value, sigma_m } if value.is_finite() && sigma_m.is_finite() => {
                MapValue::Known {
                    value: f64::from(value),
                    sigma_m: f64::from(sigma_m).max(0.0),
                }
            }
            _ => MapValue::Unknown,
        }
    }

    /// To the wire cell (f32).
    pub fn to_cell(&self) -> MapCell {
        match *self {
            MapValue::Unknown => MapCell::Unknown,
            MapValue::Occluded { max_elevation_m } => MapCell::Occluded {
                max_elevation_m: max_elevation_m as f32,
            },
            MapValue::Known { value, sigma_m } => MapCell::Known {
                value: value as f32,
                sigma_m: sigma_m as f32,
            },
        }
    }

    /// The value when known.
    pub fn known(&self) -> Option<f64> {
        match *self {
            MapValue::Known { value, .. } => Some(value),
            _ => None,
        }
    }
}

/// A terrain map of one kind over a world XY grid.
#[derive(Debug, Clone, PartialEq)]
pub struct TerrainGrid {
    kind: MapKind,
    grid: Grid<MapValue>,
}

impl TerrainGrid {
    /// A map from a grid of values.
    pub fn new(kind: MapKind, grid: Grid<MapValue>) -> Self {
        Self { kind, grid }
    }

    /// From the LTM Manager's wire map; refused when its size does not match its cells.
    pub fn from_map_grid(map: &MapGrid) -> Result<Self> {
        let bad = |reason: String| PlanError::BadMap {
            what: kind_name(map.kind),
            reason,
        };
        let (nx, ny) = (map.nx as usize, map.ny as usize);
        let cells = map.cells.iter().map(MapValue::from_cell).collect();
        let grid = Grid::from_vec(
            Point2::new(map.origin_x_m, map.origin_y_m),
            map.resolution_m,
            nx,
            ny,
            cells,
        )
        .map_err(|e| bad(e.to_string()))?;
        Ok(Self {
            kind: map.kind,
            grid,
        })
    }

    /// To the wire map.
    pub fn to_map_grid(&self) -> MapGrid {
        let o = self.grid.origin();
        MapGrid {
            kind: self.kind,
            origin_x_m: o.x,
            origin_y_m: o.y,
            resolution_m: self.grid.resolution_m(),
            nx: u32::try_from(self.grid.nx()).unwrap_or(u32::MAX),
            ny: u32::try_from(self.grid.ny()).unwrap_or(u32::MAX),
            cells: self.grid.cells().iter().map(MapValue::to_cell).collect(),
        }
    }

    /// An elevation map of the rectangle `[min, max]` straight from a height field (what a
    /// perfect LTM Manager would serve): each cell holds the highest terrain over its square,
    /// known with zero uncertainty; cells off the height field are unknown.
    pub fn elevation_from_height_field(
        terrain: &HeightField,
        min: Point2<f64>,
        max: Point2<f64>,
        resolution_m: f64,
    ) -> Result<Self> {
        let bad = |reason: String| PlanError::BadMap {
            what: "elevation",
            reason,
        };
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(bad(format!("resolution {resolution_m} m is not positive")));
        }
        let count = |lo: f64, hi: f64| ((hi - lo) / resolution_m).ceil().max(1.0);
        let (nx, ny) = (count(min.x, max.x), count(min.y, max.y));
        if !(nx.is_finite() && ny.is_finite()) || nx * ny > 4.0e7 {
            return Err(bad(format!(
                "{nx} x {ny} cells is too many; use a coarser resolution"
            )));
        }
        let half = 0.5 * resolution_m;
        let origin = Point2::new(min.x + half, min.y + half);
        let (lo, hi) = terrain.extent();
        let samples = terrain.grid();
        let pad = samples.resolution_m();
        let grid = Grid::from_fn(origin, resolution_m, nx as usize, ny as usize, |_, c| {
            if c.x < lo.x || c.x > hi.x || c.y < lo.y || c.y > hi.y {
                return MapValue::Unknown;
            }
            let a = Point2::new(c.x - half - pad, c.y - half - pad);
            let b = Point2::new(c.x + half + pad, c.y + half + pad);
            let mut top = terrain.height_at(c.x, c.y);
            if let Some((xs, ys)) = samples.cell_range(a, b) {
                for iy in ys {
                    for ix in xs.clone() {
                        if let Some(&h) = samples.get(CellIndex::new(ix, iy)) {
                            top = top.max(h);
                        }
                    }
                }
            }
            MapValue::Known {
                value: top,
                sigma_m: 0.0,
            }
        })
        .map_err(|e| bad(e.to_string()))?;
        Ok(Self {
            kind: MapKind::Elevation,
            grid,
        })
    }

    /// The map kind.
    pub fn kind(&self) -> MapKind {
        self.kind
    }

    /// The cells.
    pub fn grid(&self) -> &Grid<MapValue> {
        &self.grid
    }

    /// The cells, mutable (for tests that hide or change parts of a map).
    pub fn grid_mut(&mut self) -> &mut Grid<MapValue> {
        &mut self.grid
    }

    /// The value of the cell containing a world point; unknown off the map.
    pub fn value_at(&self, p: Point2<f64>) -> MapValue {
        self.grid
            .cell_at(p)
            .and_then(|c| self.grid.get(c).copied())
            .unwrap_or(MapValue::Unknown)
    }

    /// Number of known cells.
    pub fn known_cells(&self) -> usize {
        self.grid
            .cells()
            .iter()
            .filter(|v| matches!(v, MapValue::Known { .. }))
            .count()
    }
}

fn kind_name(kind: MapKind) -> &'static str {
    match kind {
        MapKind::Elevation => "elevation",
        MapKind::ElevationUncertainty => "elevation-uncertainty",
        MapKind::Footfall => "footfall",
        MapKind::Slope => "slope",
        MapKind::Reachability => "reachability",
    }
}

/// Conservative obstacle heights from an elevation map, with disc queries for the foot.
#[derive(Debug, Clone, PartialEq)]
pub struct ObstacleHeights {
    origin: Point2<f64>,
    resolution_m: f64,
    nx: usize,
    ny: usize,
    /// Conservative height per map cell, metres.
    height_m: Vec<f64>,
    /// Whether the cell is known (for the footfall checks).
    known: Vec<bool>,
    /// Lowest height the map allows per known cell (`value - sigma_factor * sigma`), metres;
    /// negative infinity elsewhere.
    lower_m: Vec<f64>,
    /// Range maxima along rows: `row_max[k][iy * nx + ix]` is the highest of the `2^k` cells
    /// from `ix` on (a sparse table, for fast disc maxima).
    row_max: Vec<Vec<f64>>,
    unknown_height_m: f64,
}

impl ObstacleHeights {
    /// Known cells count as `value + sigma_factor * sigma`, occluded ones as their maximum,
    /// unknown ones (and everything off the map) as `unknown_height_m`.
    pub fn new(map: &TerrainGrid, sigma_factor: f64, unknown_height_m: f64) -> Self {
        let g = map.grid();
        let mut height_m = Vec::with_capacity(g.len());
        let mut known = Vec::with_capacity(g.len());
        let mut lower_m = Vec::with_capacity(g.len());
        for v in g.cells() {
            let (h, k, low) = match *v {
                MapValue::Known { value, sigma_m } => (
                    value + sigma_factor * sigma_m,
                    true,
                    value - sigma_factor * sigma_m,
                ),
                MapValue::Occluded { max_elevation_m } => {
                    (max_elevation_m, false, f64::NEG_INFINITY)
                }
                MapValue::Unknown => (unknown_height_m, false, f64::NEG_INFINITY),
            };
            height_m.push(h);
            known.push(k);
            lower_m.push(low);
        }
        let nx = g.nx();
        let mut row_max = vec![height_m.clone()];
        let mut span = 1;
        while 2 * span <= nx {
            let prev = row_max.last().map_or(&height_m, |v| v);
            let next: Vec<f64> = (0..prev.len())
                .map(|i| {
                    let ix = i % nx;
                    match prev.get(i + span) {
                        Some(&b) if ix + span < nx => prev[i].max(b),
                        _ => prev[i],
                    }
                })
                .collect();
            row_max.push(next);
            span *= 2;
        }
        Self {
            origin: g.origin(),
            resolution_m: g.resolution_m(),
            nx,
            ny: g.ny(),
            height_m,
            known,
            lower_m,
            row_max,
            unknown_height_m,
        }
    }

    /// Highest conservative terrain over a disc, metres: the same value as
    /// [`max_in_disc`](Self::max_in_disc) without the known flag, in time proportional to
    /// the disc's rows (range maxima along each row).
    pub fn max_height_in_disc(&self, centre: Point2<f64>, radius_m: f64) -> f64 {
        let r = self.resolution_m;
        let half = 0.5 * r;
        let radius = radius_m.max(0.0);
        let (nxf, nyf) = (self.nx as f64, self.ny as f64);
        let (bx0, by0) = (self.origin.x - half, self.origin.y - half);
        let on_map = centre.x - radius >= bx0
            && centre.x + radius <= bx0 + nxf * r
            && centre.y - radius >= by0
            && centre.y + radius <= by0 + nyf * r;
        let mut top = if on_map {
            f64::NEG_INFINITY
        } else {
            self.unknown_height_m
        };
        let gy = (centre.y - self.origin.y) / r;
        let reach = radius / r + 0.5;
        let (y0, y1) = ((gy - reach).floor(), (gy + reach).ceil());
        if !(y0.is_finite() && y1.is_finite() && centre.x.is_finite()) {
            return self.unknown_height_m;
        }
        let (y0, y1) = (y0.max(0.0), y1.min(nyf - 1.0));
        let mut iy = y0;
        while iy <= y1 {
            let cy = self.origin.y + iy * r;
            let dy = ((cy - centre.y).abs() - half).max(0.0);
            if dy <= radius {
                let w = (radius * radius - dy * dy).sqrt() + half;
                let a = ((centre.x - w - self.origin.x) / r).ceil().max(0.0);
                let b = ((centre.x + w - self.origin.x) / r).floor().min(nxf - 1.0);
                if a <= b {
                    top = top.max(self.row_range_max(iy as usize, a as usize, b as usize));
                }
            }
            iy += 1.0;
        }
        if top == f64::NEG_INFINITY {
            self.unknown_height_m
        } else {
            top
        }
    }

    /// Highest height of cells `a..=b` of row `iy`.
    fn row_range_max(&self, iy: usize, a: usize, b: usize) -> f64 {
        let len = b - a + 1;
        let k = (usize::BITS - 1 - len.leading_zeros()) as usize;
        let k = k.min(self.row_max.len() - 1);
        let row = iy * self.nx;
        let level = &self.row_max[k];
        let span = 1usize << k;
        let left = level.get(row + a).copied().unwrap_or(f64::NEG_INFINITY);
        let right = level
            .get(row + b + 1 - span)
            .copied()
            .unwrap_or(f64::NEG_INFINITY);
        left.max(right)
    }

    /// Height that unknown terrain counts as, metres.
    pub fn unknown_height_m(&self) -> f64 {
        self.unknown_height_m
    }

    /// Highest conservative terrain over a disc (every map cell whose square meets it, and
    /// the unknown height where the disc leaves the map), metres; with whether every cell
    /// met was known and the disc stayed on the map.
    pub fn max_in_disc(&self, centre: Point2<f64>, radius_m: f64) -> (f64, bool) {
        let mut top = f64::NEG_INFINITY;
        let mut all_known = true;
        let on_map = self.for_cells_in_disc(centre, radius_m, |i| {
            if let (Some(&h), Some(&k)) = (self.height_m.get(i), self.known.get(i)) {
                top = top.max(h);
                all_known &= k;
            }
        });
        if !on_map {
            top = top.max(self.unknown_height_m);
            all_known = false;
        }
        if top == f64::NEG_INFINITY {
            (self.unknown_height_m, false)
        } else {
            (top, all_known)
        }
    }

    /// Highest known terrain over a disc, metres; `None` when the disc meets no known cell.
    pub fn max_known_in_disc(&self, centre: Point2<f64>, radius_m: f64) -> Option<f64> {
        let mut top: Option<f64> = None;
        self.for_cells_in_disc(centre, radius_m, |i| {
            if let (Some(&h), Some(true)) = (self.height_m.get(i), self.known.get(i)) {
                top = Some(top.map_or(h, |t: f64| t.max(h)));
            }
        });
        top
    }

    /// Highest lower bound of known terrain over a disc (`value - sigma_factor * sigma`),
    /// metres; `None` when the disc meets no known cell. Where the map is sure the ground is
    /// at least this high.
    pub fn max_known_lower_in_disc(&self, centre: Point2<f64>, radius_m: f64) -> Option<f64> {
        let mut top: Option<f64> = None;
        self.for_cells_in_disc(centre, radius_m, |i| {
            if let (Some(&h), Some(true)) = (self.lower_m.get(i), self.known.get(i)) {
                top = Some(top.map_or(h, |t: f64| t.max(h)));
            }
        });
        top
    }

    /// Calls `f` with the index of every map cell whose square meets the disc; returns
    /// whether the disc stays on the map.
    fn for_cells_in_disc(
        &self,
        centre: Point2<f64>,
        radius_m: f64,
        mut f: impl FnMut(usize),
    ) -> bool {
        let r = self.resolution_m;
        let half = 0.5 * r;
        let radius = radius_m.max(0.0);
        let (nxf, nyf) = (self.nx as f64, self.ny as f64);
        let (bx0, by0) = (self.origin.x - half, self.origin.y - half);
        let (bx1, by1) = (bx0 + nxf * r, by0 + nyf * r);
        let on_map = centre.x - radius >= bx0
            && centre.x + radius <= bx1
            && centre.y - radius >= by0
            && centre.y + radius <= by1;
        let gx = (centre.x - self.origin.x) / r;
        let gy = (centre.y - self.origin.y) / r;
        let reach = radius / r + 0.5;
        let (x0, x1) = ((gx - reach).floor(), (gx + reach).ceil());
        let (y0, y1) = ((gy - reach).floor(), (gy + reach).ceil());
        if !(x0.is_finite() && x1.is_finite() && y0.is_finite() && y1.is_finite())
            || x1 < 0.0
            || y1 < 0.0
            || x0 > nxf - 1.0
            || y0 > nyf - 1.0
        {
            return false;
        }
        let clamp = |v: f64, n: f64| v.clamp(0.0, n - 1.0) as usize;
        let (ix0, ix1) = (clamp(x0, nxf), clamp(x1, nxf));
        let (iy0, iy1) = (clamp(y0, nyf), clamp(y1, nyf));
        let r2 = radius * radius;
        for iy in iy0..=iy1 {
            let cy = self.origin.y + iy as f64 * r;
            let dy = ((cy - centre.y).abs() - half).max(0.0);
            let dy2 = dy * dy;
            if dy2 > r2 {
                continue;
            }
            let row = iy * self.nx;
            for ix in ix0..=ix1 {
                let cx = self.origin.x + ix as f64 * r;
                let dx = ((cx - centre.x).abs() - half).max(0.0);
                if dx * dx + dy2 <= r2 {
                    f(row + ix);
                }
            }
        }
        on_map
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat_with_box() -> HeightField {
        // 4 x 4 m at 2 cm, a 0.5 m tall box over [1.0, 1.4] x [2.0, 2.4].
        HeightField::from_grid(
            Grid::from_fn(Point2::new(0.0, 0.0), 0.02, 201, 201, |_, p| {
                if (1.0..=1.4).contains(&p.x) && (2.0..=2.4).contains(&p.y) {
                    0.5
                } else {
                    0.0
                }
            })
            .unwrap(),
        )
        .unwrap()
    }

    #[test]
    fn elevation_from_a_height_field_keeps_the_tops() {
        let map = TerrainGrid::elevation_from_height_field(
            &flat_with_box(),
            Point2::new(0.0, 0.0),
            Point2::new(4.0, 4.0),
            0.1,
        )
        .unwrap();
        assert_eq!(map.grid().nx(), 40);
        assert_eq!(map.value_at(Point2::new(1.2, 2.2)).known(), Some(0.5));
        assert_eq!(map.value_at(Point2::new(3.0, 3.0)).known(), Some(0.0));
        // A cell just touching the box's edge sees it (conservative).
        assert_eq!(map.value_at(Point2::new(0.95, 2.2)).known(), Some(0.5));
        assert_eq!(map.value_at(Point2::new(-1.0, 2.2)), MapValue::Unknown);
    }

    #[test]
    fn wire_round_trip_keeps_cells_and_refuses_bad_sizes() {
        let map = TerrainGrid::elevation_from_height_field(
            &flat_with_box(),
            Point2::new(0.5, 1.5),
            Point2::new(2.0, 3.0),
            0.1,
        )
        .unwrap();
        let wire = map.to_map_grid();
        let back = TerrainGrid::from_map_grid(&wire).unwrap();
        assert_eq!(back, map);
        let mut broken = wire.clone();
        broken.cells.pop();
        let err = TerrainGrid::from_map_grid(&broken).unwrap_err();
        assert!(
            err.to_string().contains("elevation map is malformed"),
            "{err}"
        );
        let mut nan = wire;
        nan.cells[0] = MapCell::Known {
            value: f32::NAN,
            sigma_m: 0.0,
        };
        let back = TerrainGrid::from_map_grid(&nan).unwrap();
        assert_eq!(back.grid().cells()[0], MapValue::Unknown);
    }

    #[test]
    fn disc_maximum_is_conservative_and_sees_unknown_edges() {
        let map = TerrainGrid::elevation_from_height_field(
            &flat_with_box(),
            Point2::new(0.0, 0.0),
            Point2::new(4.0, 4.0),
            0.05,
        )
        .unwrap();
        let obstacles = ObstacleHeights::new(&map, 2.0, 0.8);
        // 0.2 m from the box's left face: a 0.25 m disc meets it, a 0.15 m one does not.
        let (h, known) = obstacles.max_in_disc(Point2::new(0.8, 2.2), 0.25);
        assert_eq!((h, known), (0.5, true));
        let (h, _) = obstacles.max_in_disc(Point2::new(0.8, 2.2), 0.13);
        assert_eq!(h, 0.0);
        // Past the map's edge: unknown height.
        let (h, known) = obstacles.max_in_disc(Point2::new(0.1, 0.1), 0.3);
        assert_eq!((h, known), (0.8, false));
        let (h, known) = obstacles.max_in_disc(Point2::new(-5.0, -5.0), 0.3);
        assert_eq!((h, known), (0.8, false));
    }

    #[test]
    fn fast_disc_maximum_matches_the_cell_by_cell_one() {
        let hf = HeightField::from_grid(
            Grid::from_fn(Point2::new(0.0, 0.0), 0.02, 201, 151, |_, p| {
                (3.0 * p.x).sin() * (2.0 * p.y).cos() + 0.1 * (17.0 * p.x * p.y).sin()
            })
            .unwrap(),
        )
        .unwrap();
        let map = TerrainGrid::elevation_from_height_field(
            &hf,
            Point2::new(0.3, 0.2),
            Point2::new(3.7, 2.8),
            0.05,
        )
        .unwrap();
        let o = ObstacleHeights::new(&map, 2.0, 0.8);
        for k in 0..400 {
            let t = f64::from(k);
            let c = Point2::new(
                4.2 * (0.37 * t).sin().abs() - 0.1,
                3.2 * (0.23 * t).cos().abs() - 0.1,
            );
            let radius = 0.02 + 0.6 * (0.11 * t).sin().abs();
            let (slow, _) = o.max_in_disc(c, radius);
            let fast = o.max_height_in_disc(c, radius);
            assert_eq!(slow, fast, "disc at {c} radius {radius}");
        }
    }

    #[test]
    fn uncertainty_and_occlusion_raise_obstacles() {
        let grid = Grid::from_vec(
            Point2::new(0.0, 0.0),
            0.1,
            3,
            1,
            vec![
                MapValue::Known {
                    value: 0.1,
                    sigma_m: 0.05,
                },
                MapValue::Occluded {
                    max_elevation_m: 0.3,
                },
                MapValue::Unknown,
            ],
        )
        .unwrap();
        let map = TerrainGrid::new(MapKind::Elevation, grid);
        let o = ObstacleHeights::new(&map, 2.0, 0.8);
        let (h, k) = o.max_in_disc(Point2::new(0.0, 0.0), 0.01);
        assert!((h - 0.2).abs() < 1e-12 && k, "{h} {k}");
        assert_eq!(o.max_known_in_disc(Point2::new(0.1, 0.0), 0.2), Some(0.2));
        let (h, _) = o.max_in_disc(Point2::new(0.1, 0.0), 0.01);
        assert!((h - 0.3).abs() < 1e-12);
        let (h, _) = o.max_in_disc(Point2::new(0.2, 0.0), 0.01);
        assert!((h - 0.8).abs() < 1e-12);
    }
}
