//! What the simulator refuses: robots it cannot stand up, and moves it does not carry out.

use nalgebra::Point3;
use tca_legged_messages::{MoveFailed, MoveFailureKind, TipOver};

use crate::pose::world_point;

/// Why the robot could not be stood up at the start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A parameter or the start pose is not usable.
    #[error("simulator parameters: {0}")]
    Params(String),
    /// The robot's footprint at the start is not on the terrain.
    #[error(
        "the robot cannot stand at ({x_m:.3}, {y_m:.3}): {what} at ({px:.3}, {py:.3}) is off \
         the terrain, which covers x {min_x:.3}..{max_x:.3}, y {min_y:.3}..{max_y:.3}; choose \
         a start inside the map"
    )]
    OffMap {
        /// Start east.
        x_m: f64,
        /// Start north.
        y_m: f64,
        /// What is off the map (a foot or the body).
        what: String,
        /// Its east.
        px: f64,
        /// Its north.
        py: f64,
        /// The map's west edge.
        min_x: f64,
        /// The map's south edge.
        min_y: f64,
        /// The map's east edge.
        max_x: f64,
        /// The map's north edge.
        max_y: f64,
    },
    /// The ground under a foot is too steep to stand on.
    #[error(
        "the robot cannot stand: the ground under leg `{leg}` slopes {slope_deg:.1} degrees, \
         more than the {max_deg:.1} allowed; start on flatter ground"
    )]
    TooSteep {
        /// The leg.
        leg: String,
        /// The slope there, degrees.
        slope_deg: f64,
        /// The steepest allowed, degrees.
        max_deg: f64,
    },
    /// A leg cannot reach the ground under it.
    #[error(
        "the robot cannot stand: leg `{leg}` cannot reach the ground ({reason}); start on flatter ground"
    )]
    CannotReach {
        /// The leg.
        leg: String,
        /// The kinematics' reason.
        reason: String,
    },
    /// A link touches the terrain when standing.
    #[error(
        "the robot cannot stand: link `{link}` touches the terrain at ({:.3}, {:.3}, {:.3}); \
         start on clearer ground", at.x, at.y, at.z
    )]
    Collision {
        /// The link.
        link: String,
        /// Where, world frame.
        at: Point3<f64>,
    },
    /// The centre of mass is not over the feet when standing.
    #[error(
        "the robot cannot stand: its centre of mass is {margin_m:.3} m from the edge of its \
         feet's support polygon (outside when negative); start on flatter ground"
    )]
    Unstable {
        /// The margin, metres.
        margin_m: f64,
    },
}

/// The bus command a move carries out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveCommand {
    /// `legged.legMove`.
    Leg,
    /// `legged.bodyMove`.
    Body,
}

impl MoveCommand {
    /// The message name.
    pub fn name(self) -> &'static str {
        match self {
            MoveCommand::Leg => "legged.legMove",
            MoveCommand::Body => "legged.bodyMove",
        }
    }
}

