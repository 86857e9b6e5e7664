//! The terrain as the walker knows it: the LTM Manager's elevation, footfall and slope maps
//! of a region, seen through the free gait's [`TerrainView`].
//!
//! A foothold's cost is judged as on the true terrain ([`GridView`]): the footfall map's
//! deviation of the ground under the foot from its fitted plane, in foot radii, plus the
//! tangent of the slope map's angle; a foothold deviating by more than `max_residual` foot
//! radii or steeper than `max_slope_rad` is forbidden.

use nalgebra::Point2;
use tca_free_gait::{GridView, TerrainView};
use tca_single_leg_messages::{MapCell, MapGrid};

/// How far around a swing's disc, in cells, the ground seen bounds the unseen cells in it.
const GAP_FILL_CELLS: f64 = 3.0;

/// What a map cell says.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Seen {
    Unknown,
    /// Hidden; the terrain is at most this high.
    AtMost(f64),
    Known(f64),
}

/// One map as a grid of cells.
#[derive(Clone, Debug)]
struct Layer {
    origin: Point2<f64>,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Seen>,
}

impl Layer {
    fn new(grid: &MapGrid) -> Result<Self, String> {
        let (nx, ny) = (grid.nx as usize, grid.ny as usize);
        if grid.cells.len() != nx * ny || grid.resolution_m.is_nan() || grid.resolution_m <= 0.0 {
            return Err(format!(
                "a {:?} map of {nx} x {ny} cells came with {} cells at {} m; the LTM Manager sent a malformed map",
                grid.kind,
                grid.cells.len(),
                grid.resolution_m
            ));
        }
        let cells = grid
            .cells
            .iter()
            .map(|c| match *c {
                MapCell::Unknown => Seen::Unknown,
                MapCell::Occluded { max_elevation_m } => Seen::AtMost(f64::from(max_elevation_m)),
                MapCell::Known { value, .. } => Seen::Known(f64::from(value)),
            })
            .collect();
        Ok(Layer {
            origin: Point2::new(grid.origin_x_m, grid.origin_y_m),
            cell: grid.resolution_m,
            nx,
            ny,
            cells,
        })
    }

    fn index(&self, p: Point2<f64>) -> Option<(usize, usize)> {
        let fx = ((p.x - self.origin.x) / self.cell).round();
        let fy = ((p.y - self.origin.y) / self.cell).round();
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (ix, iy) = (fx as usize, fy as usize);
        (ix < self.nx && iy < self.ny).then_some((ix, iy))
    }

    /// The value at `p` interpolated bilinearly between the four known cells around it; the
    /// nearest cell's when one of them is not known.
    fn interpolated(&self, p: Point2<f64>) -> Seen {
        let fx = (p.x - self.origin.x) / self.cell;
        let fy = (p.y - self.origin.y) / self.cell;
        let (x0, y0) = (fx.floor(), fy.floor());
        if x0 >= 0.0 && y0 >= 0.0 {
            let (ix, iy) = (x0 as usize, y0 as usize);
            if ix + 1 < self.nx && iy + 1 < self.ny {
                let v = |i: usize, j: usize| match self.cells[j * self.nx + i] {
                    Seen::Known(h) => Some(h),
                    _ => None,
                };
                if let (Some(a), Some(b), Some(c), Some(d)) =
                    (v(ix, iy), v(ix + 1, iy), v(ix, iy + 1), v(ix + 1, iy + 1))
                {
                    let (tx, ty) = (fx - x0, fy - y0);
                    let low = a + (b - a) * tx;
                    let high = c + (d - c) * tx;
                    return Seen::Known(low + (high - low) * ty);
                }
            }
        }
        self.at(p)
    }

