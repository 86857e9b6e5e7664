//! The LTM Builder (§5.2.2): one range image -> an elevation map patch with a per-cell
//! uncertainty, unknown and occluded cells.
//!
//! # Method (an equivalent of the Locus method, per cell)
//!
//! The Locus method finds a cell's elevation by searching the vertical line through the cell's
//! centre for the point where it crosses the surface the range image describes: above that
//! point the scanner saw through the line (free space), below it the line is behind a measured
//! surface. This builder finds the same point without a per-cell search:
//!
//! 1. Each pixel with a return becomes a world point (`G_T_L * r * ray`), after *unwrapping*
//!    its range: the smallest `r + k * ambiguity` (k = 0, 1, ...) whose point lies in the
//!    plausible elevation band `[min_elevation_m, max_elevation_m]` is taken; a pixel with none
//!    is dropped.
//! 2. Neighbouring pixels form a triangulated surface (two triangles per 2 x 2 pixels, split
//!    along the shorter diagonal). This surface, interpolated between rays, is the boundary
//!    between the space the scanner saw to be empty and the space it could not see.
//! 3. Each cell's elevation is the highest triangle over its centre: the first point of the
//!    cell's vertical line, from above, that the scanner could not see through, i.e. the
//!    Locus crossing (with the surface interpolated linearly in space rather than in range).
//! 4. A triangle whose plane meets the viewing rays at less than `min_grazing_rad` is not a
//!    surface the scanner saw but the "curtain" between an occluding edge and what was seen
//!    behind it (the rays slide along it). A cell whose highest triangle is a curtain (higher
//!    than its highest surface triangle by more than two of that surface's standard
//!    deviations, so noise at an edge does not hide the edge's own cells) is **occluded**,
//!    carrying the curtain's height: the greatest elevation possible there, since the scanner
//!    saw empty space above it. Cells under no triangle are **unknown** (outside the field of
//!    view or beyond the last return).
//!
//! # Uncertainty
//!
//! A range error `dr` along a ray of direction `d` moves a surface with upward unit normal `n`
//! by `dr (n . d) / n_z` vertically at a fixed (x, y), so with `s_r^2 = noise(r)^2 + q^2 / 12`
//! (noise model and quantisation step `q`), a cell on a triangle gets
//! `sigma^2 = (s_r |n . d| / n_z)^2 + (tan(slope) * edge / sqrt(12))^2 + floor^2`: the range
//! term, the interpolation error of a sloped triangle whose longest horizontal edge is `edge`,
//! and a floor. On level ground seen at a grazing angle `g` the range term is `s_r sin g`.
//!
//! The same range error also moves the point horizontally, by `s_h = s_r |d_xy|`, which
//! matters where the terrain is steep around the cell (a point on a box's vertical face can
//! land in front of it): each known cell therefore also gets `(s_h * gradient)^2`, the gradient
//! being the largest elevation step to a known 4-neighbour divided by the cell size. Cells at
//! steps and edges thus carry large uncertainties, while level ground keeps the range term.
//! The result is capped at `max_sigma_m`.

use nalgebra::{Point3, Vector3};
use tca_ism::{ImageFrames, NoiseModel, PixelDirections, SensorSpec};
use tca_single_leg_messages::{RangeImage, SensorKind};

use crate::cell::Cell;
use crate::error::{LtmError, Result, check_resolution};
use crate::patch::{Patch, lattice_index};

/// Largest distance of the scanner from the world origin accepted, metres.
pub const MAX_SCANNER_DISTANCE_M: f64 = 1e6;

/// Parameters of the builder.
#[derive(Debug, Clone, PartialEq)]
pub struct BuilderConfig {
    /// Cell size of the maps built, metres.
    pub resolution_m: f64,
    /// Lowest plausible terrain elevation, metres (unwrapping band, and points below are
    /// dropped).
    pub min_elevation_m: f64,
    /// Highest plausible terrain elevation, metres.
    pub max_elevation_m: f64,
    /// Points farther than this horizontally from the scanner are not mapped, metres.
    pub max_horizontal_range_m: f64,
    /// Triangles meeting the rays at less than this angle are occlusion curtains, radians.
    pub min_grazing_rad: f64,
    /// Smallest elevation standard deviation, metres.
    pub sigma_floor_m: f64,
    /// Largest elevation standard deviation, metres.
    pub max_sigma_m: f64,
    /// The Erim's range noise (should match the sensor's).
    pub erim_noise: NoiseModel,
    /// The Perceptron's range noise.
    pub perceptron_noise: NoiseModel,
    /// Threads rasterising (at least 1). One by default: on the 2-core machines measured,
    /// a second thread did not pay for itself (see BENCHMARKS.md).
    pub threads: usize,
    /// Largest number of cells a patch may have.
    pub max_cells: usize,
}

