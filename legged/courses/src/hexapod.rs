//! The courses at the small hexapod's scale: 3.5 x 1.5 m (X 0..3.5, Y -0.75..0.75), 0.02 m
//! cells, start (0.3, 0) facing +X, goal (3.2, 0).

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_robot::{HeightField, TerrainError};

use crate::CourseStart;
use crate::relief::{Layout, Waves, bump, normalise, start_blend};

/// Sampling layout of the hexapod-scale courses.
pub(crate) const LAYOUT: Layout = Layout {
    origin: Point2::new(0.0, -0.75),
    cell_m: 0.02,
    nx: 176,
    ny: 76,
};

/// Start pose.
pub(crate) const START: CourseStart = CourseStart {
    x_m: 0.3,
    y_m: 0.0,
    yaw_rad: 0.0,
};

/// Goal point.
pub(crate) const GOAL: [f64; 2] = [3.2, 0.0];

/// Radius of the level ground around the start, metres.
pub(crate) const START_FLAT_M: f64 = 0.3;

/// Largest magnitude of the ground relief, metres.
pub(crate) const RELIEF_PEAK_M: f64 = 0.02;
/// Tallest pebble above the relief, metres.
pub(crate) const STONE_MAX_M: f64 = 0.04;

fn start_point() -> Point2<f64> {
    Point2::new(START.x_m, START.y_m)
}

/// Level ground at 0.
pub(crate) fn flat() -> Result<HeightField, TerrainError> {
    LAYOUT.render(|_| 0.0)
}

/// Relief of ±2 cm with pebbles of 1-4 cm on it, level around the start.
pub(crate) fn rough(seed: u64) -> Result<HeightField, TerrainError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x4845_5841_524f_5547);
    let waves = Waves::new(&mut rng, 12, 0.25, 1.2);
    let mut heights = Vec::with_capacity(LAYOUT.nx * LAYOUT.ny);
    for iy in 0..LAYOUT.ny {
        for ix in 0..LAYOUT.nx {
            let p = LAYOUT.node(ix, iy);
            let w = start_blend((p - start_point()).norm(), START_FLAT_M, 0.15);
            heights.push(w * waves.at(p));
        }
    }
    normalise(&mut heights, RELIEF_PEAK_M);
    let mut stones = vec![0.0_f64; heights.len()];
    for _ in 0..70 {
        let r = rng.random_range(0.02..0.06);
        let h = rng.random_range(0.01..STONE_MAX_M).min(r);
        let c = LAYOUT.snap(Point2::new(
            rng.random_range(0.6..3.45),
            rng.random_range(-0.72..0.72),
        ));
        if (c - start_point()).norm() < START_FLAT_M + r + 0.05 {
            continue;
        }
        for (i, s) in stones.iter_mut().enumerate() {
            let d = (LAYOUT.node(i % LAYOUT.nx, i / LAYOUT.nx) - c).norm() / r;
            if d < 1.0 {
                *s = s.max(h * bump(d));
            }
        }
    }
    for (h, s) in heights.iter_mut().zip(&stones) {
        *h += s;
    }
    HeightField::new(LAYOUT.origin, LAYOUT.cell_m, LAYOUT.nx, LAYOUT.ny, heights)
}
