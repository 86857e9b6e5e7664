//! The terrain as the walker knows it: the LTM Manager's elevation and footfall maps of a
//! region, seen through the free gait's [`TerrainView`].

use nalgebra::Point2;
use tca_free_gait::{GridView, TerrainView};
use tca_single_leg_messages::{MapCell, MapGrid};

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
        if grid.cells.len() != nx * ny || !(grid.resolution_m > 0.0) {
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

    fn at(&self, p: Point2<f64>) -> Seen {
        self.index(p)
            .map_or(Seen::Unknown, |(ix, iy)| self.cells[iy * self.nx + ix])
    }

    /// Cells whose centres lie within `r` of `c` (at least the cell holding `c`).
    fn disc(&self, c: Point2<f64>, r: f64) -> Vec<Seen> {
        let n = (r / self.cell).ceil() as i64;
        let mut out = vec![self.at(c)];
        for dy in -n..=n {
            for dx in -n..=n {
                let q = Point2::new(c.x + dx as f64 * self.cell, c.y + dy as f64 * self.cell);
                if (dx, dy) != (0, 0) && (q - c).norm() <= r {
                    out.push(self.at(q));
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
}

impl MapView {
    /// From an elevation and a footfall map; a malformed map is refused, saying what was
    /// wrong.
    pub fn new(elevation: &MapGrid, footfall: &MapGrid) -> Result<Self, String> {
        Ok(MapView {
            elevation: Layer::new(elevation)?,
            footfall: Layer::new(footfall)?,
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
        match self.elevation.at(p) {
            Seen::Known(h) => Some(h),
            _ => None,
        }
    }

    fn max_height_in_disc(&self, c: Point2<f64>, r: f64) -> Option<f64> {
        // A hidden cell is bounded by what hides it: enough to keep a swing clear of it.
        let mut best = f64::NEG_INFINITY;
        for s in self.elevation.disc(c, r) {
            match s {
                Seen::Known(h) | Seen::AtMost(h) => best = best.max(h),
                Seen::Unknown => return None,
            }
        }
        Some(best)
    }

    fn foothold_cost(&self, p: Point2<f64>, foot_radius_m: f64) -> Option<f64> {
        // The footfall map is evaluated for the robot's foot; every cell under the foot's
        // sole must be known, and the worst of them is the cost.
        let mut worst: f64 = 0.0;
        for s in self.footfall.disc(p, foot_radius_m * 0.5) {
            match s {
                Seen::Known(v) => worst = worst.max(v),
                _ => return None,
            }
        }
        Some(worst)
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
        let known = |v: f32| MapCell::Known { value: v, sigma_m: 0.01 };
        let elevation = grid(MapKind::Elevation, |ix, _| match ix {
            0..=4 => known(0.2),
            5 => MapCell::Occluded { max_elevation_m: 0.9 },
            _ => MapCell::Unknown,
        });
        let footfall = grid(MapKind::Footfall, |ix, _| match ix {
            0..=4 => known(0.01),
            _ => MapCell::Unknown,
        });
        let v = MapView::new(&elevation, &footfall).expect("well-formed maps");
        assert_eq!(v.height_at(Point2::new(0.2, 0.5)), Some(0.2f32 as f64));
        assert_eq!(v.height_at(Point2::new(0.5, 0.5)), None);
        assert_eq!(v.max_height_in_disc(Point2::new(0.4, 0.5), 0.1), Some(0.9f32 as f64));
        assert_eq!(v.max_height_in_disc(Point2::new(0.6, 0.5), 0.1), None);
        assert!(v.foothold_cost(Point2::new(0.2, 0.5), 0.1).is_some());
        assert_eq!(v.foothold_cost(Point2::new(0.5, 0.5), 0.1), None);
        assert_eq!(v.height_at(Point2::new(-3.0, 0.5)), None);
        let mut bad = elevation.clone();
        bad.cells.pop();
        assert!(MapView::new(&bad, &footfall).unwrap_err().contains("malformed"));
    }
}
