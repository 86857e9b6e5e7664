//! Why planning failed.

use thiserror::Error;

/// Why the planner could not start or found no path.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlanError {
    /// A parameter is out of range.
    #[error("bad planner parameter: {0}")]
    BadParameter(String),
    /// The robot model does not suit the planner.
    #[error("the robot model does not suit the planner: {0}")]
    Model(String),
    /// The start or the goal is not a place the robot can stand.
    #[error("the {which} at ({x:.3}, {y:.3}) is not a place the robot can stand: {reason}")]
    BadEndpoint {
        /// `start` or `goal`.
        which: &'static str,
        /// World X, metres.
        x: f64,
        /// World Y, metres.
        y: f64,
        /// Why no posture was found there.
        reason: String,
    },
    /// The trees did not meet within the allowed iterations.
    #[error(
        "no path after {iterations} iterations ({start_nodes} nodes grown from the start, \
         {goal_nodes} from the goal; the closest they came was {gap_m:.3} m): {reason}"
    )]
    NoPath {
        /// Iterations run.
        iterations: usize,
        /// Nodes of the start's tree.
        start_nodes: usize,
        /// Nodes of the goal's tree.
        goal_nodes: usize,
        /// Closest distance between a node of one tree and one of the other, metres.
        gap_m: f64,
        /// The commonest reason an extension failed.
        reason: String,
    },
}
