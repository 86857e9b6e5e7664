//! Footfall evaluation and slope (§5.2.2): how good a place is for the 30 cm foot.
//!
//! The elevations of the map cells whose centres lie within the foot's radius of a point are
//! fitted with a plane by least squares. The **footfall cost** is the largest distance (in
//! elevation) of a cell from that plane, metres: 0 on a plane of any slope, growing with rocks,
//! edges and holes under the foot. The **slope** is the fitted plane's angle from level,
//! radians (the mean slope over the foot's area). If any cell under the foot is occluded the
//! point is occluded (carrying the highest elevation possible under the foot); if fewer than
//! `min_known_fraction` of the cells are known it is unknown.

use nalgebra::{Matrix3, Point2, Vector3};

use crate::cell::CellState;
use crate::patch::Patch;

/// Parameters of the evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootParams {
    /// Radius of the foot, metres (0.15 for the 30 cm foot).
    pub radius_m: f64,
    /// Fraction of the cells under the foot that must be known.
    pub min_known_fraction: f64,
}

impl Default for FootParams {
    fn default() -> Self {
        Self {
            radius_m: 0.15,
            min_known_fraction: 0.8,
        }
    }
}

/// The evaluation of one place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Footing {
    /// Enough of the terrain under the foot was seen.
    Known {
        /// Largest deviation from the fitted plane, metres.
        cost_m: f64,
        /// Angle of the fitted plane from level, radians.
        slope_rad: f64,
        /// Mean elevation standard deviation of the cells under the foot, metres.
        sigma_m: f64,
    },
    /// Part of the terrain under the foot is hidden.
    Occluded {
        /// Highest elevation possible under the foot, metres.
        max_elevation_m: f32,
    },
    /// Too little of the terrain under the foot was seen.
    Unknown,
}

/// Evaluates places, reusing its scratch space.
#[derive(Debug, Default)]
pub struct FootEvaluator {
    scratch: Vec<(f64, f64, f64)>,
}

impl FootEvaluator {
    /// An evaluator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Evaluates the foot centred at `center` on the cells of `patch` (the patch must cover
    /// the foot: cells outside it count as unknown).
    pub fn evaluate(&mut self, patch: &Patch, center: Point2<f64>, params: &FootParams) -> Footing {
        let res = patch.resolution_m;
        let radius = params.radius_m.max(1.5 * res);
        let r2 = radius * radius;
        let (ia, ib) = (
            ((center.x - radius) / res).ceil() as i64,
            ((center.x + radius) / res).floor() as i64,
        );
        let (ja, jb) = (
            ((center.y - radius) / res).ceil() as i64,
            ((center.y + radius) / res).floor() as i64,
        );
        self.scratch.clear();
        let mut total = 0usize;
        let mut occluded = false;
        let mut highest = f32::NEG_INFINITY;
        let mut sigma_sum = 0.0;
        for j in ja..=jb {
            let v = j as f64 * res - center.y;
            for i in ia..=ib {
                let u = i as f64 * res - center.x;
                if u * u + v * v > r2 {
                    continue;
                }
                total += 1;
                let c = patch.get(i, j);
                match c.state {
                    CellState::Unknown => {}
                    CellState::Occluded => {
                        occluded = true;
                        highest = highest.max(c.elevation_m);
                    }
                    CellState::Known => {
                        highest = highest.max(c.elevation_m);
                        sigma_sum += f64::from(c.sigma_m);
                        self.scratch.push((u, v, f64::from(c.elevation_m)));
                    }
                }
            }
        }
        if occluded {
            return Footing::Occluded {
                max_elevation_m: highest,
            };
        }
        let known = self.scratch.len();
        if known < 3 || (known as f64) < params.min_known_fraction * total as f64 {
            return Footing::Unknown;
        }
        // Least-squares plane z = a + b u + c v.
        let mut m = Matrix3::zeros();
        let mut rhs = Vector3::zeros();
        for &(u, v, z) in &self.scratch {
            let row = Vector3::new(1.0, u, v);
            m += row * row.transpose();
            rhs += row * z;
        }
        let Some(coef) = m.lu().solve(&rhs) else {
            return Footing::Unknown;
        };
        let cost = self
            .scratch
            .iter()
            .map(|&(u, v, z)| (z - (coef.x + coef.y * u + coef.z * v)).abs())
            .fold(0.0, f64::max);
        Footing::Known {
            cost_m: cost,
            slope_rad: coef.y.hypot(coef.z).atan(),
            sigma_m: sigma_sum / known as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cell::Cell;

    fn patch(f: impl Fn(f64, f64) -> Cell) -> Patch {
        let mut p = Patch::unknown(-20, -20, 40, 40, 0.05);
        for j in -20..20 {
            for i in -20..20 {
                let c = p.center(i, j);
                if let Some(cell) = p.get_mut(i, j) {
                    *cell = f(c.x, c.y);
                }
            }
        }
        p
    }

    #[test]
    fn a_tilted_plane_is_a_perfect_footfall_with_its_slope() {
        let p = patch(|x, y| Cell::known((0.2 * x + 0.1 * y) as f32, 0.01));
        let mut e = FootEvaluator::new();
        let Footing::Known {
            cost_m,
            slope_rad,
            sigma_m,
        } = e.evaluate(&p, Point2::new(0.01, -0.02), &FootParams::default())
        else {
            panic!("expected known");
        };
        assert!(cost_m < 1e-6, "{cost_m}");
        assert!(
            (slope_rad - 0.05f64.sqrt().atan()).abs() < 1e-6,
            "{slope_rad}"
        );
        assert!((sigma_m - 0.01).abs() < 1e-6);
    }

    #[test]
    fn a_step_under_the_foot_costs_about_half_its_height() {
        let p = patch(|x, _| Cell::known(if x > 0.0 { 0.2 } else { 0.0 }, 0.01));
        let Footing::Known { cost_m, .. } =
            FootEvaluator::new().evaluate(&p, Point2::origin(), &FootParams::default())
        else {
            panic!("expected known");
        };
        assert!(cost_m > 0.05 && cost_m < 0.2, "{cost_m}");
    }

    #[test]
    fn occluded_and_unknown_cells_are_reported() {
        let params = FootParams::default();
        let p = patch(|x, y| {
            if x.hypot(y) < 0.06 {
                Cell::occluded(0.7)
            } else {
                Cell::known(0.0, 0.01)
            }
        });
        assert_eq!(
            FootEvaluator::new().evaluate(&p, Point2::origin(), &params),
            Footing::Occluded {
                max_elevation_m: 0.7
            }
        );
        let p = patch(|x, _| {
            if x < 0.0 {
                Cell::UNKNOWN
            } else {
                Cell::known(0.0, 0.01)
            }
        });
        assert_eq!(
            FootEvaluator::new().evaluate(&p, Point2::origin(), &params),
            Footing::Unknown
        );
        // Off the patch entirely.
        assert_eq!(
            FootEvaluator::new().evaluate(&p, Point2::new(50.0, 0.0), &params),
            Footing::Unknown
        );
    }
}
