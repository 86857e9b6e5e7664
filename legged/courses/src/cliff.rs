//! The CG-space courses at the Ambler's scale: 30 x 26 m (X 0..30, Y -13..13), 0.1 m cells.
//!
//! `cliff`: a plateau 2.5 m high across the whole way from x = 14 m, taller than the
//! Ambler's legs can step (1.2 m of vertical travel either way), with a ramp 10 m wide up to
//! it on the north side (y 2.5..12.5 m, rising from x = 6 m to 14 m at 17°: wide enough for the
//! Ambler, 7.7 m across its middle feet, to walk up it facing the plateau); start (4, 0),
//! goal (24, 0) on the plateau. `walled-goal`: the goal (20, 0) in a yard ringed by a cliff 1 m
//! thick and 5 m high, 5 m from it; start (5, 0). Both carry gentle seeded relief of up to
//! 5 cm away from the start, so seeds differ.

use nalgebra::Point2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tca_robot::{HeightField, TerrainError};

use crate::CourseStart;
use crate::relief::{Layout, Waves, normalise, start_blend};

/// Sampling layout of both courses.
pub(crate) const LAYOUT: Layout = Layout {
    origin: Point2::new(0.0, -13.0),
    cell_m: 0.1,
    nx: 301,
    ny: 261,
};

/// The plateau's height and where it begins, metres.
pub(crate) const PLATEAU_M: f64 = 2.5;
pub(crate) const CLIFF_X_M: f64 = 14.0;
/// The ramp: where it rises along X, and its sides along Y, metres.
pub(crate) const RAMP_X_M: (f64, f64) = (6.0, 14.0);
pub(crate) const RAMP_Y_M: (f64, f64) = (2.5, 12.5);

/// The cliff course's start and goal.
pub(crate) const CLIFF_START: CourseStart = CourseStart {
    x_m: 4.0,
    y_m: 0.0,
    yaw_rad: 0.0,
};
pub(crate) const CLIFF_GOAL: [f64; 2] = [24.0, 0.0];

/// The walled yard: its centre (the goal), inner half-side and wall thickness and height.
pub(crate) const YARD_CENTRE: [f64; 2] = [20.0, 0.0];
pub(crate) const YARD_HALF_M: f64 = 5.0;
pub(crate) const WALL_THICK_M: f64 = 1.0;
pub(crate) const WALL_M: f64 = 5.0;
pub(crate) const WALLED_START: CourseStart = CourseStart {
    x_m: 5.0,
    y_m: 0.0,
    yaw_rad: 0.0,
};

/// Largest magnitude of the relief, metres, and the level radius about the start.
pub(crate) const RELIEF_M: f64 = 0.05;
const START_FLAT_M: f64 = 3.0;

/// Relief for `seed` over the layout, level about `start`.
fn relief(seed: u64, start: Point2<f64>) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x434c_4946_4600_0000);
    let waves = Waves::new(&mut rng, 12, 1.5, 6.0);
    let mut heights = Vec::with_capacity(LAYOUT.nx * LAYOUT.ny);
    for iy in 0..LAYOUT.ny {
        for ix in 0..LAYOUT.nx {
            let p = LAYOUT.node(ix, iy);
            let w = start_blend((p - start).norm(), START_FLAT_M, 1.0);
            heights.push(w * waves.at(p));
        }
    }
    normalise(&mut heights, RELIEF_M);
    heights
}

fn with_relief(
    seed: u64,
    start: CourseStart,
    shape: impl Fn(Point2<f64>) -> f64,
) -> Result<HeightField, TerrainError> {
    let mut heights = relief(seed, Point2::new(start.x_m, start.y_m));
    for iy in 0..LAYOUT.ny {
        for ix in 0..LAYOUT.nx {
            heights[iy * LAYOUT.nx + ix] += shape(LAYOUT.node(ix, iy));
        }
    }
    HeightField::new(LAYOUT.origin, LAYOUT.cell_m, LAYOUT.nx, LAYOUT.ny, heights)
}

/// The cliff course's shape without relief.
pub(crate) fn cliff_shape(p: Point2<f64>) -> f64 {
    if p.y > RAMP_Y_M.0 && p.y < RAMP_Y_M.1 {
        (PLATEAU_M * (p.x - RAMP_X_M.0) / (RAMP_X_M.1 - RAMP_X_M.0)).clamp(0.0, PLATEAU_M)
    } else if p.x >= CLIFF_X_M {
        PLATEAU_M
    } else {
        0.0
    }
}

/// The cliff course.
pub(crate) fn cliff(seed: u64) -> Result<HeightField, TerrainError> {
    with_relief(seed, CLIFF_START, cliff_shape)
}

/// The walled yard's shape without relief.
pub(crate) fn walled_shape(p: Point2<f64>) -> f64 {
    let d = (p.x - YARD_CENTRE[0])
        .abs()
        .max((p.y - YARD_CENTRE[1]).abs());
    if (YARD_HALF_M..YARD_HALF_M + WALL_THICK_M).contains(&d) {
        WALL_M
    } else {
        0.0
    }
}

/// The walled-goal course.
pub(crate) fn walled(seed: u64) -> Result<HeightField, TerrainError> {
    with_relief(seed, WALLED_START, walled_shape)
}
