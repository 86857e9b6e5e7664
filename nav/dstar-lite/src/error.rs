//! Why a plan could not be made.

use crate::Cell;
use thiserror::Error;

/// Why a grid could not be built or a path could not be planned.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlanError {
    /// The grid has no cells.
    #[error("the grid is {nx} x {ny} cells; both sides must be at least 1")]
    EmptyGrid {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
    /// The danger vector's length differs from the number of cells.
    #[error("a {nx} x {ny} grid needs {expected} danger values but {got} were given")]
    LengthMismatch {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
        /// `nx * ny`.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// A danger value is negative or NaN.
    #[error(
        "danger {value} at cell ({}, {}) is not valid; give a value of at least 0, or infinity for an untraversable cell",
        cell.ix, cell.iy
    )]
    BadDanger {
        /// The cell.
        cell: Cell,
        /// The value given.
        value: f64,
    },
    /// `beta` is negative or not finite.
    #[error("danger weight beta = {0} is not valid; give a finite value of at least 0")]
    BadBeta(f64),
    /// A cell lies outside the grid.
    #[error("cell ({}, {}) is outside the {nx} x {ny} grid", cell.ix, cell.iy)]
    OutOfGrid {
        /// The cell.
        cell: Cell,
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
    /// No path of finite cost joins the start to the goal.
    #[error(
        "no traversable path from ({}, {}) to ({}, {}): every way is blocked by untraversable cells",
        start.ix, start.iy, goal.ix, goal.iy
    )]
    NoPath {
        /// Start cell.
        start: Cell,
        /// Goal cell.
        goal: Cell,
    },
}
