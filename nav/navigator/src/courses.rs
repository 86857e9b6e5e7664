//! Two courses modelled on the paper's experiments.

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_nav_sensing::Pose2;
use tca_robot::{HeightField, TerrainError};

/// A terrain with its start and goal.
#[derive(Debug, Clone)]
pub struct Course {
    /// The course's name.
    pub name: &'static str,
    /// The terrain.
    pub terrain: HeightField,
    /// The start pose.
    pub start: Pose2,
    /// The goal, m east and north of the start.
    pub goal_offset: [f64; 2],
}

const RES: f64 = 0.02;

fn render(
    nx: usize,
    ny: usize,
    mut f: impl FnMut(f64, f64) -> f64,
) -> Result<HeightField, TerrainError> {
    let mut h = Vec::with_capacity(nx * ny);
    for iy in 0..ny {
        for ix in 0..nx {
            h.push(f(ix as f64 * RES, iy as f64 * RES));
        }
    }
    HeightField::new(Point2::new(0.0, 0.0), RES, nx, ny, h)
}

/// Ramps and a platform (the wheeled base's test): a 4 x 4 m arena crossed by a 0.15 m
/// high platform, 0.4 m deep, whose sides are steps; one 1 m wide ramp up and one down
/// lie to the right of the straight way. The goal is 0.8 m to the left and 2.8 m ahead of
/// the start, beyond the platform: reachable only over the ramps.
pub fn ramps_course() -> Result<Course, TerrainError> {
    let top = 0.15;
    let (up0, up1, down0, down1) = (1.0, 1.8, 2.2, 3.0);
    let (ramp_y0, ramp_y1) = (0.2, 1.2);
    let terrain = render(200, 200, |x, y| {
        let platform = (up1..=down0).contains(&x);
        let on_ramp_y = (ramp_y0..=ramp_y1).contains(&y);
        if platform {
            top
        } else if on_ramp_y && (up0..up1).contains(&x) {
            top * (x - up0) / (up1 - up0)
        } else if on_ramp_y && (down0..down1).contains(&x) {
            top * (down1 - x) / (down1 - down0)
        } else {
            0.0
        }
    })?;
    Ok(Course {
        name: "ramps",
        terrain,
        start: Pose2::new(0.4, 1.8, 0.0),
        goal_offset: [2.8, 0.8],
    })
}

/// Gravel and a hill (the hexapod's test): a 2.6 x 2.2 m bed of gravel (random pebbles up
/// to 12 mm) with a 0.3 m high hill in the middle, far steeper than 20°; the goal is
/// 1.4 m ahead of the start, behind the hill.
pub fn hill_course() -> Result<Course, TerrainError> {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let (nx, ny) = (130, 110);
    let gravel: Vec<f64> = (0..nx * ny).map(|_| rng.random_range(0.0..0.012)).collect();
    // Smooth the gravel once so pebbles span a few cells.
    let smooth = |ix: usize, iy: usize| {
        let mut s = 0.0;
        let mut n = 0.0;
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                let (x, y) = (ix as isize + dx, iy as isize + dy);
                if x >= 0 && y >= 0 && (x as usize) < nx && (y as usize) < ny {
                    s += gravel[y as usize * nx + x as usize];
                    n += 1.0;
                }
            }
        }
        s / n
    };
    let (hx, hy, r) = (1.25, 1.1, 0.3);
    let terrain = render(nx, ny, |x, y| {
        let (ix, iy) = ((x / RES).round() as usize, (y / RES).round() as usize);
        let d = ((x - hx).powi(2) + (y - hy).powi(2)).sqrt();
        let hill = if d < r {
            0.3 * (0.5 + 0.5 * (std::f64::consts::PI * d / r).cos())
        } else {
            0.0
        };
        smooth(ix.min(nx - 1), iy.min(ny - 1)) + hill
    })?;
    Ok(Course {
        name: "hill",
        terrain,
        start: Pose2::new(0.55, 1.1, 0.0),
        goal_offset: [1.4, 0.0],
    })
}

/// A built-in course by name (`ramps` or `hill`).
pub fn course_by_name(name: &str) -> Option<Result<Course, TerrainError>> {
    match name {
        "ramps" => Some(ramps_course()),
        "hill" => Some(hill_course()),
        _ => None,
    }
}
