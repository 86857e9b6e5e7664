//! The Gait Planner's parameters: `params/gait.toml`, embedded as the default.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{GaitError, Result};

/// The shipped parameter file.
pub const DEFAULT_GAIT_TOML: &str = include_str!("../params/gait.toml");

/// All Gait Planner parameters (see `params/gait.toml` for the meaning of every key).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitParams {
    /// The cost maps' grid.
    pub grid: GridParams,
    /// Weights of the graded maps.
    pub weights: Weights,
    /// Footfall cost and the clear region.
    pub footfall: FootfallParams,
    /// The filtered footfall map.
    pub filtered_footfall: FilteredParams,
    /// Body advance.
    pub body_advance: AdvanceParams,
    /// Scanner visibility.
    pub scanner_visibility: VisibilityParams,
    /// Terrain elevation limits.
    pub elevation: ElevationParams,
}

/// `[grid]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridParams {
    /// Cell size, metres.
    pub resolution_m: f64,
}

/// `[weights]`: of the graded maps in the composite.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Weights {
    /// Footfall (flatness) map.
    pub footfall: f64,
    /// Filtered footfall map.
    pub filtered_footfall: f64,
    /// Body advance map.
    pub body_advance: f64,
    /// Scanner visibility map.
    pub scanner_visibility: f64,
}

/// `[footfall]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FootfallParams {
    /// Footfall statistic that costs 1, metres.
    pub worst_m: f64,
    /// Diameter of the clear region a footfall needs, metres.
    pub clear_diameter_m: f64,
    /// Largest footfall statistic inside the clear region, metres.
    pub clear_max_m: f64,
}

/// `[filtered_footfall]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilteredParams {
    /// Neighbourhood radius, metres.
    pub radius_m: f64,
    /// Distance scale of the inverse-distance weight, metres.
    pub distance_scale_m: f64,
}

/// `[body_advance]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdvanceParams {
    /// Largest body move per step, metres.
    pub threshold_m: f64,
}

/// `[scanner_visibility]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisibilityParams {
    /// Horizontal field of view, radians.
    pub azimuth_fov_rad: f64,
    /// Vertical field of view, radians.
    pub elevation_fov_rad: f64,
    /// Spacing of the sample points along the links, metres.
    pub link_sample_m: f64,
}

/// `[elevation]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElevationParams {
    /// Ground must be this far above the foot's lowest reach, metres.
    pub low_margin_m: f64,
    /// Ground must be this far below the foot's highest reach, metres.
    pub high_margin_m: f64,
}

impl Default for GaitParams {
    /// The parameters shipped in `params/gait.toml`.
    fn default() -> Self {
        match Self::from_toml_str(DEFAULT_GAIT_TOML) {
            Ok(p) => p,
            // The shipped file is checked by a unit test; reaching this is a build defect.
            Err(e) => unreachable!("shipped params/gait.toml is invalid: {e}"),
        }
    }
}

impl GaitParams {
    /// Parses and checks parameters; errors name the key.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let p: Self = toml::from_str(text).map_err(|e| GaitError::Toml(e.to_string()))?;
        p.validate()?;
        Ok(p)
    }

    /// Loads and checks a parameter file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| GaitError::Io {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::from_toml_str(&text)
    }

    /// The parameters as TOML.
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// Checks every value; the error names the key.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("grid.resolution_m", self.grid.resolution_m),
            ("footfall.worst_m", self.footfall.worst_m),
            ("footfall.clear_diameter_m", self.footfall.clear_diameter_m),
            (
                "filtered_footfall.distance_scale_m",
                self.filtered_footfall.distance_scale_m,
            ),
            ("body_advance.threshold_m", self.body_advance.threshold_m),
            (
                "scanner_visibility.azimuth_fov_rad",
                self.scanner_visibility.azimuth_fov_rad,
            ),
            (
                "scanner_visibility.elevation_fov_rad",
                self.scanner_visibility.elevation_fov_rad,
            ),
            (
                "scanner_visibility.link_sample_m",
                self.scanner_visibility.link_sample_m,
            ),
        ];
        for (key, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(GaitError::Param {
                    key,
                    value,
                    reason: "must be a finite number greater than 0",
                });
            }
        }
        let non_negative = [
            ("weights.footfall", self.weights.footfall),
            ("weights.filtered_footfall", self.weights.filtered_footfall),
            ("weights.body_advance", self.weights.body_advance),
            (
                "weights.scanner_visibility",
                self.weights.scanner_visibility,
            ),
            ("footfall.clear_max_m", self.footfall.clear_max_m),
            (
                "filtered_footfall.radius_m",
                self.filtered_footfall.radius_m,
            ),
            ("elevation.low_margin_m", self.elevation.low_margin_m),
            ("elevation.high_margin_m", self.elevation.high_margin_m),
        ];
        for (key, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(GaitError::Param {
                    key,
                    value,
                    reason: "must be a finite number of at least 0",
                });
            }
        }
        if self.grid.resolution_m < 0.02 || self.grid.resolution_m > 0.5 {
            return Err(GaitError::Param {
                key: "grid.resolution_m",
                value: self.grid.resolution_m,
                reason: "must be between 0.02 and 0.5 m",
            });
        }
        if self.filtered_footfall.radius_m > 3.0 {
            return Err(GaitError::Param {
                key: "filtered_footfall.radius_m",
                value: self.filtered_footfall.radius_m,
                reason: "must be at most 3 m",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_file_loads() {
        let p = GaitParams::from_toml_str(DEFAULT_GAIT_TOML).unwrap();
        assert_eq!(p.grid.resolution_m, 0.1);
        assert_eq!(p.body_advance.threshold_m, 1.5);
        assert_eq!(p.footfall.clear_diameter_m, 0.7);
        assert!(p.weights.footfall > p.weights.body_advance);
        // Round trip.
        assert_eq!(GaitParams::from_toml_str(&p.to_toml_string()).unwrap(), p);
    }

    #[test]
    fn errors_name_the_key() {
        let bad = DEFAULT_GAIT_TOML.replace("footfall = 4.0", "footfall = -4.0");
        let err = GaitParams::from_toml_str(&bad).unwrap_err();
        assert!(err.to_string().contains("weights.footfall"), "{err}");
        let bad = DEFAULT_GAIT_TOML.replace("threshold_m = 1.5", "threshold_m = 1.5\nspeed = 2");
        let err = GaitParams::from_toml_str(&bad).unwrap_err();
        assert!(err.to_string().contains("speed"), "{err}");
        let bad = DEFAULT_GAIT_TOML.replace("worst_m = 0.10\n", "");
        let err = GaitParams::from_toml_str(&bad).unwrap_err();
        assert!(err.to_string().contains("worst_m"), "{err}");
        let err = GaitParams::load("/nonexistent/gait.toml").unwrap_err();
        assert!(err.to_string().contains("/nonexistent/gait.toml"), "{err}");
    }
}
