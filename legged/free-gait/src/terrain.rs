//! What the gait knows of the terrain: [`TerrainView`], and [`GridView`] over a known
//! height field.

use std::sync::Arc;

use nalgebra::Point2;
use tca_robot::HeightField;

/// The terrain as the gait may see it. `None` means unknown: unknown terrain is never
/// stepped on, and a swing never passes over it.
pub trait TerrainView {
    /// The height of the ground at a point, metres.
    fn height_at(&self, p: Point2<f64>) -> Option<f64>;
    /// The highest the ground at a point can be, metres: its height where it is known, and
    /// where it is not but is bounded (hidden behind something seen, or a small gap among
    /// seen ground), that bound; `None` when nothing bounds it. A swinging foot keeps its
    /// clearance above this, so it may pass over ground it cannot stand on.
    fn height_bound_at(&self, p: Point2<f64>) -> Option<f64> {
        self.height_at(p)
    }
    /// The highest ground within a disc, metres.
    fn max_height_in_disc(&self, c: Point2<f64>, r: f64) -> Option<f64>;
    /// How bad a foothold centred at `p` is for a foot of this radius: 0 is ideal, larger
    /// is worse, infinity is forbidden; `None` when unknown.
    fn foothold_cost(&self, p: Point2<f64>, foot_radius_m: f64) -> Option<f64>;
}

impl<T: TerrainView + ?Sized> TerrainView for &T {
    fn height_at(&self, p: Point2<f64>) -> Option<f64> {
        (**self).height_at(p)
    }
    fn height_bound_at(&self, p: Point2<f64>) -> Option<f64> {
        (**self).height_bound_at(p)
    }
    fn max_height_in_disc(&self, c: Point2<f64>, r: f64) -> Option<f64> {
        (**self).max_height_in_disc(c, r)
    }
    fn foothold_cost(&self, p: Point2<f64>, foot_radius_m: f64) -> Option<f64> {
        (**self).foothold_cost(p, foot_radius_m)
    }
}

/// A [`TerrainView`] that knows a whole height field (the true terrain, in simulation):
/// everything inside its sampled rectangle is known, nothing outside.
///
/// The foothold cost of a disc is how far the ground in it strays from the plane tangent
/// at its centre (in foot radii) plus the slope's tangent; footholds straddling a step of
/// more than `max_residual` foot radii or steeper than `max_slope_rad` are forbidden.
#[derive(Debug, Clone)]
pub struct GridView {
    terrain: Arc<HeightField>,
    /// Steepest slope a foot may stand on, radians.
    pub max_slope_rad: f64,
    /// Largest departure of the ground under the foot from its tangent plane, in foot
    /// radii.
    pub max_residual: f64,
}

impl GridView {
    /// The steepest slope a foot may stand on unless set otherwise: 35 degrees, radians.
    pub const DEFAULT_MAX_SLOPE_RAD: f64 = 35.0 * std::f64::consts::PI / 180.0;
    /// The largest departure from the tangent plane under a foot unless set otherwise, in
    /// foot radii.
    pub const DEFAULT_MAX_RESIDUAL: f64 = 0.3;

    /// A view of a height field (slopes up to [`Self::DEFAULT_MAX_SLOPE_RAD`], departures up
    /// to [`Self::DEFAULT_MAX_RESIDUAL`] foot radii).
    pub fn new(terrain: Arc<HeightField>) -> Self {
        GridView {
            terrain,
            max_slope_rad: Self::DEFAULT_MAX_SLOPE_RAD,
            max_residual: Self::DEFAULT_MAX_RESIDUAL,
        }
    }

    /// The height field seen.
    pub fn terrain(&self) -> &HeightField {
        &self.terrain
    }

    fn inside(&self, p: Point2<f64>, margin: f64) -> bool {
        let (lo, hi) = self.terrain.extent();
        p.x.is_finite()
            && p.y.is_finite()
            && p.x - margin >= lo.x
            && p.x + margin <= hi.x
            && p.y - margin >= lo.y
            && p.y + margin <= hi.y
    }
}

impl From<HeightField> for GridView {
    fn from(terrain: HeightField) -> Self {
        GridView::new(Arc::new(terrain))
    }
}

impl TerrainView for GridView {
    fn height_at(&self, p: Point2<f64>) -> Option<f64> {
        self.inside(p, 0.0)
            .then(|| self.terrain.height_at(p.x, p.y))
    }

    fn max_height_in_disc(&self, c: Point2<f64>, r: f64) -> Option<f64> {
        self.inside(c, r.max(0.0))
            .then(|| self.terrain.max_height_in_disc(c, r))
    }

    fn foothold_cost(&self, p: Point2<f64>, foot_radius_m: f64) -> Option<f64> {
        let r = foot_radius_m.max(self.terrain.grid().resolution_m());
        if !self.inside(p, r) {
            return None;
        }
        let n = self.terrain.normal_at(p.x, p.y);
        let slope = n.z.clamp(-1.0, 1.0).acos();
        if slope > self.max_slope_rad {
            return Some(f64::INFINITY);
        }
        let h0 = self.terrain.height_at(p.x, p.y);
        let (gx, gy) = (-n.x / n.z, -n.y / n.z);
        let mut residual: f64 = 0.0;
        for ring in [0.5, 1.0] {
            for k in 0..12 {
                let a = f64::from(k) * std::f64::consts::TAU / 12.0;
                let (dx, dy) = (ring * r * a.cos(), ring * r * a.sin());
                let h = self.terrain.height_at(p.x + dx, p.y + dy);
                residual = residual.max((h - (h0 + gx * dx + gy * dy)).abs());
            }
        }
        let relative = residual / r;
        if relative > self.max_residual {
            return Some(f64::INFINITY);
        }
        Some(relative + slope.tan())
    }
}
