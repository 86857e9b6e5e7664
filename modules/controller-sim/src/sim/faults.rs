//! Faults injected for testing, each producing the error the real Controller reported.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::error::{Result, SimError};

/// Standard deviations of the joints' positioning noise at the end of a move.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointNoise {
    /// Shoulder, radians.
    pub shoulder_rad: f64,
    /// Elbow, radians.
    pub elbow_rad: f64,
    /// Vertical axis, metres.
    pub vertical_m: f64,
}

/// A fault that happens at a chosen moment rather than by chance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// The foot slips during the body move (past `slip_detect_m`): a move failure, after
    /// which the planners can replan from where the leg is.
    Slip,
    /// The foot force drops off during the body move: an emergency stop, a hardware fault.
    ForceDrop,
    /// A limit switch trips during the body move: a hardware fault.
    LimitSwitch,
}

impl FaultKind {
    /// Every kind, in the order the command line lists them.
    pub const ALL: [FaultKind; 3] = [
        FaultKind::Slip,
        FaultKind::ForceDrop,
        FaultKind::LimitSwitch,
    ];

    /// The name the command line uses (`slip`, `force-drop`, `limit-switch`).
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::Slip => "slip",
            FaultKind::ForceDrop => "force-drop",
            FaultKind::LimitSwitch => "limit-switch",
        }
    }
}

/// A fault injected half-way through the `body_move`-th body move since the simulator
/// started (counted from 1: in a walk from the start, the body move of step `body_move` when
/// nothing has been replanned).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScheduledFault {
    /// What happens.
    pub kind: FaultKind,
    /// During which body move, from 1.
    pub body_move: u32,
}

impl ScheduledFault {
    /// Parses `KIND@N` (`slip@3`, `force-drop@2`, `limit-switch@1`), saying what is wrong.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        let kinds = FaultKind::ALL.map(FaultKind::name).join(", ");
        let Some((kind, at)) = text.split_once('@') else {
            return Err(format!(
                "fault {text:?} is not KIND@STEP; give one of {kinds} and a step number, e.g. slip@3"
            ));
        };
        let kind = FaultKind::ALL
            .into_iter()
            .find(|k| k.name() == kind.trim())
            .ok_or_else(|| format!("no fault kind {kind:?}; the kinds are {kinds}"))?;
        let body_move = at
            .trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| format!("fault step {at:?} must be a step number, 1 or more"))?;
        Ok(Self { kind, body_move })
    }
}

impl std::fmt::Display for ScheduledFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}@{}", self.kind.name(), self.body_move)
    }
}

/// Which faults to inject and how strongly. [`FaultConfig::none`] (the default) injects
/// nothing and uses the rigid kinematics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaultConfig {
    /// Seed of the fault generator (same seed, same faults).
    pub seed: u64,
    /// Chance that a body move slips (0..=1).
    pub slip_probability: f64,
    /// How far the foot slides when it slips, metres. A slip shorter than the body move's
    /// `slip_detect_m` goes unnoticed (the foot just ends up elsewhere).
    pub slip_distance_m: f64,
    /// Chance that the foot force drops off during a body move (0..=1): emergency stop.
    pub force_drop_probability: f64,
    /// Chance that a limit switch trips spuriously during any move (0..=1).
    pub limit_switch_probability: f64,
    /// Positioning noise at the end of each leg move; a joint off by more than the
    /// simulation's servo tolerance raises a servo error.
    pub joint_noise: JointNoise,
    /// Scale of the compliance deflection model (§4.3): 0 = rigid leg, 1 = the model in the
    /// parameters. The real foot is off the rigid kinematics by this much, and body moves
    /// leave strain in the leg that is relieved at their end.
    pub compliance_scale: f64,
    /// A fault at a chosen body move, on top of the chance ones.
    pub scheduled: Option<ScheduledFault>,
}

impl Default for FaultConfig {
    fn default() -> Self {
        Self::none()
    }
}

impl FaultConfig {
    /// No faults, rigid leg.
    pub fn none() -> Self {
        Self {
            seed: 0,
            slip_probability: 0.0,
            slip_distance_m: 0.05,
            force_drop_probability: 0.0,
            limit_switch_probability: 0.0,
            joint_noise: JointNoise::default(),
            compliance_scale: 0.0,
            scheduled: None,
        }
    }

    /// Checks that probabilities are in [0, 1] and magnitudes finite and not negative.
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| Err(SimError::InvalidStart { reason });
        for (name, p) in [
            ("slip_probability", self.slip_probability),
            ("force_drop_probability", self.force_drop_probability),
            ("limit_switch_probability", self.limit_switch_probability),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return bad(format!("fault {name} = {p} must be between 0 and 1"));
            }
        }
        for (name, v) in [
            ("slip_distance_m", self.slip_distance_m),
            ("joint_noise.shoulder_rad", self.joint_noise.shoulder_rad),
            ("joint_noise.elbow_rad", self.joint_noise.elbow_rad),
            ("joint_noise.vertical_m", self.joint_noise.vertical_m),
            ("compliance_scale", self.compliance_scale),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!(
                    "fault {name} = {v} must be a finite number, zero or more"
                ));
            }
        }
        Ok(())
    }
}

/// A standard normal sample (Box-Muller).
pub(crate) fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Whether an event of probability `p` happens.
pub(crate) fn happens(rng: &mut ChaCha8Rng, p: f64) -> bool {
    p > 0.0 && rng.random::<f64>() < p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scheduled_faults_parse_and_print_back() {
        for text in ["slip@3", "force-drop@1", "limit-switch@12"] {
            assert_eq!(ScheduledFault::parse(text).unwrap().to_string(), text);
        }
        for (bad, says) in [
            ("slip", "KIND@STEP"),
            ("skid@2", "the kinds are slip, force-drop, limit-switch"),
            ("slip@0", "1 or more"),
            ("slip@x", "1 or more"),
        ] {
            let e = ScheduledFault::parse(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