/// Why a move was refused (nothing moved) or stopped (the robot is where it stopped).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MoveError {
    /// Bad input: refused before moving.
    #[error("{} refused: {reason}", command.name())]
    Refused {
        /// The command.
        command: MoveCommand,
        /// The leg it names, if one.
        leg: Option<String>,
        /// What was wrong and what to send instead.
        reason: String,
    },
    /// The robot lies tipped over and refuses every move.
    #[error("{} refused: the robot has tipped over and lies on the ground", command.name())]
    Fallen {
        /// The command.
        command: MoveCommand,
    },
    /// A joint would leave its limits, or a standing foot its workspace: refused before
    /// moving.
    #[error("{} refused: leg `{leg}`: {reason}", command.name())]
    JointLimit {
        /// The command.
        command: MoveCommand,
        /// The leg.
        leg: String,
        /// Which joint or foot, and how far.
        reason: String,
    },
    /// Too few feet would stand, or the centre of mass would leave their polygon (or come
    /// closer to its edge than the minimum): refused before moving.
    #[error("{} refused as unstable: {reason}", command.name())]
    Unstable {
        /// The command.
        command: MoveCommand,
        /// The leg to be lifted, if one.
        leg: Option<String>,
        /// The smallest margin the move would reach, metres (negative outside; minus
        /// infinity with fewer than three feet).
        margin_m: f64,
        /// Why, for people.
        reason: String,
    },
    /// A link (or a swinging foot) hit the terrain; the move stopped just before.
    #[error(
        "{} stopped: link `{link}` hit the terrain at ({:.3}, {:.3}, {:.3})", command.name(),
        at.x, at.y, at.z
    )]
    Collision {
        /// The command.
        command: MoveCommand,
        /// The leg whose link hit, if a leg's.
        leg: Option<String>,
        /// The link (a foot link for a foot sphere).
        link: String,
        /// Where, world frame.
        at: Point3<f64>,
    },
    /// A transition move reached its last way-point without touching the ground; the leg
    /// is there, in the air.
    #[error("legged.legMove: leg `{leg}` reached its last way-point without touching the ground")]
    NoContact {
        /// The leg.
        leg: String,
    },
    /// The robot tipped over during the move (only when told to carry out unstable moves).
    #[error(
        "{} tipped the robot over: margin {margin_m:.3} m with {} feet standing", command.name(),
        standing.len()
    )]
    TipOver {
        /// The command.
        command: MoveCommand,
        /// The centre of mass then, world frame.
        com: Point3<f64>,
        /// The margin then, metres.
        margin_m: f64,
        /// The legs that stood.
        standing: Vec<String>,
    },
}

/// The exception a failed move raises on the bus.
#[derive(Debug, Clone, PartialEq)]
pub enum MoveException {
    /// `legged.moveFailed`.
    MoveFailed(MoveFailed),
    /// `legged.tipOver`.
    TipOver(TipOver),
}

impl MoveError {
    /// The command that failed.
    pub fn command(&self) -> MoveCommand {
        match self {
            MoveError::Refused { command, .. }
            | MoveError::Fallen { command }
            | MoveError::JointLimit { command, .. }
            | MoveError::Unstable { command, .. }
            | MoveError::Collision { command, .. }
            | MoveError::TipOver { command, .. } => *command,
            MoveError::NoContact { .. } => MoveCommand::Leg,
        }
    }

    /// The leg it concerns, if one.
    pub fn leg(&self) -> Option<&str> {
        match self {
            MoveError::Refused { leg, .. }
            | MoveError::Unstable { leg, .. }
            | MoveError::Collision { leg, .. } => leg.as_deref(),
            MoveError::JointLimit { leg, .. } | MoveError::NoContact { leg } => Some(leg),
            MoveError::Fallen { .. } | MoveError::TipOver { .. } => None,
        }
    }

    /// The failure kind of `legged.moveFailed` (a tip-over reports [`MoveFailureKind::Unstable`]).
    pub fn kind(&self) -> MoveFailureKind {
        match self {
            MoveError::Refused { .. } | MoveError::Fallen { .. } => MoveFailureKind::Refused,
            MoveError::JointLimit { .. } => MoveFailureKind::JointLimit,
            MoveError::Unstable { .. } | MoveError::TipOver { .. } => MoveFailureKind::Unstable,
            MoveError::Collision { .. } => MoveFailureKind::Collision,
            MoveError::NoContact { .. } => MoveFailureKind::NoContact,
        }
    }

    /// Whether the robot moved before the failure (a collision, no contact, a tip-over);
    /// false for refusals, which leave everything as it was.
    pub fn moved(&self) -> bool {
        matches!(
            self,
            MoveError::Collision { .. } | MoveError::NoContact { .. } | MoveError::TipOver { .. }
        )
    }

    /// The bus exception: [`TipOver`] for a tip-over, [`MoveFailed`] otherwise.
    pub fn to_exception(&self) -> MoveException {
        match self {
            MoveError::TipOver {
                com,
                margin_m,
                standing,
                ..
            } => MoveException::TipOver(TipOver {
                com: world_point(com),
                margin_m: *margin_m,
                standing: standing.clone(),
                detail: self.to_string(),
            }),
            _ => MoveException::MoveFailed(MoveFailed {
                command: self.command().name().to_owned(),
                leg: self.leg().map(str::to_owned),
                kind: self.kind(),
                detail: self.to_string(),
            }),
        }
    }
}
