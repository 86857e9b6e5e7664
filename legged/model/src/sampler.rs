//! A small deterministic generator of joint positions, so that sampling and the inverse
//! kinematics' random starts give the same answers on every run.

use crate::leg::Leg;

/// SplitMix64: tiny, fast, and good enough to spread samples over joint ranges.
#[derive(Debug, Clone)]
pub(crate) struct Sampler {
    state: u64,
}

impl Sampler {
    pub(crate) fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in [0, 1).
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Joint positions drawn uniformly within the leg's limits.
    pub(crate) fn joints(&mut self, leg: &Leg) -> Vec<f64> {
        leg.joints()
            .iter()
            .map(|j| {
                let l = j.limits();
                l.lower + self.unit() * l.span()
            })
            .collect()
    }
}