impl Default for BuilderConfig {
    fn default() -> Self {
        Self {
            resolution_m: 0.05,
            min_elevation_m: -2.0,
            max_elevation_m: 3.0,
            max_horizontal_range_m: 15.0,
            min_grazing_rad: 8_f64.to_radians(),
            sigma_floor_m: 0.005,
            max_sigma_m: 2.0,
            erim_noise: NoiseModel::default_for(SensorKind::Erim),
            perceptron_noise: NoiseModel::default_for(SensorKind::Perceptron),
            threads: 1,
            max_cells: 16 << 20,
        }
    }
}

impl BuilderConfig {
    /// The range noise assumed for a sensor.
    pub fn noise(&self, kind: SensorKind) -> NoiseModel {
        match kind {
            SensorKind::Erim => self.erim_noise,
            SensorKind::Perceptron => self.perceptron_noise,
        }
    }

    /// Checks every parameter.
    pub fn validate(&self) -> Result<()> {
        check_resolution("map", self.resolution_m)?;
        let finite = [
            self.min_elevation_m,
            self.max_elevation_m,
            self.max_horizontal_range_m,
            self.min_grazing_rad,
            self.sigma_floor_m,
            self.max_sigma_m,
        ];
        if finite.iter().any(|v| !v.is_finite()) {
            return Err(LtmError::Config(format!(
                "builder parameters must be finite: {self:?}"
            )));
        }
        if self.min_elevation_m >= self.max_elevation_m {
            return Err(LtmError::Config(format!(
                "the elevation band [{}, {}] m is empty; give min_elevation_m < max_elevation_m",
                self.min_elevation_m, self.max_elevation_m
            )));
        }
        if !(self.sigma_floor_m > 0.0 && self.max_sigma_m >= self.sigma_floor_m) {
            return Err(LtmError::Config(format!(
                "need 0 < sigma_floor_m ({}) <= max_sigma_m ({})",
                self.sigma_floor_m, self.max_sigma_m
            )));
        }
        if !(self.erim_noise.is_valid() && self.perceptron_noise.is_valid()) {
            return Err(LtmError::Config(
                "noise parameters must be finite and non-negative".into(),
            ));
        }
        if !(self.resolution_m >= 1e-4 && self.max_horizontal_range_m <= 1e4) {
            return Err(LtmError::Config(format!(
                "a map resolution of at least 0.1 mm and a range of at most 10 km are supported \
                 (got {} m and {} m)",
                self.resolution_m, self.max_horizontal_range_m
            )));
        }
        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&self.min_grazing_rad) {
            return Err(LtmError::Config(format!(
                "min_grazing_rad {} must be in [0, pi/2)",
                self.min_grazing_rad
            )));
        }
        Ok(())
    }
}

/// The world points of an image's pixels (NaN where there is none) and their ranges.
struct ImagePoints {
    width: usize,
    height: usize,
    points: Vec<Point3<f64>>,
    ranges: Vec<f64>,
    origin: Point3<f64>,
}

impl ImagePoints {
    fn get(&self, row: usize, col: usize) -> Option<(Point3<f64>, f64)> {
        let k = row * self.width + col;
        let p = *self.points.get(k)?;
        p.x.is_finite().then(|| (p, self.ranges[k]))
    }
}

