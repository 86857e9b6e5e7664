//! Ray casting against a height field.
//!
//! A maximum mip-map (level 0: the highest corner of each bilinear patch; level k: the maximum
//! over 2^k x 2^k patches) lets a ray skip, in one step, any block it passes above. Where a
//! level-0 patch is not skipped, the ray is intersected exactly with the bilinear patch (a
//! quadratic in the ray parameter), so the hit is exact to floating-point precision.

use nalgebra::{Point3, Vector3};

use super::HeightField;
use crate::grid::Grid;

/// Where a ray meets the terrain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// The hit point, world frame, metres.
    pub point: Point3<f64>,
    /// Distance from the ray origin along the (normalised) direction, metres.
    pub range_m: f64,
    /// Upward unit normal of the surface at the hit.
    pub normal: Vector3<f64>,
}

/// Maximum mip-map over the bilinear patches of a height grid.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MaxMip {
    levels: Vec<Level>,
}

#[derive(Debug, Clone, PartialEq)]
struct Level {
    nx: usize,
    ny: usize,
    max: Vec<f64>,
}

impl MaxMip {
    pub(crate) fn build(grid: &Grid<f64>) -> Self {
        let (nx, ny) = (grid.nx() - 1, grid.ny() - 1);
        let h = grid.cells();
        let gnx = grid.nx();
        let mut base = Vec::with_capacity(nx * ny);
        for iy in 0..ny {
            for ix in 0..nx {
                let i = iy * gnx + ix;
                base.push(h[i].max(h[i + 1]).max(h[i + gnx]).max(h[i + gnx + 1]));
            }
        }
        let mut levels = vec![Level { nx, ny, max: base }];
        while let Some(prev) = levels.last().filter(|l| l.nx > 1 || l.ny > 1) {
            let (cx, cy) = (prev.nx.div_ceil(2), prev.ny.div_ceil(2));
            let mut max = vec![f64::NEG_INFINITY; cx * cy];
            for iy in 0..prev.ny {
                for ix in 0..prev.nx {
                    let v = prev.max[iy * prev.nx + ix];
                    let slot = &mut max[(iy / 2) * cx + ix / 2];
                    *slot = slot.max(v);
                }
            }
            levels.push(Level { nx: cx, ny: cy, max });
        }
        Self { levels }
    }
}

impl HeightField {
    /// Casts a ray from `origin` along `direction` (any length; normalised here) up to
    /// `max_range_m` and returns the first point where it meets the surface, or `None` if it
    /// leaves the sampled rectangle or the range first. A ray starting under the surface
    /// hits at its origin (range 0).
    pub fn cast_ray(
        &self,
        origin: &Point3<f64>,
        direction: &Vector3<f64>,
        max_range_m: f64,
    ) -> Option<RayHit> {
        let norm = direction.norm();
        if !(norm > 0.0 && norm.is_finite() && max_range_m.is_finite() && max_range_m >= 0.0) {
            return None;
        }
        if !(origin.x.is_finite() && origin.y.is_finite() && origin.z.is_finite()) {
            return None;
        }
        let d = direction / norm;
        let res = self.grid.resolution_m();
        let o = self.grid.origin();
        // Ray in grid coordinates: g(t) = g0 + gd t; patch (i, j) spans [i, i+1] x [j, j+1].
        let g0 = [(origin.x - o.x) / res, (origin.y - o.y) / res];
        let gd = [d.x / res, d.y / res];
        let extent = [(self.grid.nx() - 1) as f64, (self.grid.ny() - 1) as f64];

        let mut t_lo = 0.0_f64;
        let mut t_hi = max_range_m;
        for axis in 0..2 {
            if gd[axis] == 0.0 {
                if g0[axis] < 0.0 || g0[axis] > extent[axis] {
                    return None;
                }
            } else {
                let inv = 1.0 / gd[axis];
                let (a, b) = ((0.0 - g0[axis]) * inv, (extent[axis] - g0[axis]) * inv);
                t_lo = t_lo.max(a.min(b));
                t_hi = t_hi.min(a.max(b));
            }
        }
        // The hit lies where the ray is between the lowest and highest terrain.
        if d.z < 0.0 {
            t_lo = t_lo.max((self.max_m - origin.z) / d.z);
            t_hi = t_hi.min((self.min_m - origin.z) / d.z + 1e-9);
        } else if origin.z > self.max_m {
            return None;
        } else if d.z > 0.0 && origin.z >= self.min_m {
            t_hi = t_hi.min((self.max_m - origin.z) / d.z);
        }
        if t_lo.is_nan() || t_hi.is_nan() || t_lo > t_hi {
            return None;
        }
        let t_hit = self.march(g0, gd, origin.z, d.z, t_lo, t_hi)?;
        let point = origin + d * t_hit;
        let (ix, iy, u, v) = self.patch_at(point.x, point.y);
        Some(RayHit { point, range_m: t_hit, normal: self.patch_normal(ix, iy, u, v) })
    }