    /// The centres of the cells next to the one holding `p` on the sides `p` lies more
    /// than a quarter of a cell toward (none when `p` is near its cell's centre).
    fn toward(&self, p: Point2<f64>) -> Vec<Point2<f64>> {
        let side = |v: f64| {
            let off = v - v.round();
            if off > 0.25 {
                1.0
            } else if off < -0.25 {
                -1.0
            } else {
                0.0
            }
        };
        let fx = (p.x - self.origin.x) / self.cell;
        let fy = (p.y - self.origin.y) / self.cell;
        let (sx, sy) = (side(fx), side(fy));
        let centre = |dx: f64, dy: f64| {
            Point2::new(
                self.origin.x + (fx.round() + dx) * self.cell,
                self.origin.y + (fy.round() + dy) * self.cell,
            )
        };
        [(sx, 0.0), (0.0, sy), (sx, sy)]
            .into_iter()
            .filter(|&(dx, dy)| (dx, dy) != (0.0, 0.0))
            .map(|(dx, dy)| centre(dx, dy))
            .collect()
    }

    fn at(&self, p: Point2<f64>) -> Seen {
        self.index(p)
            .map_or(Seen::Unknown, |(ix, iy)| self.cells[iy * self.nx + ix])
    }

    /// As [`Layer::at`], a hidden cell's bound raised to the highest ground seen or bounded
    /// in the cells around it: the bound comes from a ray that passed over the cell
    /// somewhere, and the ground under a part of the cell the ray missed (the far flank of
    /// a rock) may stand as high as its neighbours.
    fn bounded(&self, p: Point2<f64>) -> Seen {
        let Some((ix, iy)) = self.index(p) else {
            return Seen::Unknown;
        };
        let Seen::AtMost(mut h) = self.cells[iy * self.nx + ix] else {
            return self.cells[iy * self.nx + ix];
        };
        for j in iy.saturating_sub(1)..(iy + 2).min(self.ny) {
            for i in ix.saturating_sub(1)..(ix + 2).min(self.nx) {
                if let Seen::Known(v) | Seen::AtMost(v) = self.cells[j * self.nx + i] {
                    h = h.max(v);
                }
            }
        }
        Seen::AtMost(h)
    }

    /// Cells whose centres lie within `r` of `c` (at least the cell holding `c`), hidden
    /// ones bounded as by [`Layer::bounded`].
    fn disc(&self, c: Point2<f64>, r: f64) -> Vec<Seen> {
        let n = (r / self.cell).ceil() as i64;
        let mut out = vec![self.bounded(c)];
        for dy in -n..=n {
            for dx in -n..=n {
                let q = Point2::new(c.x + dx as f64 * self.cell, c.y + dy as f64 * self.cell);
                if (dx, dy) != (0, 0) && (q - c).norm() <= r {
                    out.push(self.bounded(q));
                }
            }
        }
        out
    }
}

/// The LTM Manager's maps of the region around the body.
#[derive(Clone, Debug)]
pub struct MapView {
    elevation: Layer,
    footfall: Layer,
    slope: Layer,
    /// Steepest slope a foot may stand on, radians.
    pub max_slope_rad: f64,
    /// Largest departure of the ground under the foot from its fitted plane, in foot radii.
    pub max_residual: f64,
}

impl MapView {
    /// From an elevation, a footfall and a slope map, judging footholds as [`GridView::new`]
    /// does; a malformed map is refused, saying what was wrong.
    pub fn new(elevation: &MapGrid, footfall: &MapGrid, slope: &MapGrid) -> Result<Self, String> {
        Ok(MapView {
            elevation: Layer::new(elevation)?,
            footfall: Layer::new(footfall)?,
            slope: Layer::new(slope)?,
            max_slope_rad: GridView::DEFAULT_MAX_SLOPE_RAD,
            max_residual: GridView::DEFAULT_MAX_RESIDUAL,
        })
    }

    /// The share of cells within `r` of `c` that are known, for messages.
    pub fn known_share(&self, c: Point2<f64>, r: f64) -> f64 {
        let cells = self.elevation.disc(c, r);
        let known = cells.iter().filter(|s| matches!(s, Seen::Known(_))).count();
        known as f64 / cells.len().max(1) as f64
    }
}

