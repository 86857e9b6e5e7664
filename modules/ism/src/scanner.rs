//! The virtual laser rangefinder: casts one ray per pixel against the simulated terrain (and
//! any calibration targets) from the scanner's true pose on the carriage, then measures the
//! way a phase-measuring scanner does: Gaussian range noise, wrapping at the ambiguity
//! interval, quantisation to the sensor's counts, and a reflectance value.
//!
//! The scanner is mounted on the carriage by its *true* mount (`carriage <- scanner`, from
//! the robot parameters unless overridden) and tags its images with its *believed*
//! calibration (`scanner <- body`), which starts as the nominal mount and can be replaced
//! by the result of [`crate::calibration`]. Rows are cast in parallel with scoped threads.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};
use tca_robot::params::CarriageParams;
use tca_robot::{CarriagePose, HeightField, LegParams};
use tca_single_leg_messages::RangeImage;

use crate::error::{IsmError, Result};
use crate::frames::to_wire;
use crate::noise::{NoiseModel, Normal, ReflectanceModel, row_rng};
use crate::sensor::RangeSensor;
use crate::spec::{PixelDirections, SensorSpec};

/// A retro-reflective sphere seen by the scanner (the calibration target on the leg). It
/// returns full-scale reflectance from any angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereTarget {
    /// Centre, world frame.
    pub center: Point3<f64>,
    /// Radius, metres.
    pub radius_m: f64,
}

impl SphereTarget {
    /// Distance along a unit ray to the sphere's near surface, if the ray meets it ahead.
    fn intersect(&self, origin: &Point3<f64>, d: &Vector3<f64>) -> Option<f64> {
        let oc = origin - self.center;
        let b = oc.dot(d);
        let c = oc.norm_squared() - self.radius_m * self.radius_m;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let t = -b - disc.sqrt();
        (t > 0.0).then_some(t)
    }
}

/// A simulated Erim or Perceptron on the carriage, looking at a height field.
#[derive(Debug, Clone)]
pub struct VirtualScanner {
    spec: SensorSpec,
    directions: PixelDirections,
    terrain: Arc<HeightField>,
    carriage: CarriageParams,
    true_carriage_from_scanner: Isometry3<f64>,
    scanner_from_body: Isometry3<f64>,
    locus_from_scanner: Isometry3<f64>,
    noise: NoiseModel,
    reflectance: ReflectanceModel,
    seed: u64,
    threads: usize,
    sequence: u64,
    targets: Vec<SphereTarget>,
}

impl VirtualScanner {
    /// A scanner of `spec` mounted as `params.scanner` says on the carriage of `params`, with
    /// its sensor's default noise, seed 0, a calibration equal to the nominal mount and as
    /// many threads as the machine has cores.
    pub fn new(spec: SensorSpec, terrain: Arc<HeightField>, params: &LegParams) -> Self {
        let mount = params.scanner.carriage_from_scanner();
        Self {
            spec,
            directions: PixelDirections::new(&spec),
            terrain,
            carriage: params.carriage,
            true_carriage_from_scanner: mount,
            scanner_from_body: mount.inverse(),
            locus_from_scanner: Isometry3::identity(),
            noise: NoiseModel::default_for(spec.kind),
            reflectance: ReflectanceModel::default(),
            seed: 0,
            threads: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            sequence: 0,
            targets: Vec::new(),
        }
    }

    /// A scanner of `spec` mounted on a body (a legged robot's) by `body_from_scanner`,
    /// tagging its images with the nominal calibration (`scanner <- body`, the mount's
    /// inverse), with its sensor's default noise, seed 0 and as many threads as the machine
    /// has cores. Image it with [`VirtualScanner::cast_from_body`] or through
    /// [`RangeSensor::acquire_from_body`].
    pub fn on_body(
        spec: SensorSpec,
        terrain: Arc<HeightField>,
        body_from_scanner: Isometry3<f64>,
    ) -> Self {
        Self::new(spec, terrain, &LegParams::default())
            .with_true_mount(body_from_scanner)
            .with_calibration(body_from_scanner.inverse())
    }

    /// Uses this noise model.
    pub fn with_noise(mut self, noise: NoiseModel) -> Self {
        self.noise = noise;
        self
    }

    /// Uses this reflectance model.
    pub fn with_reflectance(mut self, reflectance: ReflectanceModel) -> Self {
        self.reflectance = reflectance;
        self
    }