    /// Walks the max mip-map from `t_lo` to `t_hi`; returns the ray parameter of the hit.
    fn march(&self, g0: [f64; 2], gd: [f64; 2], z0: f64, dz: f64, t_lo: f64, t_hi: f64) -> Option<f64> {
        let levels = &self.mip.levels;
        let top = levels.len() - 1;
        let inv = [
            if gd[0] != 0.0 { 1.0 / gd[0] } else { f64::INFINITY },
            if gd[1] != 0.0 { 1.0 / gd[1] } else { f64::INFINITY },
        ];
        let step = [sign_step(gd[0]), sign_step(gd[1])];
        let mut level = top;
        let mut t = t_lo;
        let start = [g0[0] + gd[0] * t, g0[1] + gd[1] * t];
        let mut cell = [
            cell_of(start[0], level, levels[level].nx),
            cell_of(start[1], level, levels[level].ny),
        ];
        loop {
            let lv = &levels[level];
            let size = (1u64 << level) as f64;
            let mut t_axis = [f64::INFINITY; 2];
            for a in 0..2 {
                if step[a] != 0 {
                    let lo = cell[a] as f64 * size;
                    let boundary = if step[a] > 0 { lo + size } else { lo };
                    t_axis[a] = (boundary - g0[a]) * inv[a];
                }
            }
            let t_exit = t_axis[0].min(t_axis[1]).min(t_hi);
            let z_min = (z0 + dz * t).min(z0 + dz * t_exit);
            let cell_max = lv.max.get(cell[1] * lv.nx + cell[0]).copied().unwrap_or(f64::INFINITY);
            if z_min <= cell_max {
                if level == 0 {
                    if let Some(hit) = self.intersect_patch(cell[0], cell[1], g0, gd, z0, dz, t, t_exit) {
                        return Some(hit);
                    }
                } else {
                    // Descend into the child that the ray is in just after `t`.
                    let probe = t + (t_exit - t) * 1e-7;
                    let child = &levels[level - 1];
                    let half = (1u64 << (level - 1)) as f64;
                    for a in 0..2 {
                        let n = if a == 0 { child.nx } else { child.ny };
                        let g = g0[a] + gd[a] * probe;
                        let lo = cell[a] * 2;
                        let hi = (lo + 1).min(n - 1);
                        let c = if g.is_finite() && g >= 0.0 { (g / half) as usize } else { 0 };
                        cell[a] = c.clamp(lo, hi);
                    }
                    level -= 1;
                    continue;
                }
            }
            if t_exit >= t_hi {
                return None;
            }
            t = t_exit;
            let old = cell;
            let axis = if t_axis[0] <= t_axis[1] { 0 } else { 1 };
            let n = if axis == 0 { lv.nx } else { lv.ny };
            let next = cell[axis] as i64 + step[axis];
            if next < 0 || next >= n as i64 {
                return None;
            }
            cell[axis] = next as usize;
            // Climb while the step crossed the boundary of a bigger block too.
            let mut prev = old;
            while level < top && (cell[0] >> 1 != prev[0] >> 1 || cell[1] >> 1 != prev[1] >> 1) {
                cell = [cell[0] >> 1, cell[1] >> 1];
                prev = [prev[0] >> 1, prev[1] >> 1];
                level += 1;
            }
        }
    }