/// Builds the elevation map patch of one range image (see the module docs for the method).
/// The image is checked against its sensor first: a wrong size, resolution, field of view or
/// transform is an error.
pub fn build_map(image: &RangeImage, config: &BuilderConfig) -> Result<Patch> {
    config.validate()?;
    let spec = SensorSpec::of(image.sensor);
    spec.check_image(image)?;
    let frames = ImageFrames::of(image)?;
    let origin = frames.global_from_locus() * Point3::origin();
    if origin.coords.norm() > MAX_SCANNER_DISTANCE_M || !origin.coords.norm().is_finite() {
        return Err(LtmError::ScannerTooFar {
            x_m: origin.x,
            y_m: origin.y,
            z_m: origin.z,
            limit_m: MAX_SCANNER_DISTANCE_M,
        });
    }
    let points = image_points(image, &spec, &frames, config);
    let res = config.resolution_m;
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points.points.iter().filter(|p| p.x.is_finite()) {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    if !lo[0].is_finite() {
        return Ok(Patch::unknown(0, 0, 0, 0, res));
    }
    let (i0, j0) = (lattice_index(lo[0], res), lattice_index(lo[1], res));
    let (i1, j1) = (lattice_index(hi[0], res), lattice_index(hi[1], res));
    let nx = (i1 - i0 + 1) as u64;
    let ny = (j1 - j0 + 1) as u64;
    if nx.saturating_mul(ny) > config.max_cells as u64 {
        return Err(LtmError::RegionTooLarge {
            nx,
            ny,
            resolution_m: res,
            limit: config.max_cells,
        });
    }
    let layout = Layout {
        i0,
        j0,
        nx: nx as usize,
        ny: ny as usize,
        res,
    };
    let quad_rows = points.height.saturating_sub(1);
    let threads = config.threads.clamp(1, quad_rows.max(1));
    let noise = config.noise(image.sensor);
    let q = spec.range_resolution_m();
    let shade = Shading {
        origin: points.origin,
        sin_min_grazing: config.min_grazing_rad.sin(),
        noise,
        quantisation_var: q * q / 12.0,
        floor_var: config.sigma_floor_m * config.sigma_floor_m,
        max_sigma: config.max_sigma_m,
    };
    let raster = if threads == 1 {
        rasterise(&points, &layout, &shade, 0..quad_rows)
    } else {
        let per = quad_rows.div_ceil(threads);
        let parts: Vec<Raster> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    let rows = (t * per).min(quad_rows)..((t + 1) * per).min(quad_rows);
                    let (points, layout, shade) = (&points, &layout, &shade);
                    scope.spawn(move || rasterise(points, layout, shade, rows))
                })
                .collect();
            handles.into_iter().filter_map(|h| h.join().ok()).collect()
        });
        let mut iter = parts.into_iter();
        let mut first = iter
            .next()
            .unwrap_or_else(|| Raster::new(layout.nx * layout.ny));
        for other in iter {
            first.absorb(&other);
        }
        first
    };
    let cells = finish_cells(&raster, &layout, config.max_sigma_m as f32);
    Ok(Patch {
        i0,
        j0,
        nx: layout.nx,
        ny: layout.ny,
        resolution_m: res,
        cells,
    })
}

/// The cells of a raster: a cell whose highest surface is within two standard deviations of
/// its highest curtain (or has no curtain over it) is known, one under a curtain is occluded;
/// known cells then get the horizontal-error term.
fn finish_cells(raster: &Raster, layout: &Layout, max_sigma: f32) -> Vec<Cell> {
    let (nx, ny) = (layout.nx, layout.ny);
    let res = layout.res as f32;
    let mut cells: Vec<Cell> = (0..nx * ny)
        .map(|k| {
            let (z, s, c) = (raster.top[k], raster.sigma[k], raster.curtain[k]);
            if z > f32::NEG_INFINITY && z >= c - 2.0 * s {
                Cell::known(z, s)
            } else if c > f32::NEG_INFINITY {
                Cell::occluded(c)
            } else {
                Cell::UNKNOWN
            }
        })
        .collect();
    let elevations: Vec<Option<f32>> = cells
        .iter()
        .map(|c| c.is_known().then_some(c.elevation_m))
        .collect();
    for (k, cell) in cells.iter_mut().enumerate() {
        let Some(z) = elevations[k] else { continue };
        let (ix, iy) = (k % nx, k / nx);
        let neighbours = [
            (ix > 0).then(|| k - 1),
            (ix + 1 < nx).then(|| k + 1),
            (iy > 0).then(|| k - nx),
            (iy + 1 < ny).then(|| k + nx),
        ];
        let step = neighbours
            .into_iter()
            .flatten()
            .filter_map(|n| elevations[n])
            .fold(0f32, |m, zn| m.max((zn - z).abs()));
        let horizontal = raster.sigma_h[k] * step / res;
        let s = cell.sigma_m;
        cell.sigma_m = (s * s + horizontal * horizontal).sqrt().min(max_sigma);
    }
    cells
}

