//! Why a step could not be planned.

/// A gait planning failure. Every variant says what was wrong and what to do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GaitError {
    /// The parameter file is not valid TOML or does not match the expected keys.
    #[error("gait parameters: {0}")]
    Toml(String),
    /// The parameter file could not be read.
    #[error("cannot read gait parameters from {path}: {reason}; check the path")]
    Io {
        /// The path.
        path: String,
        /// The I/O error.
        reason: String,
    },
    /// A parameter is out of range.
    #[error("gait parameter `{key}` = {value} is not valid: {reason}")]
    Param {
        /// The TOML key (`table.key`).
        key: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A map could not be built or is malformed.
    #[error("terrain map: {0}; send a map whose cell count is nx * ny with a positive resolution")]
    BadMap(String),
    /// The leg's parameters are not valid.
    #[error("the leg parameters are not valid: {0}; fix params/leg.toml")]
    LegParams(String),
    /// An input is NaN or infinite.
    #[error("{what} is not a finite number; give finite positions")]
    NotFinite {
        /// Which input.
        what: &'static str,
    },
    /// The carriage is already at the goal.
    #[error(
        "the carriage at y = {body_y_m:.3} m is already at the goal {goal_y_m:.3} m; no step \
         is needed"
    )]
    AtGoal {
        /// Carriage Y.
        body_y_m: f64,
        /// Goal Y.
        goal_y_m: f64,
    },
    /// Every cell was eliminated.
    #[error(
        "no acceptable footfall within reach: of {cells} cells, {unknown} are on unknown \
         terrain, {out_of_reach} are out of the leg's reach, {elevation} are too high or too \
         low, {not_clear} lack a clear 70 cm region and {no_advance} allow no body advance; \
         acquire a fresh terrain map, or walk another way"
    )]
    NoFootfall {
        /// Cells in the planning grid.
        cells: usize,
        /// Eliminated as unknown.
        unknown: usize,
        /// Eliminated as unreachable (kinematics or the Leg Recovery Planner).
        out_of_reach: usize,
        /// Eliminated by the terrain elevation map.
        elevation: usize,
        /// Eliminated by the clear-region check.
        not_clear: usize,
        /// Eliminated for allowing no advance toward the goal.
        no_advance: usize,
    },
}

/// Result of gait planning.
pub type Result<T, E = GaitError> = std::result::Result<T, E>;
