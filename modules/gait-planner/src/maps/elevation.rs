//! The terrain elevation map (§6.2.1): the ground under the foot, and whether it is within
//! the foot's vertical reach (the body height is fixed, so the leg cannot reach ground that
//! is too high or too low). Binary.

use tca_lrp::{ObstacleHeights, TerrainGrid};
use tca_robot::Grid;

use crate::region::StepRegion;

/// Per cell: the highest known ground under the foot disc (`None` when any of it is unknown
/// or occluded).
pub(crate) fn ground_map(
    region: &StepRegion,
    elevation: &TerrainGrid,
    foot_radius_m: f64,
) -> Grid<Option<f64>> {
    let heights = ObstacleHeights::new(elevation, 0.0, f64::INFINITY);
    let mut out = region.grid_of(None);
    for (c, v) in out.iter_mut() {
        let (h, known) = heights.max_in_disc(region.layout.cell_center(c), foot_radius_m);
        *v = (known && h.is_finite()).then_some(h);
    }
    out
}

/// Whether the ground is within `[lowest_m, highest_m]`.
pub(crate) fn elevation_ok(
    ground: &Grid<Option<f64>>,
    lowest_m: f64,
    highest_m: f64,
) -> Grid<bool> {
    ground.map(|g| g.is_some_and(|h| h >= lowest_m && h <= highest_m))
}