impl TerrainView for MapView {
    fn height_at(&self, p: Point2<f64>) -> Option<f64> {
        match self.elevation.interpolated(p) {
            Seen::Known(h) => Some(h),
            _ => None,
        }
    }

    fn height_bound_at(&self, p: Point2<f64>) -> Option<f64> {
        // Where the cell is not known, the bound a hidden cell carries or the one the ground
        // seen around an unseen cell gives.
        self.height_at(p)
            .or_else(|| self.max_height_in_disc(p, 0.0))
    }

    fn max_height_in_disc(&self, c: Point2<f64>, r: f64) -> Option<f64> {
        // A hidden cell is bounded by what hides it and by the ground around it: enough to
        // keep a swing clear of it. An unseen cell among seen ones (a gap between the
        // scanner's samples, the floor of a narrow hollow) is taken as high as the highest
        // ground seen around it; one with nothing seen around it makes the disc unknown.
        let mut best = f64::NEG_INFINITY;
        let mut gaps = false;
        for s in self.elevation.disc(c, r) {
            match s {
                Seen::Known(h) | Seen::AtMost(h) => best = best.max(h),
                Seen::Unknown => gaps = true,
            }
        }
        if gaps {
            let around = self
                .elevation
                .disc(c, r + GAP_FILL_CELLS * self.elevation.cell);
            let seen = around
                .iter()
                .filter(|s| !matches!(s, Seen::Unknown))
                .count();
            if seen * 2 < around.len() {
                return None;
            }
            for s in around {
                if let Seen::Known(h) | Seen::AtMost(h) = s {
                    best = best.max(h);
                }
            }
        }
        best.is_finite().then_some(best)
    }

    fn foothold_cost(&self, p: Point2<f64>, foot_radius_m: f64) -> Option<f64> {
        // The footfall and slope maps are evaluated over the robot's foot at each cell's
        // centre. A foot well off its cell's centre reaches over ground that cell's
        // evaluation does not cover (over the edge of a ditch, say): it is judged by the
        // worst of the known cells it leans toward as well.
        let (Seen::Known(mut deviation_m), Seen::Known(mut slope)) =
            (self.footfall.at(p), self.slope.at(p))
        else {
            return None;
        };
        for q in self.footfall.toward(p) {
            if let Seen::Known(d) = self.footfall.at(q) {
                deviation_m = deviation_m.max(d);
            }
            if let Seen::Known(s) = self.slope.at(q) {
                slope = slope.max(s);
            }
        }
        let relative = deviation_m / foot_radius_m.max(self.footfall.cell);
        if relative > self.max_residual || slope > self.max_slope_rad {
            return Some(f64::INFINITY);
        }
        Some(relative + slope.tan())
    }
}

/// What a step is planned on: the LTM Manager's maps, or the true terrain.
#[derive(Clone, Debug)]
pub enum StepView {
    /// The maps.
    Map(MapView),
    /// The true terrain.
    Truth(GridView),
}

impl StepView {
    /// The share of the terrain within `r` of `c` that is known (all of it, for the truth).
    pub fn known_share(&self, c: Point2<f64>, r: f64) -> f64 {
        match self {
            StepView::Map(m) => m.known_share(c, r),
            StepView::Truth(_) => 1.0,
        }
    }

    fn view(&self) -> &dyn TerrainView {
        match self {
            StepView::Map(m) => m,
            StepView::Truth(t) => t,
        }
    }
}

impl TerrainView for StepView {
    fn height_at(&self, p: Point2<f64>) -> Option<f64> {
        self.view().height_at(p)
    }

    fn height_bound_at(&self, p: Point2<f64>) -> Option<f64> {
        self.view().height_bound_at(p)
    }

    fn max_height_in_disc(&self, c: Point2<f64>, r: f64) -> Option<f64> {
        self.view().max_height_in_disc(c, r)
    }