    /// Exact intersection of the ray with bilinear patch (ix, iy) for t in [t0, t1].
    #[allow(clippy::too_many_arguments)]
    fn intersect_patch(
        &self,
        ix: usize,
        iy: usize,
        g0: [f64; 2],
        gd: [f64; 2],
        z0: f64,
        dz: f64,
        t0: f64,
        t1: f64,
    ) -> Option<f64> {
        let [h00, h10, h01, h11] = self.corners(ix, iy);
        let (e, f, g) = (h10 - h00, h01 - h00, h00 - h10 - h01 + h11);
        let u0 = g0[0] + gd[0] * t0 - ix as f64;
        let v0 = g0[1] + gd[1] * t0 - iy as f64;
        let (a, b) = (gd[0], gd[1]);
        let zs = z0 + dz * t0;
        // F(s) = z(s) - h(u(s), v(s)) = C + B s + A s^2, s = t - t0.
        let c = zs - (h00 + e * u0 + f * v0 + g * u0 * v0);
        if c <= 0.0 {
            return Some(t0);
        }
        let bq = dz - e * a - f * b - g * (u0 * b + v0 * a);
        let aq = -g * a * b;
        let s1 = t1 - t0;
        let root = if aq.abs() < 1e-12 * (bq.abs() + 1e-300) || aq == 0.0 {
            if bq < 0.0 { Some(-c / bq) } else { None }
        } else {
            let disc = bq * bq - 4.0 * aq * c;
            if disc < 0.0 {
                None
            } else {
                let q = -0.5 * (bq + bq.signum() * disc.sqrt());
                let r1 = q / aq;
                let r2 = if q != 0.0 { c / q } else { f64::INFINITY };
                [r1, r2].into_iter().filter(|r| *r >= 0.0 && *r <= s1 * (1.0 + 1e-12) + 1e-15).reduce(f64::min)
            }
        };
        root.filter(|s| *s >= 0.0 && *s <= s1 * (1.0 + 1e-12) + 1e-15).map(|s| t0 + s.min(s1))
    }
}

