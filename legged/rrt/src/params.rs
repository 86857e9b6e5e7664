//! The planner's parameters.

use serde::{Deserialize, Serialize};

use crate::error::PlanError;

/// How the legs take turns while the body moves from one node to the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Gait {
    /// Two alternating groups of three legs (front and rear of one side with the middle of
    /// the other); the body moves half the way while each group swings.
    #[default]
    Tripod,
    /// One leg at a time, rear to front on the right and then on the left; the body moves a
    /// sixth of the way while each leg swings.
    Wave,
}

impl Gait {
    /// The gait called `name` (`tripod` or `wave`).
    pub fn from_name(name: &str) -> Result<Gait, PlanError> {
        match name {
            "tripod" => Ok(Gait::Tripod),
            "wave" => Ok(Gait::Wave),
            other => Err(PlanError::BadParameter(format!(
                "unknown gait `{other}`; give `tripod` or `wave`"
            ))),
        }
    }

    /// The gait's name.
    pub fn name(self) -> &'static str {
        match self {
            Gait::Tripod => "tripod",
            Gait::Wave => "wave",
        }
    }
}

/// Everything the planner can be tuned by. Lengths in metres, angles in radians.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RrtParams {
    /// Iterations of the RRT-Connect loop before "no path" (the paper's K).
    pub max_iterations: usize,
    /// Tries of one EXTEND, the step halved after each failure (the paper's N).
    pub extend_attempts: usize,
    /// Longest step between two nodes, metres (the paper's d_max).
    pub max_step_m: f64,
    /// Shortest step worth a node, metres: a shortened step below it is Trapped.
    pub min_step_m: f64,
    /// Least distance from the bottom of the body to the highest ground under it (the
    /// paper's d_max^body), metres.
    pub body_clearance_m: f64,
    /// Height of a swinging foot's path above the terrain profile (the paper's
    /// d_min^foot), metres.
    pub foot_clearance_m: f64,
    /// The support polygon is shrunk by this much before the centre of mass is tested in
    /// it, metres.
    pub stability_margin_m: f64,
    /// Steepest roll or pitch of the body, radians.
    pub max_inclination_rad: f64,
    /// Footholds are sought within this distance of where the neutral posture puts the
    /// foot, metres.
    pub foothold_search_m: f64,
    /// Weight of the workspace-border term against the terrain term of a foothold.
    pub border_weight: f64,
    /// Spacing of the postures checked along a move, metres of body travel (swings are
    /// also sampled along their path at this spacing).
    pub check_spacing_m: f64,
    /// Radius of the capsules that stand for the leg links in the collision checks, metres.
    pub link_radius_m: f64,
    /// Largest change of heading between two nodes, radians: a new node faces the way
    /// the robot walks to it, turned at most this much from its parent.
    pub max_turn_rad: f64,
    /// The gait of every move.
    pub gait: Gait,
    /// Seed of the random samples.
    pub seed: u64,
}

impl Default for RrtParams {
    fn default() -> Self {
        RrtParams {
            max_iterations: 3000,
            extend_attempts: 4,
            max_step_m: 0.10,
            min_step_m: 0.01,
            body_clearance_m: 0.03,
            foot_clearance_m: 0.03,
            stability_margin_m: 0.02,
            max_inclination_rad: 30f64.to_radians(),
            foothold_search_m: 0.04,
            border_weight: 0.5,
            check_spacing_m: 0.01,
            link_radius_m: 0.01,
            max_turn_rad: 0.3,
            gait: Gait::Tripod,
            seed: 1,
        }
    }
}

impl RrtParams {
    /// Refuses parameters the planner cannot work with, saying which and why.
    pub fn validate(&self) -> Result<(), PlanError> {
        let positive = [
            ("max_step_m", self.max_step_m),
            ("min_step_m", self.min_step_m),
            ("check_spacing_m", self.check_spacing_m),
            ("foothold_search_m", self.foothold_search_m),
            ("max_inclination_rad", self.max_inclination_rad),
            ("max_turn_rad", self.max_turn_rad),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(PlanError::BadParameter(format!(
                    "{name} is {v}; give a finite value greater than zero"
                )));
            }
        }
        let non_negative = [
            ("body_clearance_m", self.body_clearance_m),
            ("foot_clearance_m", self.foot_clearance_m),
            ("stability_margin_m", self.stability_margin_m),
            ("border_weight", self.border_weight),
            ("link_radius_m", self.link_radius_m),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(PlanError::BadParameter(format!(
                    "{name} is {v}; give a finite value of zero or more"
                )));
            }
        }
        if self.min_step_m > self.max_step_m {
            return Err(PlanError::BadParameter(format!(
                "min_step_m ({}) is longer than max_step_m ({}); make it shorter",
                self.min_step_m, self.max_step_m
            )));
        }
        if self.max_iterations == 0 || self.extend_attempts == 0 {
            return Err(PlanError::BadParameter(
                "max_iterations and extend_attempts must be at least 1".to_owned(),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_refused() {
        RrtParams::default().validate().unwrap();
        let bad = RrtParams {
            max_step_m: -1.0,
            ..RrtParams::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("max_step_m")
        );
        let bad = RrtParams {
            min_step_m: 0.5,
            ..RrtParams::default()
        };
        assert!(bad.validate().is_err());
        assert_eq!(Gait::from_name("wave").unwrap(), Gait::Wave);
        assert!(Gait::from_name("trot").is_err());
    }
}
