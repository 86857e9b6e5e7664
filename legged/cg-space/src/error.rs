//! What can go wrong in CG-space planning.

use thiserror::Error;

/// A refusal or failure of the CG-space planner, with what was wrong and what to do.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CgError {
    /// A parameter is out of its range.
    #[error("{what} is {value}, which is not allowed: {hint}")]
    BadParameter {
        /// The parameter.
        what: &'static str,
        /// The value given.
        value: f64,
        /// What to give instead.
        hint: &'static str,
    },
    /// The robot description cannot be planned for.
    #[error("robot `{robot}` cannot be planned for: {reason}")]
    Robot {
        /// The robot's name.
        robot: String,
        /// Why.
        reason: String,
    },
    /// A pose lies outside the terrain map.
    #[error(
        "{what} ({x:.2}, {y:.2}) m is outside the map, which covers x {x_min:.2}..{x_max:.2} m and y {y_min:.2}..{y_max:.2} m"
    )]
    OutsideMap {
        /// Which pose.
        what: &'static str,
        /// World X, metres.
        x: f64,
        /// World Y, metres.
        y: f64,
        /// The map's smallest X.
        x_min: f64,
        /// The map's largest X.
        x_max: f64,
        /// The map's smallest Y.
        y_min: f64,
        /// The map's largest Y.
        y_max: f64,
    },
    /// The start or goal cell is not a valid CG cell.
    #[error("the {what} cell ({ix}, {iy}, heading bin {it}) is not a valid CG cell: {reason}")]
    InvalidEndpoint {
        /// `start` or `goal`.
        what: &'static str,
        /// Cell column.
        ix: i32,
        /// Cell row.
        iy: i32,
        /// Heading bin.
        it: u16,
        /// Why it is invalid.
        reason: String,
    },
    /// No route joins the start to the goal: the region of valid CG cells about one of
    /// them was explored to its end without meeting the other.
    #[error(
        "no route: the goal cannot be reached from the start ({explored} CG cells explored about the {enclosed}, which are enclosed by invalid cells)"
    )]
    Unreachable {
        /// `start` or `goal`: the one whose region was exhausted.
        enclosed: &'static str,
        /// How many valid cells that region holds.
        explored: usize,
    },
    /// The planner gave up within its budget without proving that no route exists.
    #[error("no route found within the planning budget ({detail}); give a larger budget")]
    BudgetExhausted {
        /// Which budget ran out.
        detail: String,
    },
    /// The route planner's joins could not be run where they were sent (workers that cannot
    /// be reached, replaced or that refused the batch).
    #[error("the route could not be planned: {reason}")]
    Joins {
        /// What the joiner said.
        reason: String,
    },
    /// The foot-level search failed along every route it was given.
    #[error("no footfalls found along the route after {replans} replans: {detail}")]
    NoFootfalls {
        /// How many times the route was replanned with offending cells marked invalid.
        replans: usize,
        /// The last failure.
        detail: String,
    },
}
