//! Maps a perfect LTM Manager would serve, computed straight from a height field: for tests,
//! benchmarks and offline runs (the real maps come from the LTM Manager over the bus).

use nalgebra::{Matrix3, Point2, Vector3};
use tca_lrp::{MapValue, TerrainGrid};
use tca_robot::{CellIndex, Grid, HeightField};
use tca_single_leg_messages::MapKind;

use crate::error::{GaitError, Result};

/// The elevation map of `[min, max]` (the highest terrain over each cell).
pub fn elevation_map(
    terrain: &HeightField,
    min: Point2<f64>,
    max: Point2<f64>,
    resolution_m: f64,
) -> Result<TerrainGrid> {
    TerrainGrid::elevation_from_height_field(terrain, min, max, resolution_m)
        .map_err(|e| GaitError::BadMap(e.to_string()))
}

/// The footfall statistic of `[min, max]`: at each cell centre, the largest deviation of the
/// terrain under a foot disc of `foot_radius_m` from its least-squares plane, metres. Cells
/// whose disc leaves the height field are unknown.
pub fn footfall_map(
    terrain: &HeightField,
    min: Point2<f64>,
    max: Point2<f64>,
    resolution_m: f64,
    foot_radius_m: f64,
) -> Result<TerrainGrid> {
    let count = |lo: f64, hi: f64| ((hi - lo) / resolution_m).ceil().max(1.0) as usize;
    let (nx, ny) = (count(min.x, max.x), count(min.y, max.y));
    let origin = Point2::new(min.x + 0.5 * resolution_m, min.y + 0.5 * resolution_m);
    let samples = terrain.grid();
    let (lo, hi) = terrain.extent();
    let grid = Grid::from_fn(origin, resolution_m, nx, ny, |_, c| {
        if c.x - foot_radius_m < lo.x
            || c.x + foot_radius_m > hi.x
            || c.y - foot_radius_m < lo.y
            || c.y + foot_radius_m > hi.y
        {
            return MapValue::Unknown;
        }
        let r = Point2::new(foot_radius_m, foot_radius_m);
        let Some((xs, ys)) = samples.cell_range(c - r.coords, c + r.coords) else {
            return MapValue::Unknown;
        };
        let mut pts = Vec::new();
        for iy in ys {
            for ix in xs.clone() {
                let cell = CellIndex::new(ix, iy);
                let p = samples.cell_center(cell);
                if (p - c).norm() <= foot_radius_m
                    && let Some(&h) = samples.get(cell)
                {
                    pts.push(Vector3::new(p.x - c.x, p.y - c.y, h));
                }
            }
        }
        match plane_deviation(&pts) {
            Some(d) => MapValue::Known {
                value: d,
                sigma_m: 0.0,
            },
            None => MapValue::Unknown,
        }
    })
    .map_err(|e| GaitError::BadMap(e.to_string()))?;
    Ok(TerrainGrid::new(MapKind::Footfall, grid))
}

/// Largest absolute residual of the least-squares plane `z = a + b x + c y` through points.
fn plane_deviation(pts: &[Vector3<f64>]) -> Option<f64> {
    if pts.len() < 3 {
        return None;
    }
    let mut ata = Matrix3::zeros();
    let mut atz = Vector3::zeros();
    for p in pts {
        let row = Vector3::new(1.0, p.x, p.y);
        ata += row * row.transpose();
        atz += row * p.z;
    }
    let coef = ata.lu().solve(&atz)?;
    pts.iter()
        .map(|p| (p.z - (coef.x + coef.y * p.x + coef.z * p.y)).abs())
        .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.max(d))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slope_is_flat_for_the_foot_and_a_step_is_not() {
        let grid = Grid::from_fn(Point2::new(0.0, 0.0), 0.02, 151, 151, |_, p| {
            if p.x < 1.5 { 0.2 * p.y } else { 0.5 }
        })
        .unwrap();
        let hf = HeightField::from_grid(grid).unwrap();
        let map =
            footfall_map(&hf, Point2::new(0.0, 0.0), Point2::new(3.0, 3.0), 0.1, 0.15).unwrap();
        let slope = map.value_at(Point2::new(0.75, 1.45)).known().unwrap();
        assert!(slope < 1e-9, "{slope}");
        let step = map.value_at(Point2::new(1.45, 1.45)).known().unwrap();
        assert!(step > 0.1, "{step}");
        assert_eq!(map.value_at(Point2::new(0.05, 1.45)), MapValue::Unknown);
    }
}
