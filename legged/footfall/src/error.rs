//! What can go wrong, said so that the operator knows what to change.

/// Why a map or a plan could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FootfallError {
    /// The robot's state or terrain cannot be used.
    #[error("{0}")]
    Scene(String),
    /// No leg of that name.
    #[error("the robot has no leg `{leg}`; its legs are {legs}")]
    UnknownLeg {
        /// The name given.
        leg: String,
        /// The legs it has, comma-separated.
        legs: String,
    },
    /// The leg chosen is not standing, so it cannot be stepped from where it is.
    #[error(
        "leg `{leg}` is not standing on the ground; FootFall plans a step of a standing leg: \
         put it down first"
    )]
    NotStanding {
        /// The leg.
        leg: String,
    },
    /// A parameter makes no sense.
    #[error("{0}")]
    Params(String),
    /// The margin table could not be read.
    #[error("margin table: {0}")]
    Margins(String),
    /// The target cannot be stepped to, with the reason (the map's colour rules).
    #[error("cannot step leg `{leg}` to ({x:.2}, {y:.2}): {reason}")]
    BadTarget {
        /// The leg.
        leg: String,
        /// Target east, metres.
        x: f64,
        /// Target north, metres.
        y: f64,
        /// Why (unreachable, unstable, rough ground, the way-point above it unreachable...).
        reason: String,
    },
    /// The start configuration already breaks a margin (the robot is too close to
    /// something), so no plan can keep the margins.
    #[error("leg `{leg}` starts in collision: {detail}; move it clear by hand first")]
    StartInCollision {
        /// The leg.
        leg: String,
        /// Which parts and how close.
        detail: String,
    },
    /// No planner found a path.
    #[error("no collision-free path for leg `{leg}`: {reason}")]
    NoPath {
        /// The leg.
        leg: String,
        /// What the planners tried.
        reason: String,
    },
    /// A plan file or plan does not fit the robot.
    #[error("plan: {0}")]
    Plan(String),
    /// A picture could not be written.
    #[error("picture: {0}")]
    Picture(String),
}

/// The crate's result.
pub type Result<T, E = FootfallError> = std::result::Result<T, E>;
