//! The planning region: the 10 cm grid over the reachable space forward of the carriage
//! (behind it when walking backward), and the polygons to ask the LTM Manager for.

use nalgebra::Point2;
use tca_robot::{Grid, LegParams};
use tca_single_leg_messages::PlanePoint;

use crate::error::{GaitError, Result};

/// Which way the carriage walks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WalkDirection {
    /// Toward +Y.
    Forward,
    /// Toward -Y (the scanner cannot see there; the maps come from the LTM's memory).
    Backward,
}

impl WalkDirection {
    /// +1 forward, -1 backward.
    pub fn sign(self) -> f64 {
        match self {
            WalkDirection::Forward => 1.0,
            WalkDirection::Backward => -1.0,
        }
    }
}

/// The cost maps' grid for one step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepRegion {
    /// Walking direction.
    pub direction: WalkDirection,
    /// Carriage Y.
    pub body_y_m: f64,
    /// World X of the leg's column.
    pub column_x_m: f64,
    /// The grid's layout (cell centres); the values are unused.
    pub layout: Grid<()>,
}

impl StepRegion {
    /// The half disc of the leg's reach ahead of (behind) the carriage, as a grid of
    /// `resolution_m` cells.
    pub fn new(
        leg: &LegParams,
        resolution_m: f64,
        body_y_m: f64,
        direction: WalkDirection,
    ) -> Result<Self> {
        let reach = leg.leg.upper_link_m + leg.leg.lower_link_m;
        let nx = ((2.0 * reach / resolution_m).ceil() as usize).max(1);
        let ny = ((reach / resolution_m).ceil() as usize).max(1);
        let x0 = leg.carriage.x_m - 0.5 * nx as f64 * resolution_m + 0.5 * resolution_m;
        let y0 = match direction {
            WalkDirection::Forward => body_y_m + 0.5 * resolution_m,
            WalkDirection::Backward => body_y_m - ny as f64 * resolution_m + 0.5 * resolution_m,
        };
        let layout = Grid::filled(Point2::new(x0, y0), resolution_m, nx, ny, ()).map_err(|_| {
            GaitError::NotFinite {
                what: "carriage position",
            }
        })?;
        Ok(Self {
            direction,
            body_y_m,
            column_x_m: leg.carriage.x_m,
            layout,
        })
    }

    /// The region's rectangle grown by `grow_m` on every side, as a polygon for map queries.
    pub fn polygon(&self, grow_m: f64) -> Vec<PlanePoint> {
        let (lo, hi) = self.layout.bounds();
        let (x0, y0, x1, y1) = (lo.x - grow_m, lo.y - grow_m, hi.x + grow_m, hi.y + grow_m);
        vec![
            PlanePoint { x_m: x0, y_m: y0 },
            PlanePoint { x_m: x1, y_m: y0 },
            PlanePoint { x_m: x1, y_m: y1 },
            PlanePoint { x_m: x0, y_m: y1 },
        ]
    }

    /// A grid of the region's layout filled with a value.
    pub fn grid_of<T: Clone>(&self, value: T) -> Grid<T> {
        self.layout.map(|_| value.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forward_region_starts_at_the_carriage_and_spans_the_reach() {
        let r = StepRegion::new(&LegParams::default(), 0.1, 2.0, WalkDirection::Forward).unwrap();
        let (lo, hi) = r.layout.bounds();
        assert!(
            (lo.y - 2.0).abs() < 1e-9 && (hi.y - 4.5).abs() < 1e-9,
            "{lo} {hi}"
        );
        assert!(
            (lo.x - 0.5).abs() < 1e-9 && (hi.x - 5.5).abs() < 1e-9,
            "{lo} {hi}"
        );
        assert_eq!((r.layout.nx(), r.layout.ny()), (50, 25));
        let back =
            StepRegion::new(&LegParams::default(), 0.1, 2.0, WalkDirection::Backward).unwrap();
        let (lo, hi) = back.layout.bounds();
        assert!(
            (lo.y + 0.5).abs() < 1e-9 && (hi.y - 2.0).abs() < 1e-9,
            "{lo} {hi}"
        );
        assert_eq!(r.polygon(0.5).len(), 4);
    }
}
