//! Solids against the height field: link shapes (sphere, box, cylinder, capsule) and foot
//! spheres.
//!
//! A shape at a world pose hits the terrain when some point of it lies below the surface.
//! The test is exact at the terrain's samples and sampled in between:
//!
//! 1. a cheap bound: the shape's lowest point against the highest sample in the blocks of
//!    the grid under its bounding disc ([`BlockMax`]); most shapes stop here;
//! 2. every terrain sample under the shape's footprint that lies inside the shape (the
//!    bilinear surface has no peak between samples, so a bump poking into the shape from
//!    below shows at a sample);
//! 3. vertical rays through the footprint every half cell (at most 32 x 32 of them): where
//!    the shape's underside lies below the surface (an edge or corner of the shape sinking
//!    into a slope between samples).

use nalgebra::{Isometry3, Point2, Point3, Vector3};
use tca_legged_model::Shape;
use tca_robot::HeightField;

/// The highest sample of each block of `BLOCK` x `BLOCK` samples of a height field.
#[derive(Debug, Clone)]
pub(crate) struct BlockMax {
    bx: usize,
    by: usize,
    max: Vec<f64>,
}

const BLOCK: usize = 8;

impl BlockMax {
    pub(crate) fn new(terrain: &HeightField) -> Self {
        let g = terrain.grid();
        let (nx, ny) = (g.nx(), g.ny());
        let (bx, by) = (nx.div_ceil(BLOCK), ny.div_ceil(BLOCK));
        let mut max = vec![f64::NEG_INFINITY; bx * by];
        let cells = g.cells();
        for iy in 0..ny {
            for ix in 0..nx {
                let b = (iy / BLOCK) * bx + ix / BLOCK;
                max[b] = max[b].max(cells[iy * nx + ix]);
            }
        }
        Self { bx, by, max }
    }

    /// An upper bound of the surface over the square of half-side `r` about `c`.
    pub(crate) fn bound(&self, terrain: &HeightField, c: Point2<f64>, r: f64) -> f64 {
        let (xs, ys) = sample_range(terrain, c, r);
        let mut best = f64::NEG_INFINITY;
        for by in ys.start / BLOCK..=(ys.end - 1) / BLOCK {
            for bx in xs.start / BLOCK..=(xs.end - 1) / BLOCK {
                if by < self.by && bx < self.bx {
                    best = best.max(self.max[by * self.bx + bx]);
                }
            }
        }
        best
    }
}

/// The sample columns and rows whose patches cover the square of half-side `r` about `c`
/// (clamped to the grid, never empty: outside it the surface continues the edge samples).
fn sample_range(
    terrain: &HeightField,
    c: Point2<f64>,
    r: f64,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let g = terrain.grid();
    let (gx0, gy0) = g.world_to_grid(Point2::new(c.x - r, c.y - r));
    let (gx1, gy1) = g.world_to_grid(Point2::new(c.x + r, c.y + r));
    let span = |a: f64, b: f64, n: usize| {
        let clamp = |v: f64| {
            if v.is_nan() {
                0
            } else {
                v.clamp(0.0, (n - 1) as f64) as usize
            }
        };
        let lo = clamp(a.floor());
        let hi = clamp(b.ceil());
        lo..hi.max(lo) + 1
    };
    (span(gx0, gx1, g.nx()), span(gy0, gy1, g.ny()))
}

