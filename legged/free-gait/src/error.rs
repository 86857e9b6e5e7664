//! Why a step could not be planned.

use thiserror::Error;

/// Why [`FreeGait::plan_step`](crate::FreeGait::plan_step) planned no step. Every message
/// says what was lacking and, where it helps, which leg.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum GaitError {
    /// The body is already within the goal tolerance: there is nothing to do.
    #[error("the body is {distance_m:.3} m from the goal, within the tolerance: no step is needed")]
    GoalReached {
        /// Horizontal distance from the body to the goal, metres.
        distance_m: f64,
    },
    /// The state given does not fit the robot (leg count, joint count, numbers).
    #[error("the walking state does not fit the robot: {reason}")]
    BadState {
        /// What is wrong with it.
        reason: String,
    },
    /// A leg that must step has nowhere to go.
    #[error("leg `{leg}` has no foothold: {reason}")]
    NoFoothold {
        /// The leg's name.
        leg: String,
        /// What every candidate lacked.
        reason: String,
    },
    /// The terrain the step needs is not known.
    #[error("the terrain ahead is unknown: {what}; scan it before stepping")]
    UnknownTerrain {
        /// Where knowledge is lacking.
        what: String,
    },
    /// The robot cannot keep its stability margin.
    #[error("no move keeps the robot stable: {reason}")]
    Unstable {
        /// Why.
        reason: String,
    },
    /// No step makes progress toward the goal; each leg's reason is given.
    #[error("no step makes progress toward the goal: {reason}")]
    Blocked {
        /// What stopped each leg and the body.
        reason: String,
    },
}