    /// Seeds the noise.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Casts with this many threads (at least 1).
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads.max(1);
        self
    }

    /// Mounts the scanner by this true `carriage <- scanner` transform (the calibration it
    /// tags images with is unchanged: use this to simulate a miscalibrated scanner).
    pub fn with_true_mount(mut self, carriage_from_scanner: Isometry3<f64>) -> Self {
        self.true_carriage_from_scanner = carriage_from_scanner;
        self
    }

    /// Tags images with this `scanner <- body` calibration.
    pub fn with_calibration(mut self, scanner_from_body: Isometry3<f64>) -> Self {
        self.scanner_from_body = scanner_from_body;
        self
    }

    /// Uses this fixed `locus <- scanner` transform.
    pub fn with_locus_from_scanner(mut self, locus_from_scanner: Isometry3<f64>) -> Self {
        self.locus_from_scanner = locus_from_scanner;
        self
    }

    /// Replaces the calibration images are tagged with.
    pub fn set_calibration(&mut self, scanner_from_body: Isometry3<f64>) {
        self.scanner_from_body = scanner_from_body;
    }

    /// The calibration images are tagged with (`scanner <- body`).
    pub fn calibration(&self) -> Isometry3<f64> {
        self.scanner_from_body
    }

    /// The true mount (`carriage <- scanner`).
    pub fn true_mount(&self) -> Isometry3<f64> {
        self.true_carriage_from_scanner
    }

    /// The noise model.
    pub fn noise(&self) -> NoiseModel {
        self.noise
    }

    /// Places calibration targets in the scene (replacing any before).
    pub fn set_targets(&mut self, targets: Vec<SphereTarget>) {
        self.targets = targets;
    }

    /// The carriage parameters the scanner is mounted with.
    pub fn carriage_params(&self) -> &CarriageParams {
        &self.carriage
    }

    /// The sensor's characteristics.
    pub fn sensor_spec(&self) -> &SensorSpec {
        &self.spec
    }

    /// The terrain the scanner looks at.
    pub fn terrain(&self) -> &Arc<HeightField> {
        &self.terrain
    }

    /// The image the scanner takes from `pose` with sequence number `sequence`; deterministic
    /// (noise depends on the seed, the sequence number and the row only).
    pub fn cast(&self, pose: &CarriagePose, sequence: u64) -> Result<RangeImage> {
        if !(pose.y_m.is_finite() && pose.roll_rad.is_finite() && pose.pitch_rad.is_finite()) {
            return Err(IsmError::Config(format!(
                "the carriage pose {pose:?} is not finite; the Controller's body position is bad"
            )));
        }
        self.cast_from(&pose.world_from_carriage(&self.carriage), sequence)
    }

    /// The image the scanner takes with its body (the frame it is mounted on) at
    /// `world_from_body`, any position and orientation, with sequence number `sequence`:
    /// rays start from `world_from_body * mount` and the image's `body <- global` transform
    /// is `world_from_body`'s inverse. This is how a scanner on a legged robot's body images
    /// (see [`crate::legged`]); deterministic like [`VirtualScanner::cast`].
    pub fn cast_from_body(
        &self,
        world_from_body: &Isometry3<f64>,
        sequence: u64,
    ) -> Result<RangeImage> {
        let finite = world_from_body
            .to_homogeneous()
            .iter()
            .all(|v| v.is_finite());
        if !finite {
            return Err(IsmError::Config(format!(
                "the body pose {world_from_body:?} is not finite; the Controller's body pose \
                 is bad"
            )));
        }
        self.cast_from(world_from_body, sequence)
    }

    /// Casts from the body at `world_from_body` (checked finite by the callers).
    fn cast_from(&self, world_from_body: &Isometry3<f64>, sequence: u64) -> Result<RangeImage> {
        if !self.noise.is_valid() {
            return Err(IsmError::Config(format!(
                "noise parameters must be finite and non-negative, got {:?}",
                self.noise
            )));
        }
        let world_from_locus =
            world_from_body * self.true_carriage_from_scanner * self.locus_from_scanner.inverse();
        let n = self.spec.pixel_count();
        let width = self.spec.width_px as usize;
        let mut range_counts = vec![0u16; n];
        let mut reflectance = vec![0u16; n];
        let rows = self.spec.height_px as usize;
        let threads = self.threads.min(rows).max(1);
        let rows_per_chunk = rows.div_ceil(threads);
        let chunk = rows_per_chunk * width;
        if threads == 1 {
            self.cast_rows(
                &world_from_locus,
                sequence,
                0,
                &mut range_counts,
                &mut reflectance,
            );
        } else {
            std::thread::scope(|scope| {
                for (i, (ranges, refl)) in range_counts
                    .chunks_mut(chunk)
                    .zip(reflectance.chunks_mut(chunk))
                    .enumerate()
                {
                    let first_row = i * rows_per_chunk;
                    let world_from_locus = &world_from_locus;
                    scope.spawn(move || {
                        self.cast_rows(world_from_locus, sequence, first_row, ranges, refl);
                    });
                }
            });
        }
        Ok(RangeImage {
            sensor: self.spec.kind,
            width: self.spec.width_px,
            height: self.spec.height_px,
            range_counts,
            reflectance,
            range_resolution_m: self.spec.range_resolution_m(),
            ambiguity_m: self.spec.ambiguity_m,
            azimuth_fov_rad: self.spec.azimuth_fov_rad,
            elevation_fov_rad: self.spec.elevation_fov_rad,
            locus_from_scanner: to_wire(&self.locus_from_scanner),
            scanner_from_body: to_wire(&self.scanner_from_body),
            body_from_global: to_wire(&world_from_body.inverse()),
            sequence,
        })
    }

    /// Casts the rows starting at `first_row` into the given slices (whole rows).
    fn cast_rows(
        &self,
        world_from_locus: &Isometry3<f64>,
        sequence: u64,
        first_row: usize,
        ranges: &mut [u16],
        refl: &mut [u16],
    ) {
        let width = self.directions.width();
        let origin = world_from_locus * Point3::origin();
        let rotation = world_from_locus.rotation;
        let full = f64::from(self.spec.max_reflectance_count());
        for (k, (range_row, refl_row)) in ranges
            .chunks_mut(width)
            .zip(refl.chunks_mut(width))
            .enumerate()
        {
            let row = first_row + k;
            let mut rng = row_rng(self.seed, sequence, row as u32);
            let mut normal = Normal::default();
            for (col, (range_px, refl_px)) in range_row.iter_mut().zip(refl_row).enumerate() {
                let Some(d_locus) = self.directions.get(row, col) else {
                    continue;
                };
                let d = rotation * d_locus;
                let Some((true_range, brightness)) = self.trace(&origin, &d) else {
                    continue;
                };
                let noisy = if self.noise.range_sigma_at(true_range) > 0.0 {
                    true_range + self.noise.range_sigma_at(true_range) * normal.sample(&mut rng)
                } else {
                    true_range
                };
                *range_px = self.spec.range_count(noisy);
                let b = if self.noise.reflectance_sigma > 0.0 {
                    brightness + self.noise.reflectance_sigma * normal.sample(&mut rng)
                } else {
                    brightness
                };
                // Count 0 is reserved for "no return".
                *refl_px = (b * full).round().clamp(1.0, full) as u16;
            }
        }
    }

    /// The nearest surface along a ray: its range and reflectance (fraction of full scale).
    fn trace(&self, origin: &Point3<f64>, d: &Vector3<f64>) -> Option<(f64, f64)> {
        let max = self.spec.max_range_m;
        let terrain = self.terrain.cast_ray(origin, d, max).map(|hit| {
            (
                hit.range_m,
                self.reflectance.terrain(hit.range_m, hit.normal.dot(d)),
            )
        });
        let target = self
            .targets
            .iter()
            .filter_map(|t| t.intersect(origin, d))
            .filter(|&t| t <= max)
            .min_by(f64::total_cmp)
            .map(|t| (t, 1.0));
        match (terrain, target) {
            (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
            (a, b) => a.or(b),
        }
    }
}