    fn foothold_cost(&self, p: Point2<f64>, foot_radius_m: f64) -> Option<f64> {
        self.view().foothold_cost(p, foot_radius_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_single_leg_messages::MapKind;

    fn grid(kind: MapKind, f: impl Fn(usize, usize) -> MapCell) -> MapGrid {
        let (nx, ny) = (10u32, 10u32);
        MapGrid {
            kind,
            origin_x_m: 0.0,
            origin_y_m: 0.0,
            resolution_m: 0.1,
            nx,
            ny,
            cells: (0..ny as usize)
                .flat_map(|iy| (0..nx as usize).map(move |ix| (ix, iy)))
                .map(|(ix, iy)| f(ix, iy))
                .collect(),
        }
    }

    #[test]
    fn unknown_cells_are_never_footholds_and_hidden_ones_bound_clearance() {
        let known = |v: f32| MapCell::Known {
            value: v,
            sigma_m: 0.01,
        };
        let elevation = grid(MapKind::Elevation, |ix, _| match ix {
            0..=4 => known(0.2),
            5 => MapCell::Occluded {
                max_elevation_m: 0.9,
            },
            _ => MapCell::Unknown,
        });
        let footfall = grid(MapKind::Footfall, |ix, _| match ix {
            0..=2 => known(0.01),
            3 | 4 => known(0.05),
            _ => MapCell::Unknown,
        });
        let slope = grid(MapKind::Slope, |ix, iy| match (ix, iy) {
            (0..=4, 0) => known(0.7),
            (0..=4, _) => known(0.1),
            _ => MapCell::Unknown,
        });
        let v = MapView::new(&elevation, &footfall, &slope).expect("well-formed maps");
        assert_eq!(v.height_at(Point2::new(0.2, 0.5)), Some(0.2f32 as f64));
        assert_eq!(v.height_at(Point2::new(0.5, 0.5)), None);
        assert_eq!(
            v.max_height_in_disc(Point2::new(0.4, 0.5), 0.1),
            Some(0.9f32 as f64)
        );
        // Unseen cells next to seen ones are bounded by the highest seen around them; a disc
        // mostly unseen is unknown.
        assert_eq!(
            v.max_height_in_disc(Point2::new(0.5, 0.5), 0.1),
            Some(0.9f32 as f64)
        );
        assert_eq!(v.max_height_in_disc(Point2::new(0.9, 0.5), 0.1), None);
        // 1 cm off the plane under a 0.1 m foot on a 0.1 rad slope.
        let cost = v.foothold_cost(Point2::new(0.2, 0.5), 0.1).expect("known");
        assert!((cost - (0.01f32 as f64 / 0.1 + (0.1f32 as f64).tan())).abs() < 1e-9);
        // 5 cm off the plane is half a foot radius: forbidden, as is a 40° slope.
        assert_eq!(
            v.foothold_cost(Point2::new(0.3, 0.5), 0.1),
            Some(f64::INFINITY)
        );
        assert_eq!(
            v.foothold_cost(Point2::new(0.1, 0.0), 0.1),
            Some(f64::INFINITY)
        );
        assert_eq!(v.foothold_cost(Point2::new(0.5, 0.5), 0.1), None);
        assert_eq!(v.height_at(Point2::new(-3.0, 0.5)), None);
        // A swing may pass over a hidden cell, as high as what hides it allows.
        assert_eq!(
            v.height_bound_at(Point2::new(0.5, 0.5)),
            Some(0.9f32 as f64)
        );
        assert_eq!(
            v.height_bound_at(Point2::new(0.2, 0.5)),
            v.height_at(Point2::new(0.2, 0.5))
        );
        // A foot well off its cell's centre is judged by the cell it leans toward too.
        assert_eq!(
            v.foothold_cost(Point2::new(0.23, 0.5), 0.1),
            Some(f64::INFINITY)
        );
        assert!(
            v.foothold_cost(Point2::new(0.17, 0.5), 0.1)
                .is_some_and(f64::is_finite)
        );
        let mut bad = elevation.clone();
        bad.cells.pop();
        assert!(
            MapView::new(&bad, &footfall, &slope)
                .unwrap_err()
                .contains("malformed")
        );
    }
}
