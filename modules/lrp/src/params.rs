//! Parameters of the Leg Recovery Planner. The mechanism (link lengths, foot radius, joint
//! limits and speeds) comes from `tca_robot::LegParams`; these are the planner's own choices.

use serde::{Deserialize, Serialize};

use crate::cost::CostModel;
use crate::error::{PlanError, Result};

/// The Leg Recovery Planner's parameters (defaults follow §6.2.2 and §6.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LrpParams {
    /// Width of a configuration-space cell along the shoulder, radians. The elbow's cells are
    /// scaled by the ratio of the joint speeds so that every cell takes the same time to
    /// cross (0.08 rad shoulder, 0.12 rad elbow with the shipped speeds: "about 0.1 rad").
    pub shoulder_cell_rad: f64,
    /// Uncertainty margin added to the foot's radius when growing obstacles, metres.
    pub uncertainty_margin_m: f64,
    /// Vertical clearance kept above the grown terrain, metres.
    pub clearance_m: f64,
    /// Known heights count as `height + sigma_factor * sigma` (the LTM's uncertainty).
    pub sigma_factor: f64,
    /// Unknown terrain counts as an obstacle this high, metres (world Z).
    pub unknown_height_m: f64,
    /// The foot may start this far below the mapped terrain (map noise, a foot pressed into
    /// sand) before the start counts as a collision, metres.
    pub start_tolerance_m: f64,
    /// Every trajectory first lifts the foot straight up at least this far, metres: a foot
    /// on the ground (or one that just struck terrain the map got wrong) clears it before
    /// any sideways motion.
    #[serde(default = "default_start_lift_m")]
    pub start_lift_m: f64,
    /// The transition move aims this far below the expected ground, metres, so that it
    /// stops on contact even when the ground is lower than mapped.
    pub transition_overshoot_m: f64,
    /// Lowest ground a footfall may have above the foot's lowest reach, metres (room to
    /// press the foot into the ground).
    pub footfall_low_margin_m: f64,
    /// Cost model: time, energy, turn penalty.
    pub cost: CostModel,
}

impl Default for LrpParams {
    fn default() -> Self {
        Self {
            shoulder_cell_rad: 0.08,
            uncertainty_margin_m: 0.05,
            clearance_m: 0.10,
            sigma_factor: 2.0,
            unknown_height_m: 0.8,
            start_tolerance_m: 0.05,
            start_lift_m: default_start_lift_m(),
            transition_overshoot_m: 0.15,
            footfall_low_margin_m: 0.05,
            cost: CostModel::default(),
        }
    }
}

fn default_start_lift_m() -> f64 {
    0.1
}

impl LrpParams {
    /// Checks every parameter; the error names the offending key.
    pub fn validate(&self) -> Result<()> {
        let positive = [("shoulder_cell_rad", self.shoulder_cell_rad)];
        for (key, value) in positive {
            if !(value.is_finite() && value > 0.0 && value <= 1.0) {
                return Err(PlanError::BadParams {
                    key,
                    value,
                    reason: "must be greater than 0 and at most 1 rad",
                });
            }
        }
        let non_negative = [
            ("uncertainty_margin_m", self.uncertainty_margin_m),
            ("clearance_m", self.clearance_m),
            ("sigma_factor", self.sigma_factor),
            ("start_tolerance_m", self.start_tolerance_m),
            ("start_lift_m", self.start_lift_m),
            ("transition_overshoot_m", self.transition_overshoot_m),
            ("footfall_low_margin_m", self.footfall_low_margin_m),
        ];
        for (key, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(PlanError::BadParams {
                    key,
                    value,
                    reason: "must be a finite number of at least 0",
                });
            }
        }
        if !self.unknown_height_m.is_finite() {
            return Err(PlanError::BadParams {
                key: "unknown_height_m",
                value: self.unknown_height_m,
                reason: "must be a finite height in metres",
            });
        }
        self.cost.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        LrpParams::default().validate().unwrap();
    }

    #[test]
    fn bad_values_name_their_key() {
        let p = LrpParams {
            shoulder_cell_rad: 0.0,
            ..LrpParams::default()
        };
        assert!(
            p.validate()
                .unwrap_err()
                .to_string()
                .contains("shoulder_cell_rad")
        );
        let p = LrpParams {
            clearance_m: f64::NAN,
            ..LrpParams::default()
        };
        assert!(
            p.validate()
                .unwrap_err()
                .to_string()
                .contains("clearance_m")
        );
    }
}
