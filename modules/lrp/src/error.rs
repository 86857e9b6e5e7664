//! Why a leg trajectory or a reachability map could not be planned.

use tca_robot::KinematicsError;

/// A planning failure. Every variant says what was wrong and what to do about it; none is a
/// panic and none comes with a trajectory that could strike terrain.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The elevation map has no known cell at all.
    #[error(
        "the elevation map has no known cell; ask the LTM Manager for a map of the region \
         around the leg (after acquiring an image)"
    )]
    EmptyMap,
    /// The map handed over is malformed.
    #[error("the {what} map is malformed: {reason}; send a map whose cell count is nx * ny")]
    BadMap {
        /// Which map.
        what: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A region asked for is not a usable polygon or grid.
    #[error(
        "the region asked for is not valid: {reason}; give at least three finite corners and a resolution above 0"
    )]
    BadRegion {
        /// What is wrong with it.
        reason: String,
    },
    /// A planner parameter is out of range.
    #[error("planner parameter `{key}` = {value} is not valid: {reason}")]
    BadParams {
        /// The parameter's name (TOML key).
        key: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// The leg's parameters are not valid.
    #[error("the leg parameters are not valid: {0}; fix params/leg.toml")]
    BadLegParams(String),
    /// An input coordinate is NaN or infinite.
    #[error("{what} is not a finite number; give finite coordinates")]
    NotFinite {
        /// Which input.
        what: &'static str,
    },
    /// The start joints are outside the joint limits.
    #[error("the leg's start position is not valid: {0}; bring the leg within its joint limits")]
    StartOutOfLimits(KinematicsError),
    /// The map says the foot is inside the terrain where it starts.
    #[error(
        "the foot starts {depth_m:.3} m inside the mapped terrain at ({x_m:.2}, {y_m:.2}) m; \
         refresh the terrain map or lift the leg clear before planning"
    )]
    StartInCollision {
        /// World X of the foot.
        x_m: f64,
        /// World Y of the foot.
        y_m: f64,
        /// How far the terrain rises above the sole, metres.
        depth_m: f64,
    },
    /// Terrain around the start is higher than the foot can lift, so the leg cannot move.
    #[error(
        "the leg cannot move from where it stands: terrain around the foot needs it at \
         {required_m:.2} m but it lifts only to {max_m:.2} m; move the leg clear by hand \
         or map the surroundings (unknown terrain counts as an obstacle)"
    )]
    StartBlocked {
        /// Foot height needed to move, metres (world Z).
        required_m: f64,
        /// Highest foot height, metres.
        max_m: f64,
    },
    /// The footfall is outside the leg's reach at this carriage position.
    #[error(
        "footfall ({x_m:.2}, {y_m:.2}) m is out of the leg's reach from the carriage at \
         y = {body_y_m:.2} m ({source}); choose a footfall within the leg's reach"
    )]
    GoalOutOfReach {
        /// World X of the footfall.
        x_m: f64,
        /// World Y of the footfall.
        y_m: f64,
        /// Carriage Y.
        body_y_m: f64,
        /// Why inverse kinematics failed.
        source: KinematicsError,
    },
    /// The footfall lies (partly) on unknown or occluded terrain.
    #[error(
        "footfall ({x_m:.2}, {y_m:.2}) m lies on terrain the map does not know; choose a \
         footfall on seen terrain"
    )]
    UnknownGoal {
        /// World X of the footfall.
        x_m: f64,
        /// World Y of the footfall.
        y_m: f64,
    },
    /// The ground at the footfall is above or below what the foot reaches.
    #[error(
        "the ground at footfall ({x_m:.2}, {y_m:.2}) m is at {ground_m:.2} m, outside the \
         foot's reach [{min_m:.2}, {max_m:.2}] m; choose a footfall within that height range"
    )]
    GoalHeightOutOfReach {
        /// World X of the footfall.
        x_m: f64,
        /// World Y of the footfall.
        y_m: f64,
        /// Mapped ground height there, metres.
        ground_m: f64,
        /// Lowest usable ground, metres.
        min_m: f64,
        /// Highest usable ground, metres.
        max_m: f64,
    },
    /// Terrain next to the footfall is higher than the foot can lift over.
    #[error(
        "footfall ({x_m:.2}, {y_m:.2}) m is too close to terrain the leg cannot lift over \
         (needs {required_m:.2} m, lifts to {max_m:.2} m); choose a footfall farther from \
         tall obstacles"
    )]
    GoalBlocked {
        /// World X of the footfall.
        x_m: f64,
        /// World Y of the footfall.
        y_m: f64,
        /// Foot height needed to arrive there, metres.
        required_m: f64,
        /// Highest foot height, metres.
        max_m: f64,
    },
    /// No collision-free trajectory joins the start to the footfall.
    #[error(
        "no collision-free trajectory reaches footfall ({x_m:.2}, {y_m:.2}) m from the leg's \
         position: obstacles too tall to lift over surround it; choose another footfall"
    )]
    Unreachable {
        /// World X of the footfall.
        x_m: f64,
        /// World Y of the footfall.
        y_m: f64,
    },
    /// A defect: the extracted trajectory failed its own clearance check. Never sent.
    #[error("internal planner defect: {0}; the trajectory was discarded, please report this")]
    Internal(String),
}

/// Result of planning.
pub type Result<T, E = PlanError> = std::result::Result<T, E>;
