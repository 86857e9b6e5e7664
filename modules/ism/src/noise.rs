//! The virtual scanners' measurement model: seeded Gaussian range and reflectance noise, and
//! the reflectance of what a ray hits.
//!
//! Noise is drawn from a ChaCha8 generator seeded per image row from
//! `(seed, image sequence, row)`, so an image is the same whatever the number of threads that
//! cast it, and two scanners with the same seed produce the same images.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_single_leg_messages::SensorKind;

/// Range and reflectance noise. The range noise's standard deviation grows linearly with the
/// range: `sigma(r) = range_sigma_m + range_sigma_per_m * r`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NoiseModel {
    /// Range noise at zero range, metres (one standard deviation).
    pub range_sigma_m: f64,
    /// Growth of the range noise per metre of range.
    pub range_sigma_per_m: f64,
    /// Reflectance noise as a fraction of full scale (one standard deviation).
    pub reflectance_sigma: f64,
}

impl NoiseModel {
    /// No noise: only quantisation.
    pub fn none() -> Self {
        Self {
            range_sigma_m: 0.0,
            range_sigma_per_m: 0.0,
            reflectance_sigma: 0.0,
        }
    }

    /// The default noise of a sensor: Erim 2 cm + 0.1 % of the range, Perceptron 4 mm +
    /// 0.05 % of the range, both 1 % of full scale in reflectance.
    pub fn default_for(kind: SensorKind) -> Self {
        match kind {
            SensorKind::Erim => Self {
                range_sigma_m: 0.02,
                range_sigma_per_m: 0.001,
                reflectance_sigma: 0.01,
            },
            SensorKind::Perceptron => Self {
                range_sigma_m: 0.004,
                range_sigma_per_m: 0.0005,
                reflectance_sigma: 0.01,
            },
        }
    }

    /// Standard deviation of the range noise at `range_m`, metres.
    pub fn range_sigma_at(&self, range_m: f64) -> f64 {
        self.range_sigma_m + self.range_sigma_per_m * range_m.max(0.0)
    }

    /// Whether every parameter is finite and non-negative.
    pub fn is_valid(&self) -> bool {
        [
            self.range_sigma_m,
            self.range_sigma_per_m,
            self.reflectance_sigma,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0)
    }
}

/// How bright surfaces look: `albedo * cos(incidence) * min(1, (reference / range)^2)` of full
/// scale for terrain; retro-reflective calibration targets saturate.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReflectanceModel {
    /// Fraction of full scale a terrain surface facing the scanner returns at or inside the
    /// reference range.
    pub terrain_albedo: f64,
    /// Range inside which the return does not weaken, metres.
    pub reference_range_m: f64,
}

impl Default for ReflectanceModel {
    fn default() -> Self {
        Self {
            terrain_albedo: 0.5,
            reference_range_m: 4.0,
        }
    }
}

impl ReflectanceModel {
    /// Fraction of full scale returned by terrain at `range_m` seen at `cos_incidence`.
    pub fn terrain(&self, range_m: f64, cos_incidence: f64) -> f64 {
        let falloff = if range_m > self.reference_range_m {
            (self.reference_range_m / range_m).powi(2)
        } else {
            1.0
        };
        (self.terrain_albedo * cos_incidence.abs() * falloff).clamp(0.0, 1.0)
    }
}

/// The noise generator of one image row.
pub(crate) fn row_rng(seed: u64, sequence: u64, row: u32) -> ChaCha8Rng {
    let mut x = seed ^ 0x9e37_79b9_7f4a_7c15;
    for v in [sequence, u64::from(row)] {
        x = splitmix(x ^ v);
    }
    ChaCha8Rng::seed_from_u64(x)
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Standard normal samples by the Box–Muller transform, which makes them in pairs: the
/// second of each pair is kept for the next call.
#[derive(Debug, Default)]
pub(crate) struct Normal {
    spare: Option<f64>,
}

impl Normal {
    /// The next standard normal sample.
    pub(crate) fn sample(&mut self, rng: &mut impl Rng) -> f64 {
        if let Some(v) = self.spare.take() {
            return v;
        }
        let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
        let u2: f64 = rng.random::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_samples_have_unit_variance() {
        let mut rng = row_rng(7, 0, 0);
        let mut normal = Normal::default();
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|_| normal.sample(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((var - 1.0).abs() < 0.05, "{var}");
        // Consecutive samples (the two halves of a pair) are uncorrelated.
        let cov = xs.chunks_exact(2).map(|p| p[0] * p[1]).sum::<f64>() / (n / 2) as f64;
        assert!(cov.abs() < 0.03, "{cov}");
    }

    #[test]
    fn rows_get_different_streams_and_seeds_repeat() {
        let a: f64 = row_rng(1, 2, 3).random();
        let b: f64 = row_rng(1, 2, 4).random();
        let c: f64 = row_rng(1, 2, 3).random();
        assert_ne!(a, b);
        assert_eq!(a, c);
    }

    #[test]
    fn reflectance_falls_off_beyond_the_reference_range() {
        let m = ReflectanceModel::default();
        assert_eq!(m.terrain(1.0, 1.0), 0.5);
        assert!((m.terrain(8.0, 1.0) - 0.125).abs() < 1e-12);
        assert!(m.terrain(8.0, 0.5) < m.terrain(8.0, 1.0));
    }
}
