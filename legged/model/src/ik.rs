//! Numeric inverse kinematics of a foot position: damped least squares within the joint
//! limits, from several starts.

use nalgebra::{DVector, Matrix3, Point3};
use serde::{Deserialize, Serialize};

use crate::error::KinematicsError;
use crate::leg::Leg;
use crate::sampler::Sampler;

/// A descent stops after this many steps in a row that each gain less than
/// `STALL_GAIN` times the tolerance.
const STALL_STEPS: usize = 5;
const STALL_GAIN: f64 = 1e-3;

/// How hard [`Leg::inverse_kinematics`] tries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IkOptions {
    /// A solution puts the foot this close to the target, metres.
    pub tolerance_m: f64,
    /// Steps allowed from each start.
    pub max_iterations: usize,
    /// Random starts tried after the given, neutral and middle ones.
    pub random_starts: usize,
    /// Joint positions to start from first (for example the leg's current ones), so that the
    /// answer stays near them when it can; moved into the limits if outside.
    pub initial: Option<Vec<f64>>,
    /// Seed of the random starts (the same seed gives the same answers).
    pub seed: u64,
}

impl Default for IkOptions {
    fn default() -> Self {
        Self {
            tolerance_m: 1e-4,
            max_iterations: 100,
            random_starts: 32,
            initial: None,
            seed: 0x5EED_1E65,
        }
    }
}

impl IkOptions {
    /// The defaults, starting from these joint positions.
    pub fn starting_at(initial: &[f64]) -> Self {
        Self {
            initial: Some(initial.to_vec()),
            ..Self::default()
        }
    }
}

/// Joint positions that put the foot at a target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IkSolution {
    /// The joint positions, within the limits.
    pub joints: Vec<f64>,
    /// Distance from the foot to the target, metres (at most the tolerance).
    pub error_m: f64,
    /// Steps taken over all starts.
    pub iterations: usize,
}

/// Where one descent ended.
struct Descent {
    joints: Vec<f64>,
    error_m: f64,
    iterations: usize,
}

impl Leg {
    /// Joint positions within the limits that put the centre of the foot's contact sphere
    /// (see [`foot_position`](Leg::foot_position)) at `target`, in the body frame.
    ///
    /// Damped least squares (Levenberg-Marquardt): each step solves
    /// `(J Jᵀ + λ² I) y = e`, moves by `Jᵀ y`, and keeps the joints within their limits by
    /// freezing a joint that a step would push past a limit it already sits on. The damping
    /// shrinks after a step that brings the foot closer and grows after one that does not.
    /// Starts: `options.initial`, the neutral and the middle positions, then random ones;
    /// the first descent that comes within the tolerance is the answer. A leg with more
    /// joints than the three a position needs takes whichever solution its start leads to.
    ///
    /// Returns [`KinematicsError::Unreachable`] when no start reaches the target, at once
    /// for a target beyond [`reach_bound`](Leg::reach_bound). Solving a reachable target
    /// takes some microseconds; refusing one within the bound runs every start (half a
    /// millisecond to a few milliseconds for the shipped robots).
    pub fn inverse_kinematics(
        &self,
        target: &Point3<f64>,
        options: &IkOptions,
    ) -> Result<IkSolution, KinematicsError> {
        if !target.coords.iter().all(|v| v.is_finite()) {
            return Err(KinematicsError::NotFinite {
                leg: self.name.clone(),
                what: "the target".to_owned(),
            });
        }
        let mut starts = Vec::new();
        if let Some(initial) = &options.initial {
            self.check(initial)?;
            starts.push(self.clamp(initial));
        }
        let beyond = (target - self.base_position()).norm() - self.reach_bound();
        if beyond > options.tolerance_m {
            return Err(KinematicsError::Unreachable {
                leg: self.name.clone(),
                target: [target.x, target.y, target.z],
                closest_m: beyond,
            });
        }
        starts.push(self.neutral());
        starts.push(self.middle());
        let mut sampler = Sampler::new(options.seed);
        let tolerance = options.tolerance_m.max(1e-12);
        let mut iterations = 0;
        let mut closest = f64::INFINITY;
        let total = starts.len() + options.random_starts;
        for n in 0..total {
            let start = if n < starts.len() {
                starts[n].clone()
            } else {
                sampler.joints(self)
            };
            let descent = self.descend(target, start, tolerance, options.max_iterations);
            iterations += descent.iterations;
            if descent.error_m <= tolerance {
                return Ok(IkSolution {
                    joints: descent.joints,
                    error_m: descent.error_m,
                    iterations,
                });
            }
            closest = closest.min(descent.error_m);
        }
        Err(KinematicsError::Unreachable {
            leg: self.name.clone(),
            target: [target.x, target.y, target.z],
            closest_m: closest,
        })
    }

    fn descend(
        &self,
        target: &Point3<f64>,
        mut q: Vec<f64>,
        tolerance: f64,
        max_iterations: usize,
    ) -> Descent {
        let scale = self.length_scale();
        let (min_damping, max_damping) = (1e-7 * scale, 1e3 * scale);
        let mut damping = 0.01 * scale;
        let mut error = target - self.foot_position_unchecked(&q);
        let mut distance = error.norm();
        let mut iterations = 0;
        let mut stalled = 0;
        while iterations < max_iterations && distance > tolerance {
            iterations += 1;
            let step = self.limited_step(&q, &error, damping);
            let candidate: Vec<f64> = self
                .joints
                .iter()
                .zip(q.iter().zip(step.iter()))
                .map(|(j, (v, dv))| j.limits.clamp(v + dv))
                .collect();
            let candidate_error = target - self.foot_position_unchecked(&candidate);
            let candidate_distance = candidate_error.norm();
            if candidate_distance < distance {
                // Steps that gain almost nothing mean a local minimum away from the target.
                stalled = if distance - candidate_distance < STALL_GAIN * tolerance {
                    stalled + 1
                } else {
                    0
                };
                if stalled >= STALL_STEPS {
                    break;
                }
                q = candidate;
                error = candidate_error;
                distance = candidate_distance;
                damping = (damping * 0.3).max(min_damping);
            } else {
                damping *= 5.0;
                if damping > max_damping {
                    break;
                }
            }
        }
        Descent {
            joints: q,
            error_m: distance,
            iterations,
        }
    }

    /// A damped least-squares step towards `error`, with the joints that sit on a limit and
    /// would be pushed past it frozen.
    fn limited_step(
        &self,
        q: &[f64],
        error: &nalgebra::Vector3<f64>,
        damping: f64,
    ) -> DVector<f64> {
        let mut jacobian = self.jacobian_unchecked(q);
        let mut frozen = vec![false; q.len()];
        loop {
            let a = &jacobian * jacobian.transpose() + Matrix3::identity() * (damping * damping);
            let y = match a.cholesky() {
                Some(c) => c.solve(error),
                None => return DVector::zeros(q.len()),
            };
            let step = jacobian.transpose() * y;
            let mut changed = false;
            for (i, joint) in self.joints.iter().enumerate() {
                let limits = joint.limits;
                let pushing_out = (q[i] <= limits.lower && step[i] < 0.0)
                    || (q[i] >= limits.upper && step[i] > 0.0);
                if !frozen[i] && pushing_out {
                    frozen[i] = true;
                    jacobian.column_mut(i).fill(0.0);
                    changed = true;
                }
            }
            if !changed {
                return step;
            }
        }
    }
}
