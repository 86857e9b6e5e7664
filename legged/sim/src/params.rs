//! Where the robot starts and how the simulator samples and judges moves.

use serde::{Deserialize, Serialize};
use tca_legged_model::RobotModel;

/// Where the robot is stood up: the body origin's ground position and heading, world frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StartPose {
    /// East, metres.
    pub x_m: f64,
    /// North, metres.
    pub y_m: f64,
    /// Heading of the body's x axis, counter-clockwise from east, radians.
    pub yaw_rad: f64,
}

/// How the simulator samples moves and what it refuses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimParams {
    /// A body move is refused when the centre of mass margin along it would fall below
    /// this, metres (0: the centre of mass may reach the polygon's edge, not pass it).
    pub min_body_margin_m: f64,
    /// A leg move is refused when the margin of the remaining stance along it would fall
    /// below this, metres.
    pub min_lift_margin_m: f64,
    /// The largest distance any point of the robot travels between two collision samples
    /// of a move, metres (bounded from the joint motion).
    pub collision_step_m: f64,
    /// A swinging foot sphere may dip this far into the ground before it counts as
    /// driven into it, metres (rounding of the contact search, not a licence to dig).
    pub contact_tolerance_m: f64,
    /// The body's height over the ground under its feet at the start, metres.
    pub standing_height_m: f64,
    /// The steepest ground a foot may stand on at the start, radians.
    pub max_start_slope_rad: f64,
    /// Refuse, before moving, a move that would leave the robot unstable (true, the
    /// default). When false the simulator carries such a move out and the robot tips over:
    /// for testing what a walker does after a fall.
    pub refuse_unstable_moves: bool,
    /// The robot sags under load when a leg lifts (`None`, the default: a rigid robot).
    #[serde(default)]
    pub sag: Option<crate::sag::SagParams>,
}

impl SimParams {
    /// Defaults scaled to the robot: collision samples every 1 % of its standing height,
    /// a contact tolerance of 0.1 % of it, margins 0, standing at its neutral height.
    pub fn for_model(model: &RobotModel) -> Self {
        let h = model.neutral_height();
        Self {
            min_body_margin_m: 0.0,
            min_lift_margin_m: 0.0,
            collision_step_m: h / 100.0,
            contact_tolerance_m: h / 1000.0,
            standing_height_m: h,
            max_start_slope_rad: 35f64.to_radians(),
            refuse_unstable_moves: true,
            sag: None,
        }
    }

    /// Refuses values that make no sense, saying which.
    pub(crate) fn check(&self) -> Result<(), String> {
        let positive = [
            ("collision_step_m", self.collision_step_m),
            ("standing_height_m", self.standing_height_m),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} is {v}; give a finite number above 0"));
            }
        }
        let finite = [
            ("min_body_margin_m", self.min_body_margin_m),
            ("min_lift_margin_m", self.min_lift_margin_m),
            ("contact_tolerance_m", self.contact_tolerance_m),
            ("max_start_slope_rad", self.max_start_slope_rad),
        ];
        for (name, v) in finite {
            if !v.is_finite() || (name == "contact_tolerance_m" && v < 0.0) {
                return Err(format!(
                    "{name} is {v}; give a finite number (>= 0 for a tolerance)"
                ));
            }
        }
        if let Some(sag) = &self.sag {
            sag.check()?;
        }
        Ok(())
    }
}
