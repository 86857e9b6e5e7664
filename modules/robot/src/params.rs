//! The testbed's parameters, read from one TOML file (`params/leg.toml`).
//!
//! [`LegParams::default`] is the file shipped with the crate (embedded at build time);
//! [`LegParams::load`] reads another one. Every key is required and unknown keys are
//! refused, so a typo cannot silently fall back to a default. Units are in the key names.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// The parameter file shipped with the crate.
pub const DEFAULT_PARAMS_TOML: &str = include_str!("../params/leg.toml");

/// Why a parameter file was refused.
#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    /// The file could not be read.
    #[error("cannot read parameter file {path}: {source}")]
    Read {
        /// The file asked for.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The TOML text is malformed, a key is missing or unknown, or a value has the wrong type.
    #[error("parameter file is not valid: {message}")]
    Parse {
        /// The TOML parser's message: it names the key and the line.
        message: String,
    },
    /// A value parsed but is not usable.
    #[error("parameter `{key}` = {value} is not valid: {reason}")]
    Invalid {
        /// Dotted path of the key, e.g. `leg.vertical.min_m`.
        key: &'static str,
        /// The value found.
        value: f64,
        /// What is wrong and what is expected.
        reason: &'static str,
    },
}

/// Result of loading parameters.
pub type Result<T, E = ParamsError> = std::result::Result<T, E>;

/// All parameters of the mechanism, the carriage, the rails, the scanner mount and the
/// simulator. See `params/leg.toml` for the meaning of every key and the frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LegParams {
    /// Where the carriage holds the leg.
    pub carriage: CarriageParams,
    /// Travel and friction of the rails.
    pub rails: RailParams,
    /// Link lengths, foot and joint axes.
    pub leg: MechanismParams,
    /// Compliance deflection model (§4.3).
    pub compliance: ComplianceParams,
    /// Foot/ground contact.
    pub contact: ContactParams,
    /// Body move procedure (§4.2).
    pub body_move: BodyMoveParams,
    /// Scanner pose on the carriage.
    pub scanner: ScannerMount,
    /// Simulator tolerances.
    pub simulation: SimulationParams,
}

/// Fixed placement of the carriage frame in the world.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CarriageParams {
    /// World X of the leg's central column, metres.
    pub x_m: f64,
    /// World Z of the horizontal links' plane (the carriage frame origin), metres.
    pub link_plane_height_m: f64,
}

/// The rails the carriage rolls on (world Y).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RailParams {
    /// Smallest carriage Y, metres.
    pub y_min_m: f64,
    /// Largest carriage Y, metres.
    pub y_max_m: f64,
    /// Rolling friction the foot must overcome during a body move, newtons.
    pub friction_n: f64,
    /// Breakaway friction: the pull that starts a standing carriage rolling (at least
    /// `friction_n`), newtons.
    pub breakaway_friction_n: f64,
}

/// Geometry of the leg and its three joint axes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MechanismParams {
    /// Shoulder axis to elbow axis, metres.
    pub upper_link_m: f64,
    /// Elbow axis to the vertical member's axis, metres.
    pub lower_link_m: f64,
    /// Radius of the foot disc, metres.
    pub foot_radius_m: f64,
    /// Radius of the vertical member, metres (not more than the foot's).
    pub column_radius_m: f64,
    /// Height of the force/torque sensor above the sole, metres.
    pub force_sensor_above_sole_m: f64,
    /// Shoulder axis.
    pub shoulder: RotaryAxisParams,
    /// Elbow axis.
    pub elbow: RotaryAxisParams,
    /// Vertical (prismatic) axis.
    pub vertical: PrismaticAxisParams,
}

/// Limits of a rotary joint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryAxisParams {
    /// Lower soft limit, radians.
    pub min_rad: f64,
    /// Upper soft limit, radians.
    pub max_rad: f64,
    /// Where the lower limit switch trips, radians (below `min_rad`).
    pub limit_switch_min_rad: f64,
    /// Where the upper limit switch trips, radians (above `max_rad`).
    pub limit_switch_max_rad: f64,
    /// Speed limit, radians per second.
    pub max_speed_rad_per_s: f64,
    /// Acceleration limit, radians per second squared.
    pub max_accel_rad_per_s2: f64,
}

