//! Odometry whose error grows with the distance travelled, as visual odometry's does.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{Pose2, gaussian};

/// Dead reckoning from the true motion with a seeded error.
///
/// Each run draws a fixed bias: every translation is scaled and rotated so that its error
/// is `drift` of its length in a random direction (1.2–1.3 % in the paper's tests). On top
/// of it, each increment gets white noise of a fifth of that per step, and each turn a
/// heading error of 0.2 % of the angle turned.
#[derive(Debug, Clone)]
pub struct DriftingOdometry {
    drift: f64,
    rng: ChaCha8Rng,
    /// The per-run bias as a complex factor (cos, sin) * (1 + s).
    bias: (f64, f64),
    estimate: Pose2,
    travelled_m: f64,
}

impl DriftingOdometry {
    /// Odometry starting from `start` (known exactly) with a `drift` fraction of the
    /// distance travelled (0.0125 for 1.25 %), seeded.
    pub fn new(start: Pose2, drift: f64, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0D0_3E7A);
        let psi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let drift = if drift.is_finite() {
            drift.max(0.0)
        } else {
            0.0
        };
        Self {
            drift,
            bias: (1.0 + drift * psi.cos(), drift * psi.sin()),
            rng,
            estimate: start,
            travelled_m: 0.0,
        }
    }

    /// The estimate after the robot moved from `from` to `to` (true poses).
    pub fn update(&mut self, from: &Pose2, to: &Pose2) -> Pose2 {
        let (f, l, t) = from.delta_to(to);
        let len = f.hypot(l);
        self.travelled_m += len;
        let (bc, bs) = self.bias;
        let sigma = 0.2 * self.drift * len;
        let fe = bc * f - bs * l + sigma * gaussian(&mut self.rng);
        let le = bs * f + bc * l + sigma * gaussian(&mut self.rng);
        let te = t + 0.002 * t.abs() * gaussian(&mut self.rng);
        // The increment is applied in the estimated frame: heading errors carry on.
        self.estimate = self.estimate.moved(fe, le, te);
        self.estimate
    }

    /// The current estimate.
    pub fn estimate(&self) -> Pose2 {
        self.estimate
    }

    /// True distance travelled so far, m.
    pub fn travelled_m(&self) -> f64 {
        self.travelled_m
    }
}
