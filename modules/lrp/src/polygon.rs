//! Map regions given as polygons on the ground plane (the `mapRegion` and
//! `legReachability` vocabulary): validation, bounding grid, and point inclusion.

use nalgebra::Point2;
use tca_robot::Grid;
use tca_single_leg_messages::PlanePoint;

use crate::error::{PlanError, Result};

/// Largest number of cells of a grid built for a region.
pub const MAX_REGION_CELLS: usize = 4_000_000;

/// Whether `p` is inside the polygon (even-odd rule; points on an edge may go either way).
pub fn contains(polygon: &[PlanePoint], p: Point2<f64>) -> bool {
    let mut inside = false;
    let n = polygon.len();
    for i in 0..n {
        let a = &polygon[i];
        let b = &polygon[(i + n - 1) % n];
        if (a.y_m > p.y) != (b.y_m > p.y) {
            let x = a.x_m + (p.y - a.y_m) * (b.x_m - a.x_m) / (b.y_m - a.y_m);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// The grid of `resolution_m` cells covering the polygon's bounding box, with each cell
/// marked whether its centre is inside the polygon. Refused for fewer than three corners,
/// non-finite corners or resolution, or more than [`MAX_REGION_CELLS`] cells.
pub fn region_grid(polygon: &[PlanePoint], resolution_m: f64) -> Result<Grid<bool>> {
    let bad = |reason: String| PlanError::BadRegion { reason };
    if polygon.len() < 3 {
        return Err(bad(format!("the polygon has {} corners", polygon.len())));
    }
    if polygon
        .iter()
        .any(|p| !(p.x_m.is_finite() && p.y_m.is_finite()))
    {
        return Err(bad("a corner is not finite".into()));
    }
    if !(resolution_m.is_finite() && resolution_m > 0.0) {
        return Err(bad(format!("the resolution is {resolution_m} m")));
    }
    let (mut lo, mut hi) = (
        Point2::new(f64::INFINITY, f64::INFINITY),
        Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for p in polygon {
        lo = Point2::new(lo.x.min(p.x_m), lo.y.min(p.y_m));
        hi = Point2::new(hi.x.max(p.x_m), hi.y.max(p.y_m));
    }
    let count = |a: f64, b: f64| ((b - a) / resolution_m).ceil().max(1.0);
    let (nx, ny) = (count(lo.x, hi.x), count(lo.y, hi.y));
    if nx * ny > MAX_REGION_CELLS as f64 {
        return Err(bad(format!(
            "{nx} x {ny} cells at {resolution_m} m is too many; use a coarser resolution"
        )));
    }
    let origin = Point2::new(lo.x + 0.5 * resolution_m, lo.y + 0.5 * resolution_m);
    Grid::from_fn(origin, resolution_m, nx as usize, ny as usize, |_, c| {
        contains(polygon, c)
    })
    .map_err(|e| bad(e.to_string()))
}

/// The axis-aligned rectangle `[min, max]` as a polygon.
pub fn rectangle(min: Point2<f64>, max: Point2<f64>) -> Vec<PlanePoint> {
    vec![
        PlanePoint {
            x_m: min.x,
            y_m: min.y,
        },
        PlanePoint {
            x_m: max.x,
            y_m: min.y,
        },
        PlanePoint {
            x_m: max.x,
            y_m: max.y,
        },
        PlanePoint {
            x_m: min.x,
            y_m: max.y,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_contains_its_inside_only() {
        let t = [
            PlanePoint { x_m: 0.0, y_m: 0.0 },
            PlanePoint { x_m: 2.0, y_m: 0.0 },
            PlanePoint { x_m: 0.0, y_m: 2.0 },
        ];
        assert!(contains(&t, Point2::new(0.5, 0.5)));
        assert!(!contains(&t, Point2::new(1.5, 1.5)));
        let g = region_grid(&t, 0.5).unwrap();
        assert_eq!((g.nx(), g.ny()), (4, 4));
        assert!(*g.get(tca_robot::CellIndex::new(0, 0)).unwrap());
        assert!(!*g.get(tca_robot::CellIndex::new(3, 3)).unwrap());
    }

    #[test]
    fn bad_regions_are_refused() {
        let line = rectangle(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0))[..2].to_vec();
        assert!(region_grid(&line, 0.1).is_err());
        let square = rectangle(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0));
        assert!(region_grid(&square, 0.0).is_err());
        assert!(region_grid(&square, 1e-6).is_err());
        let mut nan = square.clone();
        nan[1].x_m = f64::NAN;
        let err = region_grid(&nan, 0.1).unwrap_err();
        assert!(err.to_string().contains("not finite"), "{err}");
    }
}