fn image_points(
    image: &RangeImage,
    spec: &SensorSpec,
    frames: &ImageFrames,
    config: &BuilderConfig,
) -> ImagePoints {
    let g = frames.global_from_locus();
    let origin = g * Point3::origin();
    let dirs = PixelDirections::new(spec);
    let (width, height) = (spec.width_px as usize, spec.height_px as usize);
    let n = width * height;
    let mut points = vec![Point3::new(f64::NAN, f64::NAN, f64::NAN); n];
    let mut ranges = vec![f64::NAN; n];
    let max_h2 = config.max_horizontal_range_m * config.max_horizontal_range_m;
    let band = config.min_elevation_m..=config.max_elevation_m;
    for (k, (&count, &refl)) in image
        .range_counts
        .iter()
        .zip(&image.reflectance)
        .enumerate()
    {
        if refl == 0 {
            continue;
        }
        let Some(d) = dirs.get(k / width, k % width) else {
            continue;
        };
        let d = g.rotation * d;
        let measured = spec.count_range_m(count);
        let mut wraps = 0.0;
        loop {
            let r = measured + wraps * spec.ambiguity_m;
            if r > spec.max_range_m + spec.range_resolution_m() {
                break;
            }
            let p = origin + d * r;
            if band.contains(&p.z) {
                let (dx, dy) = (p.x - origin.x, p.y - origin.y);
                if dx * dx + dy * dy <= max_h2 {
                    points[k] = p;
                    ranges[k] = r;
                }
                break;
            }
            wraps += 1.0;
        }
    }
    ImagePoints {
        width,
        height,
        points,
        ranges,
        origin,
    }
}

struct Layout {
    i0: i64,
    j0: i64,
    nx: usize,
    ny: usize,
    res: f64,
}

struct Shading {
    origin: Point3<f64>,
    sin_min_grazing: f64,
    noise: NoiseModel,
    quantisation_var: f64,
    floor_var: f64,
    max_sigma: f64,
}

/// Per cell: the highest surface triangle's elevation, its vertical sigma and the horizontal
/// sigma of its points; and the highest occlusion curtain's elevation.
struct Raster {
    top: Vec<f32>,
    sigma: Vec<f32>,
    sigma_h: Vec<f32>,
    curtain: Vec<f32>,
}

impl Raster {
    fn new(n: usize) -> Self {
        Self {
            top: vec![f32::NEG_INFINITY; n],
            sigma: vec![0.0; n],
            sigma_h: vec![0.0; n],
            curtain: vec![f32::NEG_INFINITY; n],
        }
    }

    fn absorb(&mut self, other: &Raster) {
        for k in 0..self.top.len().min(other.top.len()) {
            if other.top[k] > self.top[k] {
                self.top[k] = other.top[k];
                self.sigma[k] = other.sigma[k];
                self.sigma_h[k] = other.sigma_h[k];
            }
            self.curtain[k] = self.curtain[k].max(other.curtain[k]);
        }
    }
}

fn rasterise(
    points: &ImagePoints,
    layout: &Layout,
    shade: &Shading,
    quad_rows: std::ops::Range<usize>,
) -> Raster {
    let mut raster = Raster::new(layout.nx * layout.ny);
    for row in quad_rows {
        for col in 0..points.width.saturating_sub(1) {
            let a = points.get(row, col);
            let b = points.get(row, col + 1);
            let c = points.get(row + 1, col);
            let d = points.get(row + 1, col + 1);
            // Split along the shorter diagonal when all four are present.
            let split_ad = match (a, b, c, d) {
                (Some(a), Some(b), Some(c), Some(d)) => {
                    (a.0 - d.0).norm_squared() <= (b.0 - c.0).norm_squared()
                }
                _ => true,
            };
            let triangles = if split_ad {
                [[a, b, d], [a, d, c]]
            } else {
                [[a, b, c], [b, d, c]]
            };
            for [p, q, r] in triangles {
                if let (Some(p), Some(q), Some(r)) = (p, q, r) {
                    triangle(&mut raster, layout, shade, [p, q, r]);
                }
            }
        }
    }
    raster
}

