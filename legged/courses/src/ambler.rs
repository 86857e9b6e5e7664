//! The courses at the Ambler's scale: 28 x 14 m (X 0..28, Y -7..7), 0.1 m cells, start
//! (3, 0) facing +X, goal (23, 0).

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_robot::{HeightField, TerrainError};

use crate::CourseStart;
use crate::relief::{Layout, Waves, bump, normalise, start_blend};

/// Sampling layout of every Ambler-scale course.
pub(crate) const LAYOUT: Layout = Layout {
    origin: Point2::new(0.0, -7.0),
    cell_m: 0.1,
    nx: 281,
    ny: 141,
};

/// Start pose.
pub(crate) const START: CourseStart = CourseStart {
    x_m: 3.0,
    y_m: 0.0,
    yaw_rad: 0.0,
};

/// Goal point.
pub(crate) const GOAL: [f64; 2] = [23.0, 0.0];

/// Radius of the level ground around the start, metres.
pub(crate) const START_FLAT_M: f64 = 3.0;

/// Boulder field: where boulders may stand (X range, metres).
pub(crate) const BOULDER_X_M: (f64, f64) = (5.0, 25.0);
/// Tallest boulder, metres.
pub(crate) const BOULDER_MAX_M: f64 = 1.0;
/// Radius of each reserved level foothold between the boulders, metres.
pub(crate) const FOOTHOLD_RADIUS_M: f64 = 0.35;

/// Ditch centre X, opening width and depth, metres.
pub(crate) const DITCH_X_M: f64 = 12.0;
pub(crate) const DITCH_WIDTH_M: f64 = 1.0;
pub(crate) const DITCH_DEPTH_M: f64 = 1.0;

/// Slope foot X, angle and rise to the plateau.
pub(crate) const SLOPE_FOOT_X_M: f64 = 8.0;
pub(crate) const SLOPE_DEG: f64 = 25.0;
pub(crate) const PLATEAU_M: f64 = 2.0;

/// Largest magnitude of the rough course's relief, metres.
pub(crate) const ROUGH_PEAK_M: f64 = 0.15;

fn start_point() -> Point2<f64> {
    Point2::new(START.x_m, START.y_m)
}

/// Level ground at 0.
pub(crate) fn flat() -> Result<HeightField, TerrainError> {
    LAYOUT.render(|_| 0.0)
}

/// The ditch: samples strictly inside the 1 m opening are 1 m deep, so the ground leaves 0
/// at x = 11.5 m and returns to it at x = 12.5 m (walls over one 0.1 m cell, floor 0.8 m).
pub(crate) fn ditch() -> Result<HeightField, TerrainError> {
    LAYOUT.render(|p| {
        if (p.x - DITCH_X_M).abs() < 0.5 * DITCH_WIDTH_M - 1e-6 {
            -DITCH_DEPTH_M
        } else {
            0.0
        }
    })
}

/// The slope: level to x = 8 m, a 25° ramp up to 2 m, then a level plateau to the end.
pub(crate) fn slope() -> Result<HeightField, TerrainError> {
    let grade = SLOPE_DEG.to_radians().tan();
    LAYOUT.render(|p| ((p.x - SLOPE_FOOT_X_M).max(0.0) * grade).min(PLATEAU_M))
}

/// Gentle relief of ±0.15 m everywhere but around the start.
pub(crate) fn rough(seed: u64) -> Result<HeightField, TerrainError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x524f_5547_4800_0000);
    let waves = Waves::new(&mut rng, 14, 1.5, 7.0);
    let mut heights = Vec::with_capacity(LAYOUT.nx * LAYOUT.ny);
    for iy in 0..LAYOUT.ny {
        for ix in 0..LAYOUT.nx {
            let p = LAYOUT.node(ix, iy);
            let w = start_blend((p - start_point()).norm(), START_FLAT_M, 1.0);
            heights.push(w * waves.at(p));
        }
    }
    normalise(&mut heights, ROUGH_PEAK_M);
    HeightField::new(LAYOUT.origin, LAYOUT.cell_m, LAYOUT.nx, LAYOUT.ny, heights)
}

/// One boulder: a raised-cosine dome.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Boulder {
    pub(crate) center: Point2<f64>,
    pub(crate) radius_m: f64,
    pub(crate) height_m: f64,
}

