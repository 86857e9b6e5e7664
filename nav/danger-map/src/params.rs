//! Danger parameters, one set per robot.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::DangerError;

/// The parameters of the danger computation for one robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DangerParams {
    /// Diameter of the circle each cell is judged over: the robot's largest diameter, m.
    pub robot_diameter_m: f64,
    /// Critical slope, degrees (in the file; [`DangerParams::s_crit_rad`] gives radians).
    pub s_crit_deg: f64,
    /// Critical roughness, m.
    pub r_crit_m: f64,
    /// Critical step height, m.
    pub h_crit_m: f64,
    /// Weights of slope, roughness and step height; they sum to 1.
    pub alpha: [f64; 3],
    /// Number of step cells in the circle at which the step height counts in full.
    pub n_crit: usize,
    /// Side of the square window for temporary step heights, cells (odd).
    pub step_window_cells: usize,
    /// Smallest known fraction of the circle for which a danger is computed; below it the
    /// cell is unknown (`d = 1`).
    pub min_certainty: f64,
}

impl DangerParams {
    /// The paper's values (`s_crit` = 20°, `r_crit` = 30 mm, `h_crit` = 50 mm, α = 0.5, 0.25,
    /// 0.25, `n_crit` = 50, an 11 x 11 step window) for a robot of `robot_diameter_m`.
    pub fn paper(robot_diameter_m: f64) -> Self {
        Self {
            robot_diameter_m,
            s_crit_deg: 20.0,
            r_crit_m: 0.03,
            h_crit_m: 0.05,
            alpha: [0.5, 0.25, 0.25],
            n_crit: 50,
            step_window_cells: 11,
            min_certainty: 0.3,
        }
    }

    /// Critical slope, radians.
    pub fn s_crit_rad(&self) -> f64 {
        self.s_crit_deg.to_radians()
    }

    /// Parameters from TOML text; `origin` names it in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, DangerError> {
        let p: Self = toml::from_str(text).map_err(|e| DangerError::Parse {
            path: origin.to_string(),
            source: Box::new(e),
        })?;
        p.validate()?;
        Ok(p)
    }

    /// Parameters from a TOML file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, DangerError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| DangerError::Read {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), DangerError> {
        let positive = |name, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(DangerError::BadParam {
                    name,
                    value,
                    expected: "a finite value greater than 0",
                })
            }
        };
        positive("robot_diameter_m", self.robot_diameter_m)?;
        positive("r_crit_m", self.r_crit_m)?;
        positive("h_crit_m", self.h_crit_m)?;
        if !(self.s_crit_deg > 0.0 && self.s_crit_deg < 90.0) {
            return Err(DangerError::BadParam {
                name: "s_crit_deg",
                value: self.s_crit_deg,
                expected: "an angle between 0 and 90 degrees",
            });
        }
        for (i, a) in self.alpha.iter().enumerate() {
            if !(a.is_finite() && *a >= 0.0) {
                return Err(DangerError::BadParam {
                    name: ["alpha[0]", "alpha[1]", "alpha[2]"][i],
                    value: *a,
                    expected: "a weight of at least 0",
                });
            }
        }
        let sum: f64 = self.alpha.iter().sum();
        if (sum - 1.0).abs() > 1e-6 {
            return Err(DangerError::BadParam {
                name: "alpha",
                value: sum,
                expected: "weights that sum to 1",
            });
        }
        if self.n_crit == 0 {
            return Err(DangerError::BadParam {
                name: "n_crit",
                value: 0.0,
                expected: "at least 1 cell",
            });
        }
        if self.step_window_cells < 3 || self.step_window_cells.is_multiple_of(2) {
            return Err(DangerError::BadParam {
                name: "step_window_cells",
                value: self.step_window_cells as f64,
                expected: "an odd number of cells, at least 3",
            });
        }
        if !(self.min_certainty > 0.0 && self.min_certainty <= 1.0) {
            return Err(DangerError::BadParam {
                name: "min_certainty",
                value: self.min_certainty,
                expected: "a fraction in (0, 1]",
            });
        }
        Ok(())
    }

    /// Radius of the robot's circle in cells of `resolution_m`.
    pub fn radius_cells(&self, resolution_m: f64) -> f64 {
        0.5 * self.robot_diameter_m / resolution_m
    }
}
