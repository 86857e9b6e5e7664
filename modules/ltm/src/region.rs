//! Regions of interest (§5.2.2): a polygon of at least three corners and a resolution; the
//! answer is the enclosing rectangular grid, aligned to the lattice of that resolution so that
//! overlapping requests share cells, with cells whose centre is outside the polygon unknown.

use nalgebra::Point2;
use tca_single_leg_messages::PlanePoint;

use crate::error::{LtmError, Result, check_resolution};
use crate::patch::lattice_index;

/// Largest lattice index magnitude a region may reach (keeps every index sum far from
/// overflow).
const MAX_INDEX: f64 = 1e12;

/// A checked region.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    corners: Vec<Point2<f64>>,
    resolution_m: f64,
    layout: QueryLayout,
}

/// The grid answering a region: lattice cells `i0 .. i0 + nx` by `j0 .. j0 + ny` of the
/// query's resolution (cell `(i, j)` centred at `(i * res, j * res)`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct QueryLayout {
    /// First lattice column.
    pub i0: i64,
    /// First lattice row.
    pub j0: i64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
}

impl Region {
    /// Checks a polygon and a resolution: at least three finite corners enclosing some area, a
    /// finite resolution above zero, and no more than `max_cells` cells in the enclosing grid.
    pub fn new(corners: &[PlanePoint], resolution_m: f64, max_cells: usize) -> Result<Self> {
        if corners.len() < 3 {
            return Err(LtmError::TooFewCorners(corners.len()));
        }
        check_resolution("region", resolution_m)?;
        let mut pts = Vec::with_capacity(corners.len());
        for (index, c) in corners.iter().enumerate() {
            if !(c.x_m.is_finite() && c.y_m.is_finite()) {
                return Err(LtmError::BadCorner {
                    index,
                    x_m: c.x_m,
                    y_m: c.y_m,
                });
            }
            let limit_m = MAX_INDEX * resolution_m;
            if c.x_m.abs() > limit_m || c.y_m.abs() > limit_m {
                return Err(LtmError::CornerTooFar {
                    x_m: c.x_m,
                    y_m: c.y_m,
                    resolution_m,
                    limit_m,
                });
            }
            pts.push(Point2::new(c.x_m, c.y_m));
        }
        let area2: f64 = pts
            .iter()
            .zip(pts.iter().cycle().skip(1))
            .map(|(a, b)| a.x * b.y - b.x * a.y)
            .sum();
        let (mut lo, mut hi) = (pts[0], pts[0]);
        for p in &pts {
            lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        let scale = (hi - lo).norm().max(1e-300);
        if area2.abs() <= 1e-12 * scale * scale {
            return Err(LtmError::ZeroArea);
        }
        let cells = |a: f64, b: f64| -> u64 {
            let n = ((b / resolution_m + 0.5).floor() - (a / resolution_m + 0.5).floor()) + 1.0;
            if n.is_finite() && n < u64::MAX as f64 {
                n as u64
            } else {
                u64::MAX
            }
        };
        let (nx, ny) = (cells(lo.x, hi.x), cells(lo.y, hi.y));
        if nx.saturating_mul(ny) > max_cells as u64 {
            return Err(LtmError::RegionTooLarge {
                nx,
                ny,
                resolution_m,
                limit: max_cells,
            });
        }
        let layout = QueryLayout {
            i0: lattice_index(lo.x, resolution_m),
            j0: lattice_index(lo.y, resolution_m),
            nx: nx as usize,
            ny: ny as usize,
        };
        Ok(Self {
            corners: pts,
            resolution_m,
            layout,
        })
    }

    /// The cell size, metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// The enclosing grid.
    pub fn layout(&self) -> QueryLayout {
        self.layout
    }

    /// The polygon's corners.
    pub fn corners(&self) -> &[Point2<f64>] {
        &self.corners
    }

    /// World centre of the query lattice cell `(i, j)`.
    pub fn center(&self, i: i64, j: i64) -> Point2<f64> {
        Point2::new(i as f64 * self.resolution_m, j as f64 * self.resolution_m)
    }

    /// Whether a point is inside the polygon (even-odd rule; points on an edge are inside).
    pub fn contains(&self, p: Point2<f64>) -> bool {
        let n = self.corners.len();
        let mut inside = false;
        for k in 0..n {
            let a = self.corners[k];
            let b = self.corners[(k + 1) % n];
            // On the edge?
            let ab = b - a;
            let ap = p - a;
            let cross = ab.x * ap.y - ab.y * ap.x;
            let len2 = ab.norm_squared();
            if cross.abs() <= 1e-9 * len2.sqrt().max(1e-12) {
                let t = ap.dot(&ab);
                if t >= -1e-12 && t <= len2 + 1e-12 {
                    return true;
                }
            }
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pp(x: f64, y: f64) -> PlanePoint {
        PlanePoint { x_m: x, y_m: y }
    }

    #[test]
    fn bad_regions_are_refused_with_reasons() {
        let tri = [pp(0.0, 0.0), pp(1.0, 0.0), pp(0.0, 1.0)];
        let e = Region::new(&tri[..2], 0.1, 1000).unwrap_err().to_string();
        assert!(e.contains("at least three"), "{e}");
        let e = Region::new(&tri, 0.0, 1000).unwrap_err().to_string();
        assert!(e.contains("greater than zero"), "{e}");
        assert!(Region::new(&tri, f64::NAN, 1000).is_err());
        assert!(Region::new(&tri, -1.0, 1000).is_err());
        let e = Region::new(&[pp(0.0, 0.0), pp(1.0, 1.0), pp(2.0, 2.0)], 0.1, 1000)
            .unwrap_err()
            .to_string();
        assert!(e.contains("zero area"), "{e}");
        let e = Region::new(
            &[pp(0.0, f64::INFINITY), pp(1.0, 0.0), pp(0.0, 1.0)],
            0.1,
            1000,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("corner 0"), "{e}");
        let e = Region::new(&tri, 1e-6, 1000).unwrap_err().to_string();
        assert!(e.contains("coarser"), "{e}");
        let huge = [pp(-1e300, -1e300), pp(1e300, -1e300), pp(0.0, 1e300)];
        assert!(Region::new(&huge, 0.1, 1000).is_err());
        // Far away but small: refused before any index could overflow.
        let far = [pp(1e25, 0.0), pp(1e25, 1e6), pp(1e25 + 1e10, 0.0)];
        let e = Region::new(&far, 1e6, 1000).unwrap_err().to_string();
        assert!(e.contains("beyond the map's reach"), "{e}");
    }

    #[test]
    fn the_grid_encloses_the_polygon() {
        let r = Region::new(&[pp(0.02, 0.02), pp(0.98, 0.02), pp(0.5, 0.51)], 0.1, 1000).unwrap();
        let l = r.layout();
        assert_eq!((l.i0, l.j0, l.nx, l.ny), (0, 0, 11, 6));
        assert!(r.contains(Point2::new(0.5, 0.2)));
        assert!(!r.contains(Point2::new(0.1, 0.4)));
        assert!(r.contains(Point2::new(0.02, 0.02)), "corners are inside");
        assert!(r.contains(Point2::new(0.5, 0.02)), "edges are inside");
    }

    proptest! {
        #[test]
        fn every_corner_is_in_a_grid_cell(
            pts in proptest::collection::vec((-50.0..50.0f64, -50.0..50.0f64), 3..8),
            res in 0.05..2.0f64,
        ) {
            let corners: Vec<_> = pts.iter().map(|&(x, y)| pp(x, y)).collect();
            let Ok(r) = Region::new(&corners, res, 10_000_000) else { return Ok(()); };
            let l = r.layout();
            for c in r.corners() {
                let i = lattice_index(c.x, res);
                let j = lattice_index(c.y, res);
                prop_assert!(i >= l.i0 && i < l.i0 + l.nx as i64);
                prop_assert!(j >= l.j0 && j < l.j0 + l.ny as i64);
                prop_assert!(r.contains(*c));
            }
        }
    }
}
