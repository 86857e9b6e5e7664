//! The cost maps (§6.2.1, Figure 9), one file per constraint, all on the region's grid.

pub(crate) mod advance;
pub(crate) mod elevation;
pub(crate) mod footfall;
pub(crate) mod visibility;

use tca_robot::Grid;

/// Every cost map of one step, on the region's grid (for choosing, pictures and tests).
#[derive(Debug, Clone, PartialEq)]
pub struct CostMaps {
    /// Footfall cost, 0 (flat) .. 1; `None` where unknown.
    pub footfall: Grid<Option<f64>>,
    /// Filtered footfall cost, 0 .. 1.
    pub filtered_footfall: Grid<f64>,
    /// Largest body advance from the cell, metres (`None`: the foot cannot be there).
    pub body_advance_m: Grid<Option<f64>>,
    /// Body advance cost, 0 (the full step) .. 1 (none).
    pub body_advance: Grid<f64>,
    /// Fraction of the horizontal links in the scanner's view after the body move, 0 .. 1.
    pub scanner_visibility: Grid<f64>,
    /// Leg reachability (binary, from the Leg Recovery Planner and the kinematics).
    pub reachable: Grid<bool>,
    /// Ground under the foot, metres (`None` where not all known).
    pub ground_m: Grid<Option<f64>>,
    /// Terrain elevation within reach (binary).
    pub elevation_ok: Grid<bool>,
    /// A clear region of the required diameter around the cell (binary).
    pub clear: Grid<bool>,
    /// The composite cost; `None` where a binary map eliminated the cell.
    pub total: Grid<Option<f64>>,
}
