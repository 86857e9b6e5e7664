//! The cost of leg motion: a weighted sum of time and energy ("power" in §6.2.2), with the
//! user's ratio between them, and the speed limits that turn joint distances into time.
//!
//! The joints are independent (§6.2.2: a fair approximation at the leg's slow speeds): a move
//! of `(ds, de, dz)` takes as long as its slowest joint, and each joint spends its power for
//! as long as it moves at full speed. Lifting the leg costs more than lowering it.

use serde::{Deserialize, Serialize};
use tca_robot::{Joint, LegKinematics};

use crate::error::{PlanError, Result};

/// Joint speed limits: shoulder and elbow (rad/s) and the vertical axis (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSpeeds {
    /// Shoulder, radians per second.
    pub shoulder_rad_per_s: f64,
    /// Elbow, radians per second.
    pub elbow_rad_per_s: f64,
    /// Vertical axis, metres per second (3.6 cm/s on the testbed).
    pub vertical_m_per_s: f64,
}

impl JointSpeeds {
    /// The speed limits of the leg's joints.
    pub fn of(kin: &LegKinematics) -> Self {
        Self {
            shoulder_rad_per_s: kin.limits(Joint::Shoulder).max_speed,
            elbow_rad_per_s: kin.limits(Joint::Elbow).max_speed,
            vertical_m_per_s: kin.limits(Joint::Vertical).max_speed,
        }
    }

    /// Time for the horizontal joints to move `(ds, de)` together, seconds.
    pub fn horizontal_time_s(&self, ds_rad: f64, de_rad: f64) -> f64 {
        (ds_rad.abs() / self.shoulder_rad_per_s).max(de_rad.abs() / self.elbow_rad_per_s)
    }
}

/// Time and energy of some motion.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MotionCost {
    /// Duration, seconds (joints at full speed, no acceleration phases).
    pub time_s: f64,
    /// Energy, joules.
    pub energy_j: f64,
}

impl std::ops::Add for MotionCost {
    type Output = Self;
    fn add(self, rhs: Self) -> Self {
        Self {
            time_s: self.time_s + rhs.time_s,
            energy_j: self.energy_j + rhs.energy_j,
        }
    }
}

impl std::ops::AddAssign for MotionCost {
    fn add_assign(&mut self, rhs: Self) {
        *self = *self + rhs;
    }
}

/// The cost model of the search: power drawn by each joint at full speed and the weight of
/// energy against time. `cost = time_s + energy_weight_s_per_kj * energy_j / 1000`, plus
/// `turn_penalty_s` per change of direction in the search (§6.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CostModel {
    /// The user's ratio: seconds of cost one kilojoule is worth (0 = time only).
    pub energy_weight_s_per_kj: f64,
    /// Power of the shoulder at full speed, watts.
    pub shoulder_power_w: f64,
    /// Power of the elbow at full speed, watts.
    pub elbow_power_w: f64,
    /// Power of the vertical axis lifting the leg at full speed, watts.
    pub lift_power_w: f64,
    /// Power of the vertical axis lowering the leg at full speed, watts.
    pub lower_power_w: f64,
    /// Time added for each turn of the C-space path, seconds (0.5 s in §6.3).
    pub turn_penalty_s: f64,
}

impl Default for CostModel {
    /// A rover on about 500 W (§6.1): the vertical axis lifting the heavy leg draws most.
    fn default() -> Self {
        Self {
            energy_weight_s_per_kj: 1.0,
            shoulder_power_w: 150.0,
            elbow_power_w: 100.0,
            lift_power_w: 300.0,
            lower_power_w: 50.0,
            turn_penalty_s: 0.5,
        }
    }
}

impl CostModel {
    /// Checks every field is finite and not negative.
    pub fn validate(&self) -> Result<()> {
        let fields = [
            ("cost.energy_weight_s_per_kj", self.energy_weight_s_per_kj),
            ("cost.shoulder_power_w", self.shoulder_power_w),
            ("cost.elbow_power_w", self.elbow_power_w),
            ("cost.lift_power_w", self.lift_power_w),
            ("cost.lower_power_w", self.lower_power_w),
            ("cost.turn_penalty_s", self.turn_penalty_s),
        ];
        for (key, value) in fields {
            if !(value.is_finite() && value >= 0.0) {
                return Err(PlanError::BadParams {
                    key,
                    value,
                    reason: "must be a finite number of at least 0",
                });
            }
        }
        Ok(())
    }

