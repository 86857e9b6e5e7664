//! What goes wrong: a move that failed, a hardware fault, a tip-over.

use serde::{Deserialize, Serialize};
use tca_messages::message;

use crate::geometry::WorldPoint;

/// Why a move failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MoveFailureKind {
    /// A link would hit, or hit, the terrain or another link.
    Collision,
    /// A transition move reached its end without touching the ground.
    NoContact,
    /// A standing foot slipped.
    Slip,
    /// A joint would pass its limits, or a foot leave its workspace.
    JointLimit,
    /// The centre of mass would leave the support polygon (or its margin fall below the
    /// minimum) along the move; nothing moved.
    Unstable,
    /// The command was refused (an unknown leg, way-points of the wrong length, numbers that
    /// are not finite...).
    Refused,
}

/// Exception: a leg or body move failed; the walker plans again from where the robot is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MoveFailed {
    /// The command that failed (`legged.legMove` or `legged.bodyMove`).
    pub command: String,
    /// The leg it concerns, if one.
    pub leg: Option<String>,
    /// What happened.
    pub kind: MoveFailureKind,
    /// A sentence for people.
    pub detail: String,
}
message!(MoveFailed: exception "legged.moveFailed");

/// Exception: a hardware fault; the walk is halted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HardwareFault {
    /// The leg it concerns, if one.
    pub leg: Option<String>,
    /// A sentence for people.
    pub detail: String,
}
message!(HardwareFault: exception "legged.hardwareFault");

/// Exception: the robot tipped over (the centre of mass left the support polygon, or fewer
/// than three feet stood, while the body was not supported otherwise). Counted as a fall;
/// the walk is halted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TipOver {
    /// The centre of mass when it happened, world frame.
    pub com: WorldPoint,
    /// The stability margin then, metres (negative: outside the polygon).
    pub margin_m: f64,
    /// The legs that stood.
    pub standing: Vec<String>,
    /// A sentence for people.
    pub detail: String,
}
message!(TipOver: exception "legged.tipOver");
