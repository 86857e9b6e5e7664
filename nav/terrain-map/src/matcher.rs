//! The LTM Matcher: registers a new frame's points against the map so far, to estimate how
//! far the pose the points were placed with is off.
//!
//! The points are compared with the map's surface (heights interpolated bilinearly between
//! cell centres, from every frame so far). A planar correction about a pivot (the robot's
//! position), a shift east and north and a turn, together with a height offset (the map
//! keeps each cell's highest point, so it stands a little above a single point), is found by
//! Gauss-Newton on the height differences with Huber weights. The correction is refused when
//! too few points fall on known ground, when the ground is too even in some direction to
//! tell a shift along it, or when it comes out larger than the bounds.
//!
//! On a 2 cm grid one registration is good to about a millimetre (the maxima of two
//! binnings of the same ground differ by their sampling); a robot whose odometry drifts by
//! less than that between frames gains nothing from matching every frame, and the
//! corrections' own errors add up instead.

use nalgebra::{Matrix4, Point2, Point3, Vector4};
use tca_nav_danger_map::HeightView;

use crate::TerrainMap;

/// How the matcher works.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchParams {
    /// Cells of the frame's local map used at most (taken evenly).
    pub max_points: usize,
    /// Farthest point used, m from the pivot: stereo's noise grows with the square of the
    /// range, and the highest of noisy points stands higher the more there are, so far
    /// cells disagree between frames in a way that looks like a shift.
    pub max_range_m: f64,
    /// Points a cell of the frame's local map needs to be used.
    pub min_hits: usize,
    /// Cells on known ground needed.
    pub min_points: usize,
    /// Gauss-Newton iterations.
    pub iterations: usize,
    /// Huber threshold of the height differences, m.
    pub huber_m: f64,
    /// Largest shift accepted, m.
    pub max_shift_m: f64,
    /// Largest turn accepted, rad.
    pub max_turn_rad: f64,
    /// Least information per point in every direction of the planar correction (the
    /// smallest eigenvalue of the normal matrix over the point count, in squared slope for
    /// the shift): the ground's gradient must tell every direction apart.
    pub min_information: f64,
    /// Fraction of each correction a map applies to the pose it places frames with (the
    /// registration reports all of it); below 1 the corrections' own noise is averaged.
    pub gain: f64,
}

impl Default for MatchParams {
    /// 1,500 cells of points within 2 m hit by at least 4 points each, at least 300 on known
    /// ground, 4 iterations, Huber at 15 mm, corrections
    /// up to 30 mm and 0.03 rad, least information 0.0003 (a mean squared slope of about
    /// 1° in the weakest direction), half of each correction applied.
    fn default() -> Self {
        MatchParams {
            max_points: 1500,
            max_range_m: 2.0,
            min_hits: 4,
            min_points: 300,
            iterations: 4,
            huber_m: 0.015,
            max_shift_m: 0.03,
            max_turn_rad: 0.03,
            min_information: 0.0003,
            gain: 0.5,
        }
    }
}

/// A correction found by the matcher: the points (and the pose they were placed with)
/// belong `dx_m`, `dy_m` away and turned by `dyaw_rad` about the pivot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Registration {
    /// Shift east, m.
    pub dx_m: f64,
    /// Shift north, m.
    pub dy_m: f64,
    /// Turn about the pivot, rad.
    pub dyaw_rad: f64,
    /// Points on known ground.
    pub points: usize,
    /// RMS height difference before, m (after removing the mean offset).
    pub rms_before_m: f64,
    /// RMS height difference after, m.
    pub rms_after_m: f64,
}

impl Registration {
    /// The correction scaled by `k` (shift and turn).
    pub fn scaled(&self, k: f64) -> Registration {
        Registration {
            dx_m: k * self.dx_m,
            dy_m: k * self.dy_m,
            dyaw_rad: k * self.dyaw_rad,
            ..*self
        }
    }

    /// A point moved by the correction.
    pub fn apply(&self, pivot: Point2<f64>, p: Point2<f64>) -> Point2<f64> {
        let (s, c) = self.dyaw_rad.sin_cos();
        let (x, y) = (p.x - pivot.x, p.y - pivot.y);
        Point2::new(
            pivot.x + c * x - s * y + self.dx_m,
            pivot.y + s * x + c * y + self.dy_m,
        )
    }
}

/// The map's height at a world point and its gradient, bilinear between the four cell
/// centres around it (all four known).
fn surface(map: &TerrainMap, p: Point2<f64>) -> Option<(f64, f64, f64)> {
    let (origin, res, _, _) = map.geometry();
    let gx = (p.x - origin.x) / res;
    let gy = (p.y - origin.y) / res;
    let (x0, y0) = (gx.floor(), gy.floor());
    if !(x0.is_finite() && y0.is_finite()) {
        return None;
    }
    let (u, v) = (gx - x0, gy - y0);
    let (ix, iy) = (x0 as isize, y0 as isize);
    let view = map.all();
    let h00 = view.height(ix, iy)?;
    let h10 = view.height(ix + 1, iy)?;
    let h01 = view.height(ix, iy + 1)?;
    let h11 = view.height(ix + 1, iy + 1)?;
    let h = h00 * (1.0 - u) * (1.0 - v) + h10 * u * (1.0 - v) + h01 * (1.0 - u) * v + h11 * u * v;
    let hx = ((h10 - h00) * (1.0 - v) + (h11 - h01) * v) / res;
    let hy = ((h01 - h00) * (1.0 - u) + (h11 - h10) * u) / res;
    Some((h, hx, hy))
}