    /// The scalar cost of some motion (without turn penalties).
    pub fn cost(&self, m: MotionCost) -> f64 {
        m.time_s + self.energy_weight_s_per_kj * m.energy_j * 1e-3
    }

    /// Energy of the horizontal joints moving `(ds, de)`, joules.
    pub fn horizontal_energy_j(&self, speeds: &JointSpeeds, ds_rad: f64, de_rad: f64) -> f64 {
        self.shoulder_power_w * ds_rad.abs() / speeds.shoulder_rad_per_s
            + self.elbow_power_w * de_rad.abs() / speeds.elbow_rad_per_s
    }

    /// Energy of the vertical axis moving the foot up (`dz > 0`) or down, joules.
    pub fn vertical_energy_j(&self, speeds: &JointSpeeds, dz_m: f64) -> f64 {
        let power = if dz_m > 0.0 {
            self.lift_power_w
        } else {
            self.lower_power_w
        };
        power * dz_m.abs() / speeds.vertical_m_per_s
    }

    /// Time and energy of one straight joint-space move of `(ds, de)` with the foot rising by
    /// `dz` (all joints arriving together).
    pub fn segment(&self, speeds: &JointSpeeds, ds_rad: f64, de_rad: f64, dz_m: f64) -> MotionCost {
        MotionCost {
            time_s: speeds
                .horizontal_time_s(ds_rad, de_rad)
                .max(dz_m.abs() / speeds.vertical_m_per_s),
            energy_j: self.horizontal_energy_j(speeds, ds_rad, de_rad)
                + self.vertical_energy_j(speeds, dz_m),
        }
    }

    /// Time and energy of a path through `(shoulder_rad, elbow_rad, foot_z_m)` points.
    pub fn path(&self, speeds: &JointSpeeds, points: &[[f64; 3]]) -> MotionCost {
        points
            .windows(2)
            .map(|w| {
                self.segment(
                    speeds,
                    w[1][0] - w[0][0],
                    w[1][1] - w[0][1],
                    w[1][2] - w[0][2],
                )
            })
            .fold(MotionCost::default(), |a, b| a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_robot::LegParams;

    fn speeds() -> JointSpeeds {
        JointSpeeds::of(&LegKinematics::new(&LegParams::default()))
    }

    #[test]
    fn the_slowest_joint_sets_the_time() {
        let s = speeds();
        let m = CostModel::default();
        // 0.5 rad of shoulder at 0.1 rad/s = 5 s; 0.36 m of lift at 3.6 cm/s = 10 s.
        let c = m.segment(&s, 0.5, 0.1, 0.36);
        assert!((c.time_s - 10.0).abs() < 1e-9);
        let expected = 150.0 * 5.0 + 100.0 * (0.1 / 0.15) + 300.0 * 10.0;
        assert!((c.energy_j - expected).abs() < 1e-9);
        // Lowering is cheaper than lifting.
        assert!(m.segment(&s, 0.0, 0.0, -0.36).energy_j < c.energy_j);
    }

    #[test]
    fn cost_weighs_energy_by_the_ratio() {
        let mut m = CostModel::default();
        let motion = MotionCost {
            time_s: 10.0,
            energy_j: 2000.0,
        };
        assert!((m.cost(motion) - 12.0).abs() < 1e-12);
        m.energy_weight_s_per_kj = 0.0;
        assert!((m.cost(motion) - 10.0).abs() < 1e-12);
    }

    #[test]
    fn negative_weights_are_refused_with_their_key() {
        let m = CostModel {
            turn_penalty_s: -1.0,
            ..CostModel::default()
        };
        let err = m.validate().unwrap_err();
        assert!(err.to_string().contains("cost.turn_penalty_s"), "{err}");
    }
}
