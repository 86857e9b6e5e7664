//! The two laser rangefinders of §2.2: image sizes, fields of view, range digitisation, and
//! the geometry of a pixel's ray.
//!
//! # Pixel geometry
//!
//! Rays are defined in the **locus frame** L (+X along the centre of the field of view, +Y
//! left, +Z up; see [`crate::frames`]). Column `c` (0 at the left, seen from behind the
//! scanner) looks at azimuth `az(c) = fov_az / 2 - (c + 0.5) * fov_az / width`, row `r` (0 at
//! the top) at elevation `el(r) = fov_el / 2 - (r + 0.5) * fov_el / height`, and the ray's
//! unit direction is `(cos el cos az, cos el sin az, sin el)`: the polygon mirror pans, the
//! nodding mirror tilts.
//!
//! # Range digitisation
//!
//! A phase-measuring scanner knows the range only modulo its ambiguity interval. A range `r`
//! is digitised as `floor((r mod ambiguity) / resolution)` with
//! `resolution = ambiguity / 2^bits`; a count `n` reads back as `(n + 0.5) * resolution`.
//! A pixel whose reflectance count is 0 had no return (nothing within the sensor's reach).

use nalgebra::Vector3;
use tca_single_leg_messages::{RangeImage, SensorKind};

use crate::error::{IsmError, Result};

/// The range ambiguity interval of the Erim: "approximately 20 m" with a resolution of
/// "approximately 7.62 cm" over 8 bits, i.e. 3 inches per count, 64 ft in all.
pub const ERIM_AMBIGUITY_M: f64 = 19.5072;
/// The range ambiguity interval of the Perceptron (0.98 cm per 12-bit count).
pub const PERCEPTRON_AMBIGUITY_M: f64 = 40.0;

/// A scanner's fixed characteristics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorSpec {
    /// Which scanner.
    pub kind: SensorKind,
    /// Columns (azimuth samples).
    pub width_px: u32,
    /// Rows (elevation samples).
    pub height_px: u32,
    /// Horizontal field of view, radians.
    pub azimuth_fov_rad: f64,
    /// Vertical field of view, radians.
    pub elevation_fov_rad: f64,
    /// Bits of the range channel.
    pub range_bits: u32,
    /// Bits of the reflectance channel.
    pub reflectance_bits: u32,
    /// Range ambiguity interval, metres.
    pub ambiguity_m: f64,
    /// Farthest surface that still returns enough light to be measured, metres.
    pub max_range_m: f64,
}

impl SensorSpec {
    /// The Erim: 64 x 256 pixels over 80° (azimuth) x 30° (elevation), 8-bit range and
    /// reflectance, 19.5 m ambiguity interval (7.62 cm per count).
    pub fn erim() -> Self {
        Self {
            kind: SensorKind::Erim,
            width_px: 256,
            height_px: 64,
            azimuth_fov_rad: 80_f64.to_radians(),
            elevation_fov_rad: 30_f64.to_radians(),
            range_bits: 8,
            reflectance_bits: 8,
            ambiguity_m: ERIM_AMBIGUITY_M,
            max_range_m: 2.0 * ERIM_AMBIGUITY_M,
        }
    }

    /// The Perceptron: 256 x 256 pixels over 60° x 60°, 12-bit range and reflectance, 40 m
    /// ambiguity interval (0.98 cm per count).
    pub fn perceptron() -> Self {
        Self {
            kind: SensorKind::Perceptron,
            width_px: 256,
            height_px: 256,
            azimuth_fov_rad: 60_f64.to_radians(),
            elevation_fov_rad: 60_f64.to_radians(),
            range_bits: 12,
            reflectance_bits: 12,
            ambiguity_m: PERCEPTRON_AMBIGUITY_M,
            max_range_m: 2.0 * PERCEPTRON_AMBIGUITY_M,
        }
    }

    /// The spec of a sensor kind.
    pub fn of(kind: SensorKind) -> Self {
        match kind {
            SensorKind::Erim => Self::erim(),
            SensorKind::Perceptron => Self::perceptron(),
        }
    }

    /// Pixels per image.
    pub fn pixel_count(&self) -> usize {
        self.width_px as usize * self.height_px as usize
    }

    /// Metres per range count.
    pub fn range_resolution_m(&self) -> f64 {
        self.ambiguity_m / f64::from(1u32 << self.range_bits)
    }

    /// The largest range count.
    pub fn max_range_count(&self) -> u16 {
        ((1u32 << self.range_bits) - 1) as u16
    }

