//! The rock field at the ATHLETE-like rover's scale: 14 x 14 m (X 0..14, Y -7..7), 0.05 m
//! cells, start (7, 0) facing +X, goal (12, 0). Rocks of 8-45 cm stand among the wheels'
//! reach; the ground under every wheel of the standing rover is level.

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_robot::{HeightField, TerrainError};

use crate::CourseStart;
use crate::relief::{Layout, Waves, bump, normalise};

/// Sampling layout of the rock field.
pub(crate) const LAYOUT: Layout = Layout {
    origin: Point2::new(0.0, -7.0),
    cell_m: 0.05,
    nx: 281,
    ny: 281,
};

/// Start pose: the rover's body centre.
pub(crate) const START: CourseStart = CourseStart {
    x_m: 7.0,
    y_m: 0.0,
    yaw_rad: 0.0,
};

/// Goal point: far enough inside that the shipped `athlete` (wheels 2.75 m out, more with
/// its reach) stands on the field there.
pub(crate) const GOAL: [f64; 2] = [10.5, 0.0];

/// Where the rover's wheels stand at the start, relative to its body centre: the
/// neutral wheel circle of the shipped `athlete` (2.75 m radius, limbs at ±30°, ±90°,
/// ±150°).
pub const WHEEL_RING_M: f64 = 2.75;
/// The limbs' directions from forward, degrees.
pub const LIMB_BEARINGS_DEG: [f64; 6] = [30.0, 90.0, 150.0, -30.0, -90.0, -150.0];
/// Radius of the level disc kept around every starting wheel, metres.
pub const WHEEL_PATCH_M: f64 = 0.6;
/// Tallest rock, metres.
pub const ROCK_MAX_M: f64 = 0.45;
/// Lowest rock, metres.
pub const ROCK_MIN_M: f64 = 0.08;
/// Largest magnitude of the relief between the rocks, metres.
pub const RELIEF_PEAK_M: f64 = 0.03;
/// How many rocks are tried (some are dropped for the wheels' discs).
const ROCKS_TRIED: usize = 110;

/// The starting wheel positions (world XY).
pub fn wheel_spots() -> Vec<Point2<f64>> {
    LIMB_BEARINGS_DEG
        .iter()
        .map(|deg| {
            let a = deg.to_radians() + START.yaw_rad;
            Point2::new(
                START.x_m + WHEEL_RING_M * a.cos(),
                START.y_m + WHEEL_RING_M * a.sin(),
            )
        })
        .collect()
}

/// One rock: a raised-cosine dome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rock {
    /// Centre, world XY.
    pub center: Point2<f64>,
    /// Radius of its base, metres.
    pub radius_m: f64,
    /// Height above the ground around it, metres.
    pub height_m: f64,
}

/// The rocks of `seed`: radii 0.15-0.45 m, heights 0.08-0.45 m (never more than 1.2
/// radii), none within [`WHEEL_PATCH_M`] of a starting wheel, the tallest exactly
/// [`ROCK_MAX_M`].
pub fn rock_list(seed: u64) -> Vec<Rock> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x524f_434b_4649_454c);
    let wheels = wheel_spots();
    let mut rocks: Vec<Rock> = Vec::new();
    for _ in 0..ROCKS_TRIED {
        let center = LAYOUT.snap(Point2::new(
            rng.random_range(0.6..13.4),
            rng.random_range(-6.4..6.4),
        ));
        let radius_m: f64 = rng.random_range(0.15..0.45);
        let height_m = rng.random_range(ROCK_MIN_M..ROCK_MAX_M).min(1.2 * radius_m);
        let clear = wheels
            .iter()
            .all(|w| (center - w).norm() >= WHEEL_PATCH_M + radius_m + 0.05);
        if clear {
            rocks.push(Rock {
                center,
                radius_m,
                height_m,
            });
        }
    }
    if let Some(r) = rocks
        .iter_mut()
        .max_by(|a, b| a.radius_m.total_cmp(&b.radius_m))
    {
        r.height_m = ROCK_MAX_M;
    }
    rocks
}

/// The rock field: a relief of ±3 cm (level under the starting wheels) with the rocks on it.
pub(crate) fn rock_field(seed: u64) -> Result<HeightField, TerrainError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5245_4c49_4546_5f52);
    let waves = Waves::new(&mut rng, 10, 1.0, 4.0);
    let wheels = wheel_spots();
    let mut heights = Vec::with_capacity(LAYOUT.nx * LAYOUT.ny);
    for iy in 0..LAYOUT.ny {
        for ix in 0..LAYOUT.nx {
            let p = LAYOUT.node(ix, iy);
            let near = wheels
                .iter()
                .map(|w| (p - w).norm())
                .fold(f64::INFINITY, f64::min);
            // Level within the wheel's disc, relief fading in over the next 0.4 m.
            let w = 1.0 - bump(((near - WHEEL_PATCH_M) / 0.4).max(0.0));
            heights.push(w * waves.at(p));
        }
    }
    normalise(&mut heights, RELIEF_PEAK_M);
    // Rocks sit on the relief; where two overlap the higher one shows.
    let mut rocks = vec![0.0_f64; heights.len()];
    for rock in rock_list(seed) {
        let reach = (rock.radius_m / LAYOUT.cell_m).ceil() as isize + 1;
        let cx = ((rock.center.x - LAYOUT.origin.x) / LAYOUT.cell_m).round() as isize;
        let cy = ((rock.center.y - LAYOUT.origin.y) / LAYOUT.cell_m).round() as isize;
        for iy in (cy - reach).max(0)..=(cy + reach).min(LAYOUT.ny as isize - 1) {
            for ix in (cx - reach).max(0)..=(cx + reach).min(LAYOUT.nx as isize - 1) {
                let (ix, iy) = (ix as usize, iy as usize);
                let d = (LAYOUT.node(ix, iy) - rock.center).norm() / rock.radius_m;
                if d < 1.0 {
                    let r = &mut rocks[iy * LAYOUT.nx + ix];
                    *r = r.max(rock.height_m * bump(d));
                }
            }
        }
    }
    for (h, r) in heights.iter_mut().zip(&rocks) {
        *h += r;
    }
    HeightField::new(LAYOUT.origin, LAYOUT.cell_m, LAYOUT.nx, LAYOUT.ny, heights)
}