/// Where a shape at a world pose is in the terrain: the deepest point found and how deep,
/// or `None` when it is clear.
pub(crate) fn shape_contact(
    terrain: &HeightField,
    blocks: &BlockMax,
    shape: &Shape,
    pose: &Isometry3<f64>,
) -> Option<(Point3<f64>, f64)> {
    let lowest = pose.translation.vector.z - shape.depth_below(pose);
    if lowest > terrain.max_height_m() {
        return None;
    }
    let r = shape.bounding_radius();
    let c = Point2::new(pose.translation.vector.x, pose.translation.vector.y);
    if lowest > blocks.bound(terrain, c, r) {
        return None;
    }
    let inverse = pose.inverse();
    let mut deepest: Option<(Point3<f64>, f64)> = None;
    let mut note = |p: Point3<f64>, depth: f64| {
        if deepest.is_none_or(|(_, d)| depth > d) {
            deepest = Some((p, depth));
        }
    };
    // Terrain samples inside the shape.
    let g = terrain.grid();
    let (xs, ys) = sample_range(terrain, c, r);
    let cells = g.cells();
    let res = g.resolution_m();
    for iy in ys {
        for ix in xs.clone() {
            let x = g.origin().x + ix as f64 * res;
            let y = g.origin().y + iy as f64 * res;
            if (x - c.x).abs() > r || (y - c.y).abs() > r {
                continue;
            }
            let p = Point3::new(x, y, cells[iy * g.nx() + ix]);
            let local = inverse * p;
            if contains(shape, &local) {
                // Depth: how far the shape's underside there lies below the sample.
                let depth = underside(shape, &inverse, x, y, lowest)
                    .map(|z| p.z - z)
                    .unwrap_or(0.0);
                note(p, depth.max(0.0));
            }
        }
    }
    // Corners, rims and the lowest point of the shape.
    for p in key_points(shape, pose) {
        let h = terrain.height_at(p.x, p.y);
        if p.z < h {
            note(p, h - p.z);
        }
    }
    // Vertical rays through the footprint.
    let spacing = (0.5 * res).max(2.0 * r / 32.0).min(0.5 * r.max(1e-9));
    let n = ((2.0 * r / spacing).ceil() as usize).clamp(1, 64);
    let step = 2.0 * r / n as f64;
    for j in 0..=n {
        let y = c.y - r + j as f64 * step;
        for i in 0..=n {
            let x = c.x - r + i as f64 * step;
            if let Some(z) = underside(shape, &inverse, x, y, lowest) {
                let h = terrain.height_at(x, y);
                if z < h {
                    note(Point3::new(x, y, z), h - z);
                }
            }
        }
    }
    deepest
}

/// Points of a shape at a world pose where it reaches furthest: its lowest point, a box's
/// corners, the rims of a cylinder's ends, a capsule's lowest points on its end balls.
fn key_points(shape: &Shape, pose: &Isometry3<f64>) -> Vec<Point3<f64>> {
    let down = pose.rotation.inverse() * -Vector3::z();
    let mut local: Vec<Point3<f64>> = Vec::new();
    match *shape {
        Shape::Sphere { radius } => local.push(Point3::from(down * radius)),
        Shape::Box { size } => {
            for k in 0..8 {
                let pick = |bit: usize, v: f64| if k & bit == 0 { -v / 2.0 } else { v / 2.0 };
                local.push(Point3::new(
                    pick(1, size.x),
                    pick(2, size.y),
                    pick(4, size.z),
                ));
            }
        }
        Shape::Cylinder { radius, length } => {
            for z in [-length / 2.0, length / 2.0] {
                for k in 0..8 {
                    let a = std::f64::consts::TAU * k as f64 / 8.0;
                    local.push(Point3::new(radius * a.cos(), radius * a.sin(), z));
                }
                let across = Vector3::new(down.x, down.y, 0.0);
                if across.norm() > 1e-12 {
                    local.push(Point3::from(across.normalize() * radius + Vector3::z() * z));
                }
            }
        }
        Shape::Capsule { radius, length } => {
            for z in [-length / 2.0, length / 2.0] {
                local.push(Point3::from(down * radius + Vector3::z() * z));
            }
        }
    }
    local.into_iter().map(|p| pose * p).collect()
}

/// The world height of the underside of the shape above (x, y), if the vertical line
/// there meets it. `lowest` is the shape's lowest world height.
fn underside(shape: &Shape, inverse: &Isometry3<f64>, x: f64, y: f64, lowest: f64) -> Option<f64> {
    let below = lowest - 1.0;
    let origin = inverse * Point3::new(x, y, below);
    let dir = inverse.rotation * Vector3::z();
    ray_enter(shape, &origin.coords, &dir).map(|t| below + t)
}

