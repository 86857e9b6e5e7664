//! Whether the ground under a foot will do: the plane fitted to the terrain under the foot's
//! footprint, its slope and how far the ground strays from it (evenness), as a
//! traversability analysis classifies a digital elevation model's cells.

use nalgebra::{Matrix3, Point2, Vector3};
use serde::{Deserialize, Serialize};
use tca_robot::HeightField;

/// The limits a foothold's ground must keep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GroundRules {
    /// Steepest plane under the foot, radians.
    pub max_slope_rad: f64,
    /// Largest distance of the ground under the foot from that plane, metres.
    pub max_roughness_m: f64,
}

impl Default for GroundRules {
    /// 20° and 6 cm: a wheel of 0.5 m stands on gentle relief, not on a rock's flank or
    /// astride a rock's edge.
    fn default() -> Self {
        Self {
            max_slope_rad: 20f64.to_radians(),
            max_roughness_m: 0.06,
        }
    }
}

/// The plane fitted under a footprint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GroundFit {
    /// Its slope, radians.
    pub slope_rad: f64,
    /// The largest distance of a ground point from it, metres.
    pub roughness_m: f64,
    /// Ground points used.
    pub points: usize,
}

impl GroundFit {
    /// Whether the fit keeps the rules.
    pub fn acceptable(&self, rules: &GroundRules) -> bool {
        self.slope_rad <= rules.max_slope_rad && self.roughness_m <= rules.max_roughness_m
    }

    /// Why it does not, or `None`.
    pub fn rejection(&self, rules: &GroundRules) -> Option<String> {
        if self.slope_rad > rules.max_slope_rad {
            Some(format!(
                "the ground under the foot slopes {:.0}° (at most {:.0}°)",
                self.slope_rad.to_degrees(),
                rules.max_slope_rad.to_degrees()
            ))
        } else if self.roughness_m > rules.max_roughness_m {
            Some(format!(
                "the ground under the foot strays {:.0} cm from its plane (at most {:.0} cm)",
                self.roughness_m * 100.0,
                rules.max_roughness_m * 100.0
            ))
        } else {
            None
        }
    }
}

/// Whether a disc lies inside the terrain's sampled rectangle.
pub fn disc_inside(terrain: &HeightField, c: Point2<f64>, r: f64) -> bool {
    let (lo, hi) = terrain.extent();
    c.x.is_finite()
        && c.y.is_finite()
        && c.x - r >= lo.x
        && c.x + r <= hi.x
        && c.y - r >= lo.y
        && c.y + r <= hi.y
}

/// The plane through the terrain's samples within `radius` of `c` (at least the four
/// around `c`), or `None` when the disc leaves the terrain.
pub fn fit_footprint(terrain: &HeightField, c: Point2<f64>, radius: f64) -> Option<GroundFit> {
    if !disc_inside(terrain, c, radius) {
        return None;
    }
    let g = terrain.grid();
    let res = g.resolution_m();
    let r = radius.max(res);
    let mut points = Vec::new();
    if let Some((xs, ys)) =
        g.cell_range(Point2::new(c.x - r, c.y - r), Point2::new(c.x + r, c.y + r))
    {
        for iy in ys {
            for ix in xs.clone() {
                let x = g.origin().x + ix as f64 * res;
                let y = g.origin().y + iy as f64 * res;
                if (x - c.x).powi(2) + (y - c.y).powi(2) <= r * r {
                    points.push(Vector3::new(x - c.x, y - c.y, g.cells()[iy * g.nx() + ix]));
                }
            }
        }
    }
    if points.len() < 3 {
        for (dx, dy) in [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)] {
            let (x, y) = (c.x + dx * res, c.y + dy * res);
            points.push(Vector3::new(x - c.x, y - c.y, terrain.height_at(x, y)));
        }
    }
    Some(fit_points(&points))
}

/// The least-squares plane `z = a + b x + c y` through points given relative to the
/// footprint's centre.
pub fn fit_points(points: &[Vector3<f64>]) -> GroundFit {
    let mut m = Matrix3::zeros();
    let mut v = Vector3::zeros();
    for p in points {
        let row = Vector3::new(1.0, p.x, p.y);
        m += row * row.transpose();
        v += row * p.z;
    }
    let coef = m.try_inverse().map(|inv| inv * v).unwrap_or_else(|| {
        Vector3::new(
            points.iter().map(|p| p.z).sum::<f64>() / points.len().max(1) as f64,
            0.0,
            0.0,
        )
    });
    let slope_rad = coef.y.hypot(coef.z).atan();
    let roughness_m = points
        .iter()
        .map(|p| (p.z - (coef.x + coef.y * p.x + coef.z * p.y)).abs())
        .fold(0.0, f64::max);
    GroundFit {
        slope_rad,
        roughness_m,
        points: points.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(f: impl Fn(f64, f64) -> f64) -> HeightField {
        let (nx, ny, res) = (41, 41, 0.05);
        let mut h = Vec::new();
        for iy in 0..ny {
            for ix in 0..nx {
                h.push(f(ix as f64 * res, iy as f64 * res));
            }
        }
        HeightField::new(Point2::origin(), res, nx, ny, h).unwrap()
    }

    #[test]
    fn a_tilted_plane_has_its_slope_and_no_roughness() {
        let t = field(|x, _| 0.2 * x);
        let fit = fit_footprint(&t, Point2::new(1.0, 1.0), 0.25).unwrap();
        assert!((fit.slope_rad - 0.2f64.atan()).abs() < 1e-9);
        assert!(fit.roughness_m < 1e-9);
        assert!(fit.points > 70);
        assert!(fit.acceptable(&GroundRules::default()));
    }

    #[test]
    fn a_step_under_the_foot_is_rough_and_refused() {
        let t = field(|x, _| if x > 1.0 { 0.3 } else { 0.0 });
        let fit = fit_footprint(&t, Point2::new(1.0, 1.0), 0.25).unwrap();
        assert!(fit.roughness_m > 0.1, "{fit:?}");
        let why = fit.rejection(&GroundRules::default()).unwrap();
        assert!(why.contains("slopes") || why.contains("strays"), "{why}");
    }

    #[test]
    fn a_footprint_off_the_terrain_has_no_fit() {
        let t = field(|_, _| 0.0);
        assert!(fit_footprint(&t, Point2::new(0.1, 1.0), 0.25).is_none());
        assert!(fit_footprint(&t, Point2::new(f64::NAN, 1.0), 0.25).is_none());
    }
}