    /// The largest reflectance count (full scale).
    pub fn max_reflectance_count(&self) -> u16 {
        ((1u32 << self.reflectance_bits) - 1) as u16
    }

    /// Angle between neighbouring columns, radians.
    pub fn azimuth_step_rad(&self) -> f64 {
        self.azimuth_fov_rad / f64::from(self.width_px)
    }

    /// Angle between neighbouring rows, radians.
    pub fn elevation_step_rad(&self) -> f64 {
        self.elevation_fov_rad / f64::from(self.height_px)
    }

    /// Azimuth of a column's centre, radians (positive to the left).
    pub fn column_azimuth_rad(&self, col: f64) -> f64 {
        0.5 * self.azimuth_fov_rad - (col + 0.5) * self.azimuth_step_rad()
    }

    /// Elevation of a row's centre, radians (positive up).
    pub fn row_elevation_rad(&self, row: f64) -> f64 {
        0.5 * self.elevation_fov_rad - (row + 0.5) * self.elevation_step_rad()
    }

    /// The unit direction of pixel `(row, col)` in the locus frame.
    pub fn pixel_direction(&self, row: u32, col: u32) -> Vector3<f64> {
        direction(
            self.row_elevation_rad(f64::from(row)),
            self.column_azimuth_rad(f64::from(col)),
        )
    }

    /// The continuous image position `(row, col)` a locus-frame direction falls on (pixel
    /// centres at integers), or `None` for a zero or non-finite direction. The position may
    /// lie outside the image.
    pub fn image_position(&self, d: &Vector3<f64>) -> Option<(f64, f64)> {
        let horizontal = d.x.hypot(d.y);
        if !(horizontal.is_finite() && d.z.is_finite()) || (horizontal == 0.0 && d.z == 0.0) {
            return None;
        }
        let el = d.z.atan2(horizontal);
        let az = d.y.atan2(d.x);
        let row = (0.5 * self.elevation_fov_rad - el) / self.elevation_step_rad() - 0.5;
        let col = (0.5 * self.azimuth_fov_rad - az) / self.azimuth_step_rad() - 0.5;
        Some((row, col))
    }

    /// The count a true range digitises to (wrapped at the ambiguity interval; negative
    /// ranges read 0).
    pub fn range_count(&self, range_m: f64) -> u16 {
        if !(range_m.is_finite() && range_m > 0.0) {
            return 0;
        }
        let wrapped = range_m.rem_euclid(self.ambiguity_m);
        let count = (wrapped / self.range_resolution_m()).floor();
        (count as u32).min(u32::from(self.max_range_count())) as u16
    }

    /// The range a count reads as, within the first ambiguity interval (centre of the count's
    /// bin), metres.
    pub fn count_range_m(&self, count: u16) -> f64 {
        (f64::from(count) + 0.5) * self.range_resolution_m()
    }

    /// Checks that an image fits this sensor: size, channel lengths, range resolution,
    /// ambiguity interval, fields of view and count ranges.
    pub fn check_image(&self, image: &RangeImage) -> Result<()> {
        if image.sensor != self.kind {
            return Err(IsmError::Config(format!(
                "a {:?} image was given to the {:?} sensor's check",
                image.sensor, self.kind
            )));
        }
        if image.width != self.width_px || image.height != self.height_px {
            return Err(IsmError::ImageSize {
                sensor: self.kind,
                expected_width: self.width_px,
                expected_height: self.height_px,
                width: image.width,
                height: image.height,
            });
        }
        let expected = self.pixel_count();
        for (channel, len) in [
            ("range", image.range_counts.len()),
            ("reflectance", image.reflectance.len()),
        ] {
            if len != expected {
                return Err(IsmError::ImageData {
                    channel,
                    width: image.width,
                    height: image.height,
                    expected,
                    got: len,
                });
            }
        }
        let parameters = [
            (
                "range resolution (m)",
                self.range_resolution_m(),
                image.range_resolution_m,
            ),
            (
                "ambiguity interval (m)",
                self.ambiguity_m,
                image.ambiguity_m,
            ),
            (
                "azimuth field of view (rad)",
                self.azimuth_fov_rad,
                image.azimuth_fov_rad,
            ),
            (
                "elevation field of view (rad)",
                self.elevation_fov_rad,
                image.elevation_fov_rad,
            ),
        ];
        for (parameter, expected, got) in parameters {
            let close = (got - expected).abs() <= 1e-9 * expected.abs().max(1.0);
            if !close {
                return Err(IsmError::ImageParameter {
                    sensor: self.kind,
                    parameter,
                    expected,
                    got,
                });
            }
        }
        for (channel, data, max) in [
            ("range", &image.range_counts, self.max_range_count()),
            (
                "reflectance",
                &image.reflectance,
                self.max_reflectance_count(),
            ),
        ] {
            if let Some((index, &value)) = data.iter().enumerate().find(|&(_, &v)| v > max) {
                return Err(IsmError::CountOutOfRange {
                    channel,
                    index,
                    value,
                    max,
                });
            }
        }
        Ok(())
    }
}