fn huber(r: f64, k: f64) -> f64 {
    if r.abs() <= k { 1.0 } else { k / r.abs() }
}

impl TerrainMap {
    /// Registers `points` (world frame, placed with the pose whose position is `pivot`)
    /// against the map so far. `None` when the correction cannot be told (see the module
    /// docs).
    pub fn register(
        &self,
        points: &[Point3<f64>],
        pivot: Point2<f64>,
        params: &MatchParams,
    ) -> Option<Registration> {
        if points.is_empty() || params.max_points == 0 {
            return None;
        }
        // The frame's own local map (highest point per cell, as the map keeps them), as
        // points at the cell centres: like is compared with like.
        let (origin, res, nx, ny) = self.geometry();
        let mut local: std::collections::HashMap<(i64, i64), (f64, usize)> =
            std::collections::HashMap::new();
        for p in points {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite())
                || (p.x - pivot.x).hypot(p.y - pivot.y) > params.max_range_m
            {
                continue;
            }
            let ix = ((p.x - origin.x) / res + 0.5).floor() as i64;
            let iy = ((p.y - origin.y) / res + 0.5).floor() as i64;
            if ix < 0 || iy < 0 || ix >= nx as i64 || iy >= ny as i64 {
                continue;
            }
            let h = local.entry((ix, iy)).or_insert((f64::NEG_INFINITY, 0));
            h.0 = h.0.max(p.z);
            h.1 += 1;
        }
        // Cells hit by few points keep a maximum lower than the map's: left out.
        let mut cells: Vec<((i64, i64), f64)> = local
            .into_iter()
            .filter(|(_, (_, n))| *n >= params.min_hits)
            .map(|(c, (z, _))| (c, z))
            .collect();
        cells.sort_unstable_by_key(|c| c.0);
        let step = cells.len().div_ceil(params.max_points).max(1);
        let pts: Vec<Point3<f64>> = cells
            .iter()
            .step_by(step)
            .map(|&((ix, iy), z)| {
                Point3::new(origin.x + ix as f64 * res, origin.y + iy as f64 * res, z)
            })
            .collect();
        // Unknowns: shift east, shift north, turn, height offset.
        let mut t = Vector4::zeros();
        let mut rms_before = None;
        let mut last = (0usize, 0.0, Matrix4::zeros());
        for _ in 0..params.iterations.max(1) {
            let reg = Registration {
                dx_m: t[0],
                dy_m: t[1],
                dyaw_rad: t[2],
                points: 0,
                rms_before_m: 0.0,
                rms_after_m: 0.0,
            };
            let mut h = Matrix4::zeros();
            let mut g = Vector4::zeros();
            let (mut n, mut sum, mut sum2) = (0usize, 0.0, 0.0);
            for p in &pts {
                let q = reg.apply(pivot, Point2::new(p.x, p.y));
                let Some((z, hx, hy)) = surface(self, q) else {
                    continue;
                };
                let r = p.z - z - t[3];
                // d(q)/d(turn) about the pivot, after the shift.
                let (ox, oy) = (q.x - pivot.x - t[0], q.y - pivot.y - t[1]);
                let j = Vector4::new(-hx, -hy, -(hx * -oy + hy * ox), -1.0);
                let w = huber(r, params.huber_m);
                h += w * j * j.transpose();
                g += w * j * r;
                n += 1;
                sum += r + t[3];
                sum2 += (r + t[3]).powi(2);
            }
            if n < params.min_points {
                return None;
            }
            let mean = sum / n as f64;
            let rms = (sum2 / n as f64 - mean * mean).max(0.0).sqrt();
            rms_before.get_or_insert(rms);
            last = (n, rms, h);
            let delta = h.lu().solve(&(-g))?;
            t += delta;
        }
        let (n, _, h) = last;
        // The planar block's weakest direction, per point (shift in slope², turn scaled by
        // one metre of lever).
        let planar = h.fixed_view::<3, 3>(0, 0).into_owned() / n as f64;
        let min_eig = planar.symmetric_eigenvalues().min();
        if min_eig.is_nan() || min_eig < params.min_information {
            return None;
        }
        if !(t[0].hypot(t[1]) <= params.max_shift_m && t[2].abs() <= params.max_turn_rad) {
            return None;
        }
        // The fit after the last step.
        let reg = Registration {
            dx_m: t[0],
            dy_m: t[1],
            dyaw_rad: t[2],
            points: n,
            rms_before_m: rms_before.unwrap_or(0.0),
            rms_after_m: 0.0,
        };
        let res: Vec<f64> = pts
            .iter()
            .filter_map(|p| {
                let q = reg.apply(pivot, Point2::new(p.x, p.y));
                surface(self, q).map(|(z, _, _)| p.z - z)
            })
            .collect();
        let m = res.iter().sum::<f64>() / res.len().max(1) as f64;
        let rms_after =
            (res.iter().map(|r| (r - m).powi(2)).sum::<f64>() / res.len().max(1) as f64).sqrt();
        Some(Registration {
            rms_after_m: rms_after,
            ..reg
        })
    }
}