/// Limits of the prismatic vertical axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrismaticAxisParams {
    /// Shortest extension, metres.
    pub min_m: f64,
    /// Longest extension, metres.
    pub max_m: f64,
    /// Where the lower limit switch trips, metres (below `min_m`).
    pub limit_switch_min_m: f64,
    /// Where the upper limit switch trips, metres (above `max_m`).
    pub limit_switch_max_m: f64,
    /// Speed limit, metres per second (3.6 cm/s on the testbed).
    pub max_speed_m_per_s: f64,
    /// Acceleration limit, metres per second squared.
    pub max_accel_m_per_s2: f64,
}

/// Coefficients of the compliance deflection model (see
/// [`LegKinematics::deflection`](crate::LegKinematics::deflection)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComplianceParams {
    /// Downward sag per metre of horizontal reach.
    pub sag_m_per_m_reach: f64,
    /// Rail torsion, radians per metre of the foot's carriage-X offset.
    pub torsion_rad_per_m_offset: f64,
    /// Horizontal deflection per newton of horizontal load at full extension.
    pub lateral_m_per_n: f64,
    /// Vertical deflection per newton of vertical load at full extension.
    pub vertical_m_per_n: f64,
    /// The sag the Controller's and planners' calibrated kinematics compensate
    /// ([`LegKinematics::compensated`](crate::LegKinematics::compensated)).
    pub model_sag_m_per_m_reach: f64,
    /// The rail torsion the calibrated kinematics compensate (fitted to measurements: a
    /// little short of the real torsion, so compensated leg moves are a few centimetres off).
    pub model_torsion_rad_per_m_offset: f64,
}

/// Foot/ground contact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactParams {
    /// Stiffness of leg plus ground, newtons per metre of compression.
    pub stiffness_n_per_m: f64,
    /// Transition force set point at start-up, newtons.
    pub default_transition_force_n: f64,
    /// Foot/ground friction coefficient.
    pub friction_coefficient: f64,
}

/// The body move procedure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyMoveParams {
    /// Force pressed into the ground first (800 lb), newtons.
    pub compress_force_n: f64,
    /// Force kept while propelling (500 lb), newtons.
    pub traction_force_n: f64,
    /// Gain of the linear velocity law, metres per second per metre of error.
    pub gain_per_s: f64,
    /// Clip of the carriage speed, metres per second.
    pub max_speed_m_per_s: f64,
    /// Control loop rate, hertz.
    pub control_rate_hz: f64,
    /// The move ends when the carriage is this close to its target, metres.
    pub position_tolerance_m: f64,
    /// Full-extension margin: the elbow is kept at least this far from straight, radians.
    pub min_abs_elbow_rad: f64,
    /// Force drop-off threshold as a fraction of the traction force.
    pub force_drop_fraction: f64,
    /// Carriage lag that counts as a slip, metres.
    pub slip_detect_m: f64,
}

/// Pose of the laser scanner on the carriage.
///
/// Scanner frame: +X along the boresight, +Y to the left, +Z up. With zero angles the
/// boresight is carriage +Y (forward).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScannerMount {
    /// Scanner origin in the carriage frame, metres.
    pub position_m: [f64; 3],
    /// Turn of the boresight to the left of forward, radians.
    pub yaw_rad: f64,
    /// Tilt of the boresight below the horizontal, radians.
    pub pitch_down_rad: f64,
    /// Roll about the boresight, radians.
    pub roll_rad: f64,
}

/// Tolerances of the simulator.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationParams {
    /// Largest foot travel between terrain checks, metres.
    pub collision_step_m: f64,
    /// Period of path samples in move reports, seconds.
    pub report_period_s: f64,
    /// How far a foot resting on the ground may slide before it counts as dragged, metres.
    pub drag_tolerance_m: f64,
    /// Positioning error of a rotary joint that is a servo error, radians.
    pub servo_error_rad: f64,
    /// Positioning error of the vertical axis that is a servo error, metres.
    pub servo_error_m: f64,
}

impl Default for LegParams {
    /// The parameters shipped in `params/leg.toml`.
    fn default() -> Self {
        match Self::from_toml_str(DEFAULT_PARAMS_TOML) {
            Ok(params) => params,
            // The shipped file is checked by a unit test; reaching this is a build defect.
            Err(err) => unreachable!("shipped params/leg.toml is invalid: {err}"),
        }
    }
}