fn triangle(raster: &mut Raster, layout: &Layout, shade: &Shading, v: [(Point3<f64>, f64); 3]) {
    let [(p0, r0), (p1, r1), (p2, r2)] = v;
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let det = e1.x * e2.y - e1.y * e2.x;
    if det.abs() < 1e-12 {
        return; // Vertical or degenerate: covers no cell centre.
    }
    let mut n = e1.cross(&e2);
    let norm = n.norm();
    if norm <= 0.0 {
        return;
    }
    n /= norm;
    if n.z < 0.0 {
        n = -n;
    }
    let centroid = Point3::from((p0.coords + p1.coords + p2.coords) / 3.0);
    let view: Vector3<f64> = (centroid - shade.origin).normalize();
    let sin_grazing = n.dot(&view).abs();
    let range = (r0 + r1 + r2) / 3.0;
    let sr2 = shade.noise.range_sigma_at(range).powi(2) + shade.quantisation_var;
    let sigma_h = (sr2.sqrt() * view.x.hypot(view.y)) as f32;
    let curtain = sin_grazing < shade.sin_min_grazing;
    let sigma: f32 = if curtain {
        0.0
    } else {
        let nz = n.z.max(1e-6);
        let range_term = sr2 * (sin_grazing / nz).powi(2);
        let edge2 = [e1, e2, p2 - p1]
            .iter()
            .map(|e| e.x * e.x + e.y * e.y)
            .fold(0.0, f64::max);
        let tan2 = (1.0 - nz * nz).max(0.0) / (nz * nz);
        let interp_term = tan2 * edge2 / 12.0;
        (range_term + interp_term + shade.floor_var)
            .sqrt()
            .min(shade.max_sigma) as f32
    };
    let res = layout.res;
    let (min_x, max_x) = (p0.x.min(p1.x).min(p2.x), p0.x.max(p1.x).max(p2.x));
    let (min_y, max_y) = (p0.y.min(p1.y).min(p2.y), p0.y.max(p1.y).max(p2.y));
    let ia = ((min_x / res).ceil() as i64).max(layout.i0);
    let ib = ((max_x / res).floor() as i64).min(layout.i0 + layout.nx as i64 - 1);
    let ja = ((min_y / res).ceil() as i64).max(layout.j0);
    let jb = ((max_y / res).floor() as i64).min(layout.j0 + layout.ny as i64 - 1);
    const EPS: f64 = 1e-9;
    let inv = 1.0 / det;
    for j in ja..=jb {
        let y = j as f64 * res - p0.y;
        let row = (j - layout.j0) as usize * layout.nx;
        for i in ia..=ib {
            let x = i as f64 * res - p0.x;
            let alpha = (x * e2.y - y * e2.x) * inv;
            let beta = (e1.x * y - e1.y * x) * inv;
            if alpha < -EPS || beta < -EPS || alpha + beta > 1.0 + EPS {
                continue;
            }
            let z = (p0.z + alpha * e1.z + beta * e2.z) as f32;
            let k = row + (i - layout.i0) as usize;
            if curtain {
                if let Some(c) = raster.curtain.get_mut(k) {
                    *c = c.max(z);
                }
            } else if let (Some(t), Some(s), Some(h)) = (
                raster.top.get_mut(k),
                raster.sigma.get_mut(k),
                raster.sigma_h.get_mut(k),
            ) && z > *t
            {
                *t = z;
                *s = sigma;
                *h = sigma_h;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_config_is_valid_and_bad_ones_are_refused() {
        BuilderConfig::default().validate().unwrap();
        let mut c = BuilderConfig {
            resolution_m: 0.0,
            ..BuilderConfig::default()
        };
        assert!(c.validate().unwrap_err().to_string().contains("resolution"));
        c.resolution_m = f64::NAN;
        assert!(c.validate().is_err());
        c.resolution_m = 0.1;
        c.min_elevation_m = 5.0;
        assert!(c.validate().unwrap_err().to_string().contains("band"));
    }
}
