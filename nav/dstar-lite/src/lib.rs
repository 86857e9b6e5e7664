//! Path planning over a danger grid for rough-terrain navigation, after Chilian and
//! Hirschmüller, "Stereo Camera Based Navigation of Mobile Robots on Rough Terrain".
//!
//! The grid's cells are the vertices of a graph; each cell is joined to its eight
//! neighbours. Moving from a cell `N` to a neighbour `N'` costs
//!
//! ```text
//! c(N, N') = |N - N'| + beta * d(N')
//! ```
//!
//! where `|N - N'|` is 1 along a row or column and √2 diagonally (lengths are in cells, so
//! that `beta` weighs one cell's danger against one cell's length) and `d(N')` is the
//! danger of the cell entered, in `[0, 1]` or `∞`. A cell of danger `∞` is never entered.
//!
//! * [`DStarLite`] searches from the goal toward the start and keeps its search between
//!   calls: after cells change ([`DStarLite::set_danger`]) and the robot moves
//!   ([`DStarLite::move_start`]), [`DStarLite::plan`] repairs only what the change touched.
//! * [`astar`] plans from scratch, the baseline the incremental planner is compared with.
//!
//! Both use the octile distance as heuristic, which never overestimates the cost since
//! every danger is at least 0, and is consistent (it obeys the triangle inequality over
//! the eight moves), so both return paths of minimum cost.

mod astar;
mod dstar;
mod error;
mod grid;
mod key;

pub use astar::astar;
pub use dstar::DStarLite;
pub use error::PlanError;
pub use grid::{Cell, CostGrid, octile};

/// A planned path and what it took to find it.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    /// The cells from the start to the goal, both included.
    pub cells: Vec<Cell>,
    /// The sum of the edge costs along `cells`.
    pub cost: f64,
    /// Vertices expanded (taken off the open list and processed) by the call that
    /// produced this path.
    pub expansions: u64,
}