/// The unit direction at elevation `el` and azimuth `az` (locus frame).
pub fn direction(el: f64, az: f64) -> Vector3<f64> {
    let (se, ce) = el.sin_cos();
    let (sa, ca) = az.sin_cos();
    Vector3::new(ce * ca, ce * sa, se)
}

/// Every pixel's direction, precomputed per row and column: `direction(row, col)` costs four
/// multiplications.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelDirections {
    width: usize,
    row_cos_sin: Vec<(f64, f64)>,
    col_cos_sin: Vec<(f64, f64)>,
}

impl PixelDirections {
    /// The table of a sensor.
    pub fn new(spec: &SensorSpec) -> Self {
        let row_cos_sin = (0..spec.height_px)
            .map(|r| {
                let (s, c) = spec.row_elevation_rad(f64::from(r)).sin_cos();
                (c, s)
            })
            .collect();
        let col_cos_sin = (0..spec.width_px)
            .map(|c| {
                let (s, co) = spec.column_azimuth_rad(f64::from(c)).sin_cos();
                (co, s)
            })
            .collect();
        Self {
            width: spec.width_px as usize,
            row_cos_sin,
            col_cos_sin,
        }
    }

    /// Columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> usize {
        self.row_cos_sin.len()
    }

    /// The unit direction of pixel `(row, col)`; `None` outside the image.
    pub fn get(&self, row: usize, col: usize) -> Option<Vector3<f64>> {
        let &(ce, se) = self.row_cos_sin.get(row)?;
        let &(ca, sa) = self.col_cos_sin.get(col)?;
        Some(Vector3::new(ce * ca, ce * sa, se))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolutions_match_the_report() {
        let erim = SensorSpec::erim();
        assert!((erim.range_resolution_m() - 0.0762).abs() < 1e-6);
        let p = SensorSpec::perceptron();
        assert!((p.range_resolution_m() - 0.0098).abs() < 1e-4);
        assert_eq!(erim.pixel_count(), 64 * 256);
        assert_eq!(p.max_range_count(), 4095);
    }

    #[test]
    fn pixel_direction_round_trips_through_image_position() {
        for spec in [SensorSpec::erim(), SensorSpec::perceptron()] {
            for (r, c) in [(0, 0), (3, 200), (spec.height_px - 1, spec.width_px - 1)] {
                let d = spec.pixel_direction(r, c);
                assert!((d.norm() - 1.0).abs() < 1e-12);
                let (row, col) = spec.image_position(&d).unwrap();
                assert!((row - f64::from(r)).abs() < 1e-9, "{row} vs {r}");
                assert!((col - f64::from(c)).abs() < 1e-9, "{col} vs {c}");
                assert_eq!(
                    PixelDirections::new(&spec)
                        .get(r as usize, c as usize)
                        .unwrap(),
                    d
                );
            }
        }
    }

    #[test]
    fn column_zero_looks_left_and_row_zero_looks_up() {
        let spec = SensorSpec::erim();
        let top_left = spec.pixel_direction(0, 0);
        assert!(top_left.y > 0.0 && top_left.z > 0.0);
        let angle = top_left.y.atan2(top_left.x);
        assert!((angle - (40_f64.to_radians() - spec.azimuth_step_rad() / 2.0)).abs() < 1e-12);
    }

    #[test]
    fn ranges_wrap_at_the_ambiguity_interval() {
        let spec = SensorSpec::erim();
        let a = spec.range_count(5.0);
        let b = spec.range_count(5.0 + ERIM_AMBIGUITY_M);
        assert_eq!(a, b);
        assert!((spec.count_range_m(a) - 5.0).abs() <= spec.range_resolution_m() / 2.0);
        assert_eq!(spec.range_count(-1.0), 0);
        assert_eq!(spec.range_count(f64::NAN), 0);
        assert_eq!(spec.range_count(ERIM_AMBIGUITY_M - 1e-9), 255);
    }
}