impl LegParams {
    /// Parses and validates parameters from TOML text.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let params: Self = toml::from_str(text).map_err(|err| ParamsError::Parse {
            message: err.to_string().trim_end().to_owned(),
        })?;
        params.validate()?;
        Ok(params)
    }

    /// Reads, parses and validates a parameter file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ParamsError::Read {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_toml_str(&text)
    }

    /// Writes the parameters as TOML text (without the shipped file's comments).
    pub fn to_toml_string(&self) -> String {
        // Serializing plain structs of numbers cannot fail.
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Checks that every value is usable; the error names the first bad key.
    pub fn validate(&self) -> Result<()> {
        let l = &self.leg;
        let finite_checks: [(&'static str, f64); 10] = [
            ("carriage.x_m", self.carriage.x_m),
            (
                "carriage.link_plane_height_m",
                self.carriage.link_plane_height_m,
            ),
            ("rails.y_min_m", self.rails.y_min_m),
            ("rails.y_max_m", self.rails.y_max_m),
            ("scanner.position_m", self.scanner.position_m[0]),
            ("scanner.position_m", self.scanner.position_m[1]),
            ("scanner.position_m", self.scanner.position_m[2]),
            ("scanner.yaw_rad", self.scanner.yaw_rad),
            ("scanner.pitch_down_rad", self.scanner.pitch_down_rad),
            ("scanner.roll_rad", self.scanner.roll_rad),
        ];
        for (key, value) in finite_checks {
            finite(key, value)?;
        }
        let positive_checks: [(&'static str, f64); 27] = [
            ("leg.upper_link_m", l.upper_link_m),
            ("leg.lower_link_m", l.lower_link_m),
            ("leg.foot_radius_m", l.foot_radius_m),
            ("leg.column_radius_m", l.column_radius_m),
            ("leg.force_sensor_above_sole_m", l.force_sensor_above_sole_m),
            (
                "leg.shoulder.max_speed_rad_per_s",
                l.shoulder.max_speed_rad_per_s,
            ),
            (
                "leg.shoulder.max_accel_rad_per_s2",
                l.shoulder.max_accel_rad_per_s2,
            ),
            ("leg.elbow.max_speed_rad_per_s", l.elbow.max_speed_rad_per_s),
            (
                "leg.elbow.max_accel_rad_per_s2",
                l.elbow.max_accel_rad_per_s2,
            ),
            (
                "leg.vertical.max_speed_m_per_s",
                l.vertical.max_speed_m_per_s,
            ),
            (
                "leg.vertical.max_accel_m_per_s2",
                l.vertical.max_accel_m_per_s2,
            ),
            ("leg.vertical.min_m", l.vertical.min_m),
            ("contact.stiffness_n_per_m", self.contact.stiffness_n_per_m),
            (
                "contact.default_transition_force_n",
                self.contact.default_transition_force_n,
            ),
            (
                "contact.friction_coefficient",
                self.contact.friction_coefficient,
            ),
            (
                "body_move.compress_force_n",
                self.body_move.compress_force_n,
            ),
            (
                "body_move.traction_force_n",
                self.body_move.traction_force_n,
            ),
            ("body_move.gain_per_s", self.body_move.gain_per_s),
            (
                "body_move.max_speed_m_per_s",
                self.body_move.max_speed_m_per_s,
            ),
            ("body_move.control_rate_hz", self.body_move.control_rate_hz),
            (
                "body_move.position_tolerance_m",
                self.body_move.position_tolerance_m,
            ),
            ("body_move.slip_detect_m", self.body_move.slip_detect_m),
            (
                "simulation.collision_step_m",
                self.simulation.collision_step_m,
            ),
            (
                "simulation.report_period_s",
                self.simulation.report_period_s,
            ),
            (
                "simulation.drag_tolerance_m",
                self.simulation.drag_tolerance_m,
            ),
            (
                "simulation.servo_error_rad",
                self.simulation.servo_error_rad,
            ),
            ("simulation.servo_error_m", self.simulation.servo_error_m),
        ];
        for (key, value) in positive_checks {
            positive(key, value)?;
        }
        let non_negative_checks: [(&'static str, f64); 10] = [
            ("rails.friction_n", self.rails.friction_n),
            (
                "rails.breakaway_friction_n",
                self.rails.breakaway_friction_n,
            ),
            (
                "compliance.sag_m_per_m_reach",
                self.compliance.sag_m_per_m_reach,
            ),
            (
                "compliance.torsion_rad_per_m_offset",
                self.compliance.torsion_rad_per_m_offset,
            ),
            (
                "compliance.lateral_m_per_n",
                self.compliance.lateral_m_per_n,
            ),
            (
                "compliance.vertical_m_per_n",
                self.compliance.vertical_m_per_n,
            ),
            (
                "compliance.model_sag_m_per_m_reach",
                self.compliance.model_sag_m_per_m_reach,
            ),
            (
                "compliance.model_torsion_rad_per_m_offset",
                self.compliance.model_torsion_rad_per_m_offset,
            ),
            (
                "body_move.min_abs_elbow_rad",
                self.body_move.min_abs_elbow_rad,
            ),
            (
                "body_move.force_drop_fraction",
                self.body_move.force_drop_fraction,
            ),
        ];
        for (key, value) in non_negative_checks {
            non_negative(key, value)?;
        }
        rotary_axis("leg.shoulder", &l.shoulder)?;
        rotary_axis("leg.elbow", &l.elbow)?;
        if self.rails.breakaway_friction_n < self.rails.friction_n {
            return Err(invalid(
                "rails.breakaway_friction_n",
                self.rails.breakaway_friction_n,
                "the breakaway friction of the carriage must be at least its rolling friction (rails.friction_n)",
            ));
        }
        if l.shoulder.min_rad < -std::f64::consts::PI || l.shoulder.max_rad > std::f64::consts::PI {
            return Err(invalid(
                "leg.shoulder.max_rad",
                l.shoulder.max_rad,
                "the shoulder range must lie within [-pi, pi] so inverse kinematics is unique",
            ));
        }
        let v = &l.vertical;
        if v.max_m <= v.min_m {
            return Err(invalid(
                "leg.vertical.max_m",
                v.max_m,
                "must be greater than leg.vertical.min_m",
            ));
        }
        if v.limit_switch_min_m > v.min_m {
            return Err(invalid(
                "leg.vertical.limit_switch_min_m",
                v.limit_switch_min_m,
                "the limit switch must sit at or below leg.vertical.min_m",
            ));
        }
        if v.limit_switch_max_m < v.max_m {
            return Err(invalid(
                "leg.vertical.limit_switch_max_m",
                v.limit_switch_max_m,
                "the limit switch must sit at or above leg.vertical.max_m",
            ));
        }
        if l.column_radius_m > l.foot_radius_m {
            return Err(invalid(
                "leg.column_radius_m",
                l.column_radius_m,
                "the vertical member must not be wider than the foot (the foot check covers it)",
            ));
        }
        if self.rails.y_max_m <= self.rails.y_min_m {
            return Err(invalid(
                "rails.y_max_m",
                self.rails.y_max_m,
                "must be greater than rails.y_min_m",
            ));
        }
        if self.body_move.traction_force_n > self.body_move.compress_force_n {
            return Err(invalid(
                "body_move.traction_force_n",
                self.body_move.traction_force_n,
                "must not exceed body_move.compress_force_n",
            ));
        }
        if self.body_move.force_drop_fraction >= 1.0 {
            return Err(invalid(
                "body_move.force_drop_fraction",
                self.body_move.force_drop_fraction,
                "must be below 1",
            ));
        }
        Ok(())
    }
}

fn invalid(key: &'static str, value: f64, reason: &'static str) -> ParamsError {
    ParamsError::Invalid { key, value, reason }
}

fn finite(key: &'static str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, value, "must be a finite number"))
    }
}

fn positive(key: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            key,
            value,
            "must be a finite number greater than zero",
        ))
    }
}