/// The reserved level footholds of the boulder field for `seed`: a rhombic lattice with
/// columns every 1 m along X (5..25 m) and, in each column, a foothold every 2 m along Y,
/// alternate columns offset by 1 m; each point jittered by up to 0.1 m.
pub(crate) fn footholds(rng: &mut ChaCha8Rng) -> Vec<Point2<f64>> {
    let mut out = Vec::new();
    for c in 0..=20 {
        let x = BOULDER_X_M.0 + c as f64;
        let mut y = -7.0 + (c % 2) as f64;
        while y <= 7.0 + 1e-9 {
            out.push(Point2::new(
                x + rng.random_range(-0.1..0.1),
                y + rng.random_range(-0.1..0.1),
            ));
            y += 2.0;
        }
    }
    out
}

/// The boulders for `seed`: one in most holes of the foothold lattice, each clear of every
/// reserved foothold, of the start's level patch and of the field's X bounds; the largest
/// is exactly 1.0 m high.
pub(crate) fn boulder_list(seed: u64) -> (Vec<Boulder>, Vec<Point2<f64>>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x424f_554c_4445_5253);
    let holds = footholds(&mut rng);
    let mut boulders: Vec<Boulder> = Vec::new();
    for c in 0..=20 {
        let x = BOULDER_X_M.0 + c as f64;
        let mut y = -6.0 - (c % 2) as f64;
        while y <= 7.0 + 1e-9 {
            let place = rng.random_bool(0.75);
            let jitter = Point2::new(rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1));
            let wanted_r: f64 = rng.random_range(0.45..0.72);
            let wanted_h: f64 = rng.random_range(0.3..BOULDER_MAX_M);
            let center = LAYOUT.snap(Point2::new(x + jitter.x, y + jitter.y));
            y += 2.0;
            if !place {
                continue;
            }
            let mut room = (center.x - BOULDER_X_M.0)
                .min(BOULDER_X_M.1 - center.x)
                .min((center - start_point()).norm() - START_FLAT_M - 0.2);
            for h in &holds {
                room = room.min((center - h).norm() - FOOTHOLD_RADIUS_M - 0.05);
            }
            if room < 0.35 {
                continue;
            }
            let radius_m = wanted_r.min(room);
            boulders.push(Boulder {
                center,
                radius_m,
                height_m: wanted_h.min(1.6 * radius_m),
            });
        }
    }
    // The widest boulder is the tallest: exactly the field's limit.
    if let Some(b) = boulders
        .iter_mut()
        .max_by(|a, b| a.radius_m.total_cmp(&b.radius_m))
    {
        b.height_m = BOULDER_MAX_M;
    }
    (boulders, holds)
}

/// Boulder field over x 5..25 m on level ground.
pub(crate) fn boulders(seed: u64) -> Result<HeightField, TerrainError> {
    let (list, _) = boulder_list(seed);
    let mut heights = vec![0.0_f64; LAYOUT.nx * LAYOUT.ny];
    let cell = LAYOUT.cell_m;
    for b in &list {
        let lo_x = ((b.center.x - b.radius_m - LAYOUT.origin.x) / cell)
            .floor()
            .max(0.0) as usize;
        let hi_x = (((b.center.x + b.radius_m - LAYOUT.origin.x) / cell).ceil() as usize)
            .min(LAYOUT.nx - 1);
        let lo_y = ((b.center.y - b.radius_m - LAYOUT.origin.y) / cell)
            .floor()
            .max(0.0) as usize;
        let hi_y = (((b.center.y + b.radius_m - LAYOUT.origin.y) / cell).ceil() as usize)
            .min(LAYOUT.ny - 1);
        for iy in lo_y..=hi_y {
            for ix in lo_x..=hi_x {
                let d = (LAYOUT.node(ix, iy) - b.center).norm() / b.radius_m;
                let h = b.height_m * bump(d);
                let slot = &mut heights[iy * LAYOUT.nx + ix];
                *slot = slot.max(h);
            }
        }
    }
    HeightField::new(LAYOUT.origin, LAYOUT.cell_m, LAYOUT.nx, LAYOUT.ny, heights)
}
