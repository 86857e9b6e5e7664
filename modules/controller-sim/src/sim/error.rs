//! Errors of the simulated Controller, classified as the walking system must treat them.

use nalgebra::Point3;
use tca_robot::{Joint, JointPosition, KinematicsError};

/// How the walking system must treat a failed command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FailureKind {
    /// The command was refused before anything moved (bad input); fix the command.
    Rejected,
    /// The move failed but the hardware is sound (collision, no contact, slip, extension
    /// limit): the planner can replan from where the leg is.
    MoveFailure,
    /// The hardware stopped itself (limit switch, force drop-off, servo error): the walk
    /// must halt.
    HardwareFault,
}

/// Why a command to the simulated Controller failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// `leg_move` with no way-points.
    #[error("legMove needs at least one way-point; the leg did not move")]
    EmptyWaypoints,
    /// A number in the command is NaN or infinite.
    #[error("{what} is not a finite number; the leg did not move")]
    NotFinite {
        /// What was not finite, e.g. `way-point 2` or `body move target`.
        what: String,
    },
    /// A way-point is outside the joint limits.
    #[error("way-point {index} is not reachable: {source}; the leg did not move")]
    WaypointOutOfLimits {
        /// 0-based index of the way-point.
        index: usize,
        /// Which joint and limits.
        source: KinematicsError,
    },
    /// A body move target beyond the rails.
    #[error(
        "body move target y = {target_y_m:.3} m is beyond the rails [{min_y_m:.3}, {max_y_m:.3}] m; \
         the carriage did not move"
    )]
    BeyondRails {
        /// Target asked for.
        target_y_m: f64,
        /// Rail start.
        min_y_m: f64,
        /// Rail end.
        max_y_m: f64,
    },
    /// A body move with the foot in the air.
    #[error(
        "body move needs the foot planted on the ground (place it with a transition legMove first); the carriage did not move"
    )]
    FootNotPlanted,
    /// A transition force outside the usable range.
    #[error(
        "transition force {newtons} N is not valid; give a force above 0 and at most {max_n} N"
    )]
    InvalidForce {
        /// Force asked for.
        newtons: f64,
        /// Largest allowed.
        max_n: f64,
    },
    /// The simulator's start state is impossible.
    #[error("cannot start the simulator: {reason}")]
    InvalidStart {
        /// What is wrong.
        reason: String,
    },
    /// The leg or foot struck the terrain; the leg stopped at the contact.
    #[error(
        "the foot {how} the terrain at ({x:.3}, {y:.3}, {z:.3}) m (terrain top {terrain_height_m:.3} m); \
         the leg stopped there",
        how = if *dragged { "dragged along" } else { "struck" },
        x = foot_world.x, y = foot_world.y, z = foot_world.z
    )]
    Collision {
        /// Foot sole centre at the contact, world frame.
        foot_world: Point3<f64>,
        /// Highest terrain under the foot there.
        terrain_height_m: f64,
        /// Joint position where the leg stopped.
        joints: JointPosition,
        /// Whether the foot was dragged along the ground rather than striking it.
        dragged: bool,
    },
    /// Transition mode reached the last way-point before the set force.
    #[error(
        "transition move reached its last way-point with {force_n:.0} N of the {set_point_n:.0} N set point \
         (no ground contact where expected)"
    )]
    NoContact {
        /// Force reached (0 if the foot never touched).
        force_n: f64,
        /// The transition force set point.
        set_point_n: f64,
        /// Joint position where the leg stopped.
        joints: JointPosition,
    },
    /// The foot slipped during a body move.
    #[error(
        "the foot slipped {slid_m:.3} m during the body move; the carriage stopped at y = {carriage_y_m:.3} m"
    )]
    Slip {
        /// How far the foot slid.
        slid_m: f64,
        /// Where the carriage stopped.
        carriage_y_m: f64,
    },
    /// A body move would take a joint past its limits or the leg to full extension.
    #[error(
        "body move stopped at y = {reached_y_m:.3} m of {target_y_m:.3} m: the {joint} reached its limit \
         (leg at full extension); plant the foot further ahead and move again"
    )]
    ExtensionLimit {
        /// Where the carriage stopped.
        reached_y_m: f64,
        /// The target.
        target_y_m: f64,
        /// The joint at its limit.
        joint: Joint,
    },
    /// A limit switch tripped: the Controller shut the leg down.
    #[error("the {joint} limit switch tripped at {position:.4} {unit}; the leg is shut down", unit = joint.unit())]
    LimitSwitch {
        /// The joint.
        joint: Joint,
        /// Its position.
        position: f64,
    },
    /// The foot force dropped off during a body move (the foot broke free): emergency stop.
    #[error(
        "the foot force dropped from {force_before_n:.0} N to {force_after_n:.0} N during the body move \
         (foot broke free); emergency stop at y = {carriage_y_m:.3} m"
    )]
    ForceDropOff {
        /// Where the carriage stopped.
        carriage_y_m: f64,
        /// Force before the drop.
        force_before_n: f64,
        /// Force after the drop.
        force_after_n: f64,
    },
    /// A joint ended too far from its command: the servo shut down.
    #[error("servo error on the {joint}: {error:.4} {unit} from its command; the leg is shut down", unit = joint.unit())]
    ServoError {
        /// The joint.
        joint: Joint,
        /// Position error.
        error: f64,
    },
}

impl SimError {
    /// How the walking system must treat this error.
    pub fn kind(&self) -> FailureKind {
        match self {
            SimError::EmptyWaypoints
            | SimError::NotFinite { .. }
            | SimError::WaypointOutOfLimits { .. }
            | SimError::BeyondRails { .. }
            | SimError::FootNotPlanted
            | SimError::InvalidForce { .. }
            | SimError::InvalidStart { .. } => FailureKind::Rejected,
            SimError::Collision { .. }
            | SimError::NoContact { .. }
            | SimError::Slip { .. }
            | SimError::ExtensionLimit { .. } => FailureKind::MoveFailure,
            SimError::LimitSwitch { .. }
            | SimError::ForceDropOff { .. }
            | SimError::ServoError { .. } => FailureKind::HardwareFault,
        }
    }

    /// Whether the walk must halt.
    pub fn is_hardware_fault(&self) -> bool {
        self.kind() == FailureKind::HardwareFault
    }

    /// Whether the planner can replan from where the leg is.
    pub fn is_move_failure(&self) -> bool {
        self.kind() == FailureKind::MoveFailure
    }

    /// Whether the command was refused with nothing moved.
    pub fn is_rejected(&self) -> bool {
        self.kind() == FailureKind::Rejected
    }
}

/// Result of a simulator command.
pub type Result<T, E = SimError> = std::result::Result<T, E>;