fn non_negative(key: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(invalid(key, value, "must be a finite number, zero or more"))
    }
}

fn rotary_axis(prefix: &'static str, axis: &RotaryAxisParams) -> Result<()> {
    // The key names are built from fixed prefixes so they can stay `&'static str`.
    let keys: [&'static str; 4] = match prefix {
        "leg.shoulder" => [
            "leg.shoulder.min_rad",
            "leg.shoulder.max_rad",
            "leg.shoulder.limit_switch_min_rad",
            "leg.shoulder.limit_switch_max_rad",
        ],
        _ => [
            "leg.elbow.min_rad",
            "leg.elbow.max_rad",
            "leg.elbow.limit_switch_min_rad",
            "leg.elbow.limit_switch_max_rad",
        ],
    };
    for (key, value) in keys.iter().zip([
        axis.min_rad,
        axis.max_rad,
        axis.limit_switch_min_rad,
        axis.limit_switch_max_rad,
    ]) {
        finite(key, value)?;
    }
    if axis.max_rad <= axis.min_rad {
        return Err(invalid(
            keys[1],
            axis.max_rad,
            "must be greater than the axis' min_rad",
        ));
    }
    if axis.limit_switch_min_rad > axis.min_rad {
        return Err(invalid(
            keys[2],
            axis.limit_switch_min_rad,
            "the limit switch must sit at or below min_rad",
        ));
    }
    if axis.limit_switch_max_rad < axis.max_rad {
        return Err(invalid(
            keys[3],
            axis.limit_switch_max_rad,
            "the limit switch must sit at or above max_rad",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_file_is_valid_and_has_the_papers_figures() {
        let p = LegParams::from_toml_str(DEFAULT_PARAMS_TOML).expect("shipped file parses");
        assert!((p.leg.vertical.max_speed_m_per_s - 0.036).abs() < 1e-12);
        assert!((p.body_move.compress_force_n - 3558.6).abs() < 1e-9);
        assert!((p.body_move.traction_force_n - 2224.1).abs() < 1e-9);
        assert!((p.leg.upper_link_m + p.leg.lower_link_m - 2.5).abs() < 1e-9);
        // Foot reaches about 1 m above and 0.5 m below the sand.
        let top = p.carriage.link_plane_height_m - p.leg.vertical.min_m;
        let bottom = p.carriage.link_plane_height_m - p.leg.vertical.max_m;
        assert!((top - 1.0).abs() < 1e-9 && (bottom + 0.5).abs() < 1e-9);
    }

    #[test]
    fn round_trips_through_toml() {
        let p = LegParams::default();
        let again = LegParams::from_toml_str(&p.to_toml_string()).expect("round trip");
        assert_eq!(p, again);
    }

    #[test]
    fn unknown_key_is_named() {
        let text = DEFAULT_PARAMS_TOML.replace("y_max_m = 10.5", "y_max_m = 10.5\nfrictoin = 1.0");
        let err = LegParams::from_toml_str(&text).unwrap_err().to_string();
        assert!(err.contains("frictoin"), "{err}");
    }

    #[test]
    fn a_breakaway_friction_below_the_rolling_one_is_refused() {
        let text = DEFAULT_PARAMS_TOML.replace(
            "breakaway_friction_n = 1150.0",
            "breakaway_friction_n = 500.0",
        );
        let err = LegParams::from_toml_str(&text).unwrap_err().to_string();
        assert!(
            err.contains("breakaway_friction_n") && err.contains("rolling"),
            "{err}"
        );
    }

    #[test]
    fn missing_key_is_named() {
        let text = DEFAULT_PARAMS_TOML.replace("lower_link_m = 1.2\n", "");
        let err = LegParams::from_toml_str(&text).unwrap_err().to_string();
        assert!(err.contains("lower_link_m"), "{err}");
    }

    #[test]
    fn wrong_type_is_refused_with_its_line() {
        let text = DEFAULT_PARAMS_TOML.replace("x_m = 3.0", "x_m = \"three\"");
        let err = LegParams::from_toml_str(&text).unwrap_err().to_string();
        assert!(err.contains("line"), "{err}");
    }

    #[test]
    fn bad_value_is_refused_with_its_key() {
        let text =
            DEFAULT_PARAMS_TOML.replace("max_speed_m_per_s = 0.036", "max_speed_m_per_s = -0.036");
        match LegParams::from_toml_str(&text) {
            Err(ParamsError::Invalid { key, .. }) => {
                assert_eq!(key, "leg.vertical.max_speed_m_per_s")
            }
            other => panic!("expected an invalid key, got {other:?}"),
        }
        let text =
            DEFAULT_PARAMS_TOML.replace("limit_switch_max_m = 4.52", "limit_switch_max_m = 4.4");
        match LegParams::from_toml_str(&text) {
            Err(ParamsError::Invalid { key, .. }) => {
                assert_eq!(key, "leg.vertical.limit_switch_max_m")
            }
            other => panic!("expected an invalid key, got {other:?}"),
        }
    }

    #[test]
    fn load_reports_a_missing_file() {
        let err = LegParams::load("/nonexistent/leg.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("/nonexistent/leg.toml"), "{err}");
    }
}