fn sign_step(v: f64) -> i64 {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

fn cell_of(g: f64, level: usize, n: usize) -> usize {
    let size = (1u64 << level) as f64;
    let c = if g.is_finite() && g > 0.0 { (g / size) as usize } else { 0 };
    c.min(n - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use nalgebra::Point2;
    use proptest::prelude::*;

    fn flat(height: f64) -> HeightField {
        HeightField::flat(Point2::origin(), Point2::new(6.0, 11.0), 0.02, height).unwrap()
    }

    #[test]
    fn hits_level_ground_at_the_analytic_range() {
        let t = flat(0.0);
        let origin = Point3::new(3.0, 1.5, 4.5);
        for deg in [10.0_f64, 25.0, 45.0, 70.0, 90.0] {
            let a = deg.to_radians();
            let dir = Vector3::new(0.1, a.cos(), -a.sin());
            let hit = t.cast_ray(&origin, &dir, 100.0);
            let dn = dir.normalize();
            let range = 4.5 / -dn.z;
            let end = origin + dn * range;
            if end.x <= 6.0 && end.y <= 11.0 {
                let hit = hit.expect("hits the ground");
                assert!((hit.range_m - range).abs() < 1e-9, "{deg}: {} vs {range}", hit.range_m);
                assert!(hit.point.z.abs() < 1e-9);
                assert!((hit.normal - Vector3::z()).norm() < 1e-12);
            } else {
                assert!(hit.is_none(), "{deg}: leaves the pit");
            }
        }
    }

    #[test]
    fn hits_a_box_face_at_the_right_point() {
        // A 0.5 m box spanning y in [4, 5], x in [2, 4].
        let g = Grid::from_fn(Point2::origin(), 0.02, 301, 551, |_, p| {
            if (2.0..=4.0).contains(&p.x) && (4.0..=5.0).contains(&p.y) { 0.5 } else { 0.0 }
        })
        .unwrap();
        let t = HeightField::from_grid(g).unwrap();
        // Horizontal ray at z = 0.25 toward +Y hits the face; the bilinear face is the ramp
        // between samples y = 3.98 (0 m) and 4.00 (0.5 m): height 0.25 at y = 3.99.
        let hit = t.cast_ray(&Point3::new(3.0, 1.0, 0.25), &Vector3::y(), 20.0).unwrap();
        assert!((hit.point.y - 3.99).abs() < 1e-9, "{:?}", hit.point);
        assert!((hit.range_m - 2.99).abs() < 1e-9);
        assert!(hit.normal.y < -0.99);
        // A ray over the box lands on its top.
        let hit = t.cast_ray(&Point3::new(3.0, 4.5, 3.0), &Vector3::new(0.0, 0.0, -1.0), 20.0).unwrap();
        assert!((hit.point.z - 0.5).abs() < 1e-12 && (hit.range_m - 2.5).abs() < 1e-12);
        // A ray above everything misses.
        assert!(t.cast_ray(&Point3::new(3.0, 1.0, 0.6), &Vector3::y(), 20.0).is_none());
        // Short range stops before the box.
        assert!(t.cast_ray(&Point3::new(3.0, 1.0, 0.25), &Vector3::y(), 2.0).is_none());
    }

    #[test]
    fn degenerate_rays() {
        let t = flat(0.0);
        assert!(t.cast_ray(&Point3::new(3.0, 3.0, 1.0), &Vector3::zeros(), 10.0).is_none());
        assert!(t.cast_ray(&Point3::new(3.0, 3.0, 1.0), &Vector3::new(f64::NAN, 0.0, -1.0), 10.0).is_none());
        assert!(t.cast_ray(&Point3::new(3.0, 3.0, 1.0), &Vector3::z(), 10.0).is_none());
        let under = t.cast_ray(&Point3::new(3.0, 3.0, -0.5), &Vector3::y(), 10.0).unwrap();
        assert_eq!(under.range_m, 0.0);
        // Starting outside the pit and coming in.
        let hit = t.cast_ray(&Point3::new(-2.0, 3.0, 2.0), &Vector3::new(1.0, 0.0, -0.5), 10.0).unwrap();
        assert!((hit.point.x - 2.0).abs() < 1e-9);
    }

    /// Reference: fine march along the ray with bisection on the bilinear surface.
    fn brute_force(t: &HeightField, o: &Point3<f64>, d: &Vector3<f64>, max: f64) -> Option<f64> {
        let d = d.normalize();
        let (lo, hi) = t.extent();
        let inside = |p: &Point3<f64>| p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y;
        let f = |s: f64| {
            let p = o + d * s;
            p.z - t.height_at(p.x, p.y)
        };
        let step = 0.0005;
        let mut s = 0.0;
        let mut entered = false;
        while s <= max {
            let p = o + d * s;
            if inside(&p) {
                if !entered && f(s) <= 0.0 {
                    return Some(s);
                }
                entered = true;
                let s2 = (s + step).min(max);
                if inside(&(o + d * s2)) && f(s2) <= 0.0 {
                    let (mut a, mut b) = (s, s2);
                    for _ in 0..60 {
                        let m = 0.5 * (a + b);
                        if f(m) <= 0.0 { b = m } else { a = m }
                    }
                    return Some(b);
                }
            } else if entered {
                return None;
            }
            s += step;
        }
        None
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn agrees_with_a_fine_march_on_rough_terrain(
            seed in 0u64..1000, ox in 0.5f64..2.5, oy in 0.5f64..2.5, oz in 0.5f64..2.0,
            az in 0.0f64..std::f64::consts::TAU, el in 0.1f64..1.4,
        ) {
            let g = Grid::from_fn(Point2::origin(), 0.05, 61, 61, |c, _| {
                let k = (c.ix as u64 * 7919 + c.iy as u64 * 104_729 + seed * 31) % 1000;
                (k as f64 / 1000.0) * 0.4
            }).unwrap();
            let t = HeightField::from_grid(g).unwrap();
            let o = Point3::new(ox, oy, oz);
            let d = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), -el.sin());
            let fast = t.cast_ray(&o, &d, 10.0).map(|h| h.range_m);
            let slow = brute_force(&t, &o, &d, 10.0);
            match (fast, slow) {
                (Some(a), Some(b)) => prop_assert!((a - b).abs() < 1e-3, "fast {a} slow {b}"),
                (None, None) => {}
                // A graze thinner than the reference's step may be seen by one only.
                (a, b) => prop_assert!(false, "fast {a:?} slow {b:?}"),
            }
        }
    }
}