/// The distance along a unit ray (shape frame) at which it enters the shape, if it does.
fn ray_enter(shape: &Shape, o: &Vector3<f64>, d: &Vector3<f64>) -> Option<f64> {
    match *shape {
        Shape::Sphere { radius } => sphere_enter(o, d, radius),
        Shape::Box { size } => {
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            for i in 0..3 {
                let (a, b) = slab(o[i], d[i], size[i] / 2.0)?;
                lo = lo.max(a);
                hi = hi.min(b);
            }
            (lo <= hi).then_some(lo)
        }
        Shape::Cylinder { radius, length } => cylinder_enter(o, d, radius, length / 2.0),
        Shape::Capsule { radius, length } => {
            let h = length / 2.0;
            let ends = [
                sphere_enter(&(o - Vector3::new(0.0, 0.0, h)), d, radius),
                sphere_enter(&(o + Vector3::new(0.0, 0.0, h)), d, radius),
                cylinder_enter(o, d, radius, h),
            ];
            ends.into_iter().flatten().reduce(f64::min)
        }
    }
}

fn slab(o: f64, d: f64, half: f64) -> Option<(f64, f64)> {
    if d.abs() < 1e-12 {
        return (o.abs() <= half).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let (a, b) = ((-half - o) / d, (half - o) / d);
    Some((a.min(b), a.max(b)))
}

fn sphere_enter(o: &Vector3<f64>, d: &Vector3<f64>, r: f64) -> Option<f64> {
    let b = o.dot(d);
    let c = o.norm_squared() - r * r;
    let disc = b * b - c;
    (disc >= 0.0).then(|| -b - disc.sqrt())
}

fn cylinder_enter(o: &Vector3<f64>, d: &Vector3<f64>, r: f64, half: f64) -> Option<f64> {
    let a = d.x * d.x + d.y * d.y;
    let (lo, hi) = if a < 1e-12 {
        if o.x * o.x + o.y * o.y > r * r {
            return None;
        }
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        let b = o.x * d.x + o.y * d.y;
        let c = o.x * o.x + o.y * o.y - r * r;
        let disc = b * b - a * c;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        ((-b - s) / a, (-b + s) / a)
    };
    let (za, zb) = slab(o.z, d.z, half)?;
    let (lo, hi) = (lo.max(za), hi.min(zb));
    (lo <= hi).then_some(lo)
}

/// Whether a point in the shape's frame lies in it.
fn contains(shape: &Shape, p: &Point3<f64>) -> bool {
    match *shape {
        Shape::Sphere { radius } => p.coords.norm_squared() <= radius * radius,
        Shape::Box { size } => (0..3).all(|i| p[i].abs() <= size[i] / 2.0),
        Shape::Cylinder { radius, length } => {
            p.x * p.x + p.y * p.y <= radius * radius && p.z.abs() <= length / 2.0
        }
        Shape::Capsule { radius, length } => {
            let z = p.z.clamp(-length / 2.0, length / 2.0);
            (p.coords - Vector3::new(0.0, 0.0, z)).norm_squared() <= radius * radius
        }
    }
}

/// How high above the ground a foot sphere of radius `r` centred at `c` is, metres: its
/// centre's height above the highest centre it could rest at there when lowered
/// vertically (negative: in the ground). Sampled at the centre, on three rings, and at the
/// terrain samples under the sphere.
pub fn foot_clearance(terrain: &HeightField, c: &Point3<f64>, r: f64) -> f64 {
    c.z - rest_height(terrain, Point2::new(c.x, c.y), r)
}

/// The height of a foot sphere's centre resting on the terrain above `xy`.
pub fn rest_height(terrain: &HeightField, xy: Point2<f64>, r: f64) -> f64 {
    resting(terrain, xy, r).0
}

/// Where a foot sphere of radius `r` lowered onto the terrain above `xy` touches it: the
/// terrain point under the sphere that holds it highest (on a level patch the point under
/// its centre; on a step's edge, the edge). Where several sampled points hold it almost
/// as high (on a slope, whose true contact lies between samples), their average weighted
/// by how nearly each holds it up, so that the point moves smoothly with the foot rather
/// than jumping from one sample to the next.
pub fn touch_point(terrain: &HeightField, xy: Point2<f64>, r: f64) -> Point3<f64> {
    let mut candidates = Vec::new();
    each_resting_candidate(terrain, xy, r, |centre, point| {
        candidates.push((centre, point))
    });
    let best = candidates
        .iter()
        .map(|c| c.0)
        .fold(f64::NEG_INFINITY, f64::max);
    // Points holding the centre within a few multiples of this below the best count.
    let scale = (0.005 * r).max(1e-6);
    let (mut sum, mut weight) = (nalgebra::Vector3::zeros(), 0.0);
    for (centre, point) in &candidates {
        let w = (-(best - centre) / scale).exp();
        if w > 1e-6 {
            sum += point.coords * w;
            weight += w;
        }
    }
    if weight > 0.0 {
        Point3::from(sum / weight)
    } else {
        resting(terrain, xy, r).1
    }
}

/// The resting height of the sphere's centre and the terrain point that holds it there.
fn resting(terrain: &HeightField, xy: Point2<f64>, r: f64) -> (f64, Point3<f64>) {
    let mut best = (f64::NEG_INFINITY, Point3::new(xy.x, xy.y, 0.0));
    each_resting_candidate(terrain, xy, r, |centre, point| {
        if centre > best.0 {
            best = (centre, point);
        }
    });
    best
}

/// Every sampled terrain point under the sphere (its centre, three rings, the terrain's
/// own samples) with the height the sphere's centre would rest at on it alone.
fn each_resting_candidate(
    terrain: &HeightField,
    xy: Point2<f64>,
    r: f64,
    mut out: impl FnMut(f64, Point3<f64>),
) {
    let h = terrain.height_at(xy.x, xy.y);
    out(h + r, Point3::new(xy.x, xy.y, h));
    if r <= 0.0 {
        return;
    }
    let lift = |d2: f64| (r * r - d2).max(0.0).sqrt();
    for ring in 1..=3 {
        let rr = r * ring as f64 / 3.0;
        let count = 8 * ring;
        for k in 0..count {
            let a = std::f64::consts::TAU * k as f64 / count as f64;
            let (s, co) = a.sin_cos();
            let (x, y) = (xy.x + rr * co, xy.y + rr * s);
            let ground = terrain.height_at(x, y);
            out(ground + lift(rr * rr), Point3::new(x, y, ground));
        }
    }
    let g = terrain.grid();
    let (xs, ys) = sample_range(terrain, xy, r);
    let res = g.resolution_m();
    for iy in ys {
        for ix in xs.clone() {
            let x = g.origin().x + ix as f64 * res;
            let y = g.origin().y + iy as f64 * res;
            let d2 = (x - xy.x).powi(2) + (y - xy.y).powi(2);
            if d2 <= r * r {
                let ground = g.cells()[iy * g.nx() + ix];
                out(ground + lift(d2), Point3::new(x, y, ground));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn bump() -> HeightField {
        // Flat at 0 with one sample raised to 1 m at (1, 1).
        let (nx, ny) = (21, 21);
        let mut h = vec![0.0; nx * ny];
        h[10 * nx + 10] = 1.0;
        HeightField::new(Point2::origin(), 0.1, nx, ny, h).unwrap()
    }

    fn at(x: f64, y: f64, z: f64) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::identity())
    }

    #[test]
    fn shapes_hit_a_bump_and_clear_it() {
        let t = bump();
        let b = BlockMax::new(&t);
        let shapes = [
            Shape::Sphere { radius: 0.2 },
            Shape::Box {
                size: Vector3::new(0.4, 0.4, 0.4),
            },
            Shape::Cylinder {
                radius: 0.2,
                length: 0.4,
            },
            Shape::Capsule {
                radius: 0.1,
                length: 0.2,
            },
        ];
        for s in shapes {
            // Centred over the bump, bottom at 0.8: hit.
            let pose = at(1.0, 1.0, 0.8 + s.depth_below(&at(0.0, 0.0, 0.0)));
            assert!(shape_contact(&t, &b, &s, &pose).is_some(), "{s:?}");
            // Above it: clear.
            let pose = at(1.0, 1.0, 1.05 + s.depth_below(&at(0.0, 0.0, 0.0)));
            assert!(shape_contact(&t, &b, &s, &pose).is_none(), "{s:?}");
            // Low but beside it: clear.
            let pose = at(0.4, 0.4, 0.05 + s.depth_below(&at(0.0, 0.0, 0.0)));
            assert!(shape_contact(&t, &b, &s, &pose).is_none(), "{s:?}");
            // Sunk into the flat ground away from the bump: hit.
            let pose = at(0.4, 0.4, -0.02 + s.depth_below(&at(0.0, 0.0, 0.0)));
            assert!(shape_contact(&t, &b, &s, &pose).is_some(), "{s:?}");
        }
    }

    #[test]
    fn a_tilted_box_corner_is_found() {
        let t = HeightField::flat(Point2::origin(), Point2::new(2.0, 2.0), 0.1, 0.0).unwrap();
        let b = BlockMax::new(&t);
        let s = Shape::Box {
            size: Vector3::new(0.5, 0.5, 0.1),
        };
        let tilt = UnitQuaternion::from_euler_angles(0.5, 0.3, 0.0);
        let mut pose = Isometry3::from_parts(Translation3::new(1.0, 1.0, 0.0), tilt);
        pose.translation.vector.z = s.depth_below(&pose) - 0.01;
        assert!(shape_contact(&t, &b, &s, &pose).is_some());
        pose.translation.vector.z += 0.02;
        assert!(shape_contact(&t, &b, &s, &pose).is_none());
    }

    #[test]
    fn a_foot_rests_on_the_highest_point_under_it() {
        let t = bump();
        assert!((rest_height(&t, Point2::new(0.5, 0.5), 0.05) - 0.05).abs() < 1e-12);
        // Directly over the bump the sphere rests on its peak.
        assert!((rest_height(&t, Point2::new(1.0, 1.0), 0.05) - 1.05).abs() < 1e-12);
        let c = Point3::new(0.5, 0.5, 0.03);
        assert!(foot_clearance(&t, &c, 0.05) < 0.0);
    }

    #[test]
    fn the_touch_point_on_a_slope_moves_smoothly_with_the_foot() {
        // A 25 degree slope rising along x, 0.1 m cells: the Ambler's foot on it.
        let (nx, ny, res) = (60, 20, 0.1);
        let rise = 25f64.to_radians().tan();
        let h: Vec<f64> = (0..ny)
            .flat_map(|_| (0..nx).map(move |ix| ix as f64 * res * rise))
            .collect();
        let t = HeightField::new(Point2::new(0.0, 0.0), res, nx, ny, h).unwrap();
        let r = 0.15;
        let mut last: Option<Point3<f64>> = None;
        for k in 0..300 {
            let xy = Point2::new(2.0 + k as f64 * 0.001, 1.0 + k as f64 * 0.0003);
            let p = touch_point(&t, xy, r);
            // On the plane, a little uphill of the centre.
            assert!((p.z - t.height_at(p.x, p.y)).abs() < 2e-3, "{p:?}");
            assert!(p.x > xy.x && p.x < xy.x + r, "{p:?} {xy:?}");
            if let Some(q) = last {
                assert!(
                    (p - q).norm() < 3e-3,
                    "a 1 mm move of the foot moved the point {:.4} m",
                    (p - q).norm()
                );
            }
            last = Some(p);
        }
    }
}
