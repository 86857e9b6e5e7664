//! The reachable workspace of a foot, sampled over the joint ranges.

use std::fmt;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::leg::Leg;
use crate::sampler::Sampler;

/// Seed of the workspace samples (the same leg always gives the same samples).
const WORKSPACE_SEED: u64 = 0x0057_0125_9ACE;

/// Where a foot can go: the bounds of foot positions sampled over the joint ranges.
///
/// The samples are the corners of the joint ranges (every joint at a limit, when there are
/// few enough) and uniformly random joint positions, so the bounds are a little inside the
/// true ones and tighten with more samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkspaceSummary {
    /// The leg's name.
    pub leg: String,
    /// How many joint positions were sampled.
    pub samples: usize,
    /// Smallest x, y and z of the foot (contact-sphere centre) in the body frame, metres.
    pub min: Point3<f64>,
    /// Largest x, y and z of the foot in the body frame, metres.
    pub max: Point3<f64>,
    /// Where the leg meets the body (its first joint), body frame.
    pub base: Point3<f64>,
    /// Smallest horizontal (x, y) distance of the foot from the base, metres.
    pub reach_min_m: f64,
    /// Largest horizontal distance of the foot from the base, metres.
    pub reach_max_m: f64,
}

impl fmt::Display for WorkspaceSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: foot x {:.3}..{:.3}, y {:.3}..{:.3}, z {:.3}..{:.3} m; {:.3}..{:.3} m out from \
             the base at ({:.3}, {:.3}, {:.3}) m ({} samples)",
            self.leg,
            self.min.x,
            self.max.x,
            self.min.y,
            self.max.y,
            self.min.z,
            self.max.z,
            self.reach_min_m,
            self.reach_max_m,
            self.base.x,
            self.base.y,
            self.base.z,
            self.samples
        )
    }
}

impl Leg {
    /// Joint positions spread over the joint ranges: the corners of the ranges when there
    /// are at most `count / 2` of them, then uniformly random ones, `count` in all
    /// (deterministic).
    pub fn joint_samples(&self, count: usize) -> Vec<Vec<f64>> {
        let mut samples = Vec::with_capacity(count);
        let dof = self.dof();
        if dof < 20 && (1usize << dof) <= count / 2 {
            for corner in 0..(1usize << dof) {
                samples.push(
                    self.joints
                        .iter()
                        .enumerate()
                        .map(|(i, j)| {
                            if corner >> i & 1 == 0 {
                                j.limits.lower
                            } else {
                                j.limits.upper
                            }
                        })
                        .collect(),
                );
            }
        }
        let mut sampler = Sampler::new(WORKSPACE_SEED);
        while samples.len() < count {
            samples.push(sampler.joints(self));
        }
        samples
    }

    /// Foot positions (contact-sphere centres, body frame) at
    /// [`joint_samples`](Self::joint_samples)`(count)`.
    pub fn workspace_samples(&self, count: usize) -> Vec<Point3<f64>> {
        self.joint_samples(count)
            .iter()
            .map(|q| self.foot_position_unchecked(q))
            .collect()
    }

    /// The bounds of [`workspace_samples`](Self::workspace_samples)`(count)` (at least one
    /// sample is taken).
    pub fn workspace_summary(&self, count: usize) -> WorkspaceSummary {
        let points = self.workspace_samples(count.max(1));
        let base = self.base_position();
        let mut min = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut max = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        let (mut reach_min, mut reach_max) = (f64::INFINITY, 0.0f64);
        for p in &points {
            min = min.inf(p);
            max = max.sup(p);
            let reach = (p.x - base.x).hypot(p.y - base.y);
            reach_min = reach_min.min(reach);
            reach_max = reach_max.max(reach);
        }
        WorkspaceSummary {
            leg: self.name.clone(),
            samples: points.len(),
            min,
            max,
            base,
            reach_min_m: reach_min,
            reach_max_m: reach_max,
        }
    }
}