impl RangeSensor for VirtualScanner {
    fn spec(&self) -> &SensorSpec {
        &self.spec
    }

    fn acquire(&mut self, pose: &CarriagePose) -> Result<RangeImage> {
        let image = self.cast(pose, self.sequence)?;
        self.sequence += 1;
        Ok(image)
    }

    fn acquire_from_body(&mut self, world_from_body: &Isometry3<f64>) -> Result<RangeImage> {
        let image = self.cast_from_body(world_from_body, self.sequence)?;
        self.sequence += 1;
        Ok(image)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;
    use tca_single_leg_messages::SensorKind;

    use crate::frames::ImageFrames;

    fn flat(height_m: f64) -> Arc<HeightField> {
        Arc::new(
            HeightField::flat(
                Point2::new(-20.0, -20.0),
                Point2::new(26.0, 40.0),
                0.5,
                height_m,
            )
            .unwrap(),
        )
    }

    #[test]
    fn noiseless_flat_ground_reads_true_ranges() {
        let params = LegParams::default();
        let scanner = VirtualScanner::new(SensorSpec::perceptron(), flat(0.0), &params)
            .with_noise(NoiseModel::none());
        let pose = CarriagePose::level(2.0);
        let image = scanner.cast(&pose, 0).unwrap();
        SensorSpec::perceptron().check_image(&image).unwrap();
        let frames = ImageFrames::of(&image).unwrap();
        let g = frames.global_from_locus();
        let spec = SensorSpec::perceptron();
        let mut checked = 0;
        for row in (0..256).step_by(17) {
            for col in (0..256).step_by(13) {
                let i = row * 256 + col;
                if image.reflectance[i] == 0 {
                    continue;
                }
                let r = spec.count_range_m(image.range_counts[i]);
                let p = g * Point3::from(spec.pixel_direction(row as u32, col as u32) * r);
                assert!(
                    p.z.abs() < spec.range_resolution_m(),
                    "z = {} at {row},{col}",
                    p.z
                );
                checked += 1;
            }
        }
        assert!(checked > 200, "{checked}");
    }

    #[test]
    fn images_do_not_depend_on_the_thread_count() {
        let params = LegParams::default();
        let one = VirtualScanner::new(SensorSpec::erim(), flat(0.0), &params)
            .with_seed(9)
            .with_threads(1);
        let three = one.clone().with_threads(3);
        let pose = CarriagePose::level(1.0);
        assert_eq!(one.cast(&pose, 4).unwrap(), three.cast(&pose, 4).unwrap());
        assert_ne!(
            one.cast(&pose, 4).unwrap().range_counts,
            one.cast(&pose, 5).unwrap().range_counts
        );
    }

    #[test]
    fn far_surfaces_wrap_at_the_ambiguity_interval() {
        // Ground 25 m below a scanner looking straight down: the Erim reads 25 - 19.5 m.
        let params = LegParams::default();
        let down = Isometry3::from_parts(
            nalgebra::Translation3::new(0.0, 0.0, 0.0),
            nalgebra::UnitQuaternion::from_axis_angle(
                &Vector3::y_axis(),
                std::f64::consts::FRAC_PI_2,
            ),
        );
        let terrain = flat(4.0 - 25.0);
        let scanner = VirtualScanner::new(SensorSpec::erim(), terrain, &params)
            .with_noise(NoiseModel::none())
            .with_true_mount(down);
        let image = scanner.cast(&CarriagePose::level(3.0), 0).unwrap();
        let spec = SensorSpec::erim();
        let centre = 32 * 256 + 128;
        let read = spec.count_range_m(image.range_counts[centre]);
        assert!(image.reflectance[centre] > 0);
        assert!(
            (read - (25.0 - spec.ambiguity_m)).abs() < 0.1,
            "read {read} m for a 25 m range"
        );
    }

    #[test]
    fn no_return_means_reflectance_zero() {
        let params = LegParams::default();
        // Looking up at the sky.
        let up = Isometry3::from_parts(
            nalgebra::Translation3::identity(),
            nalgebra::UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -1.2),
        );
        let scanner =
            VirtualScanner::new(SensorSpec::erim(), flat(0.0), &params).with_true_mount(up);
        let image = scanner.cast(&CarriagePose::level(3.0), 0).unwrap();
        assert!(image.reflectance.iter().all(|&r| r == 0));
        assert_eq!(image.sensor, SensorKind::Erim);
    }

    #[test]
    fn bad_pose_is_an_error_not_a_panic() {
        let params = LegParams::default();
        let scanner = VirtualScanner::new(SensorSpec::erim(), flat(0.0), &params);
        let e = scanner.cast(&CarriagePose::level(f64::NAN), 0).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
    }

    #[test]
    fn targets_are_bright_and_in_front_of_the_terrain() {
        let params = LegParams::default();
        let mut scanner = VirtualScanner::new(SensorSpec::perceptron(), flat(0.0), &params)
            .with_noise(NoiseModel::none());
        let pose = CarriagePose::level(2.0);
        let world_from_scanner = params.scanner.world_from_scanner(&params.carriage, &pose);
        let center = world_from_scanner * Point3::new(3.0, 0.0, 0.0);
        scanner.set_targets(vec![SphereTarget {
            center,
            radius_m: 0.1,
        }]);
        let image = scanner.cast(&pose, 0).unwrap();
        let full = SensorSpec::perceptron().max_reflectance_count();
        let bright = image.reflectance.iter().filter(|&&r| r == full).count();
        assert!(bright > 20, "{bright} target pixels");
    }
}
