//! Scenes shared by the Leg Recovery Planner's tests: terrains, maps and planted feet.

#![allow(dead_code, unreachable_pub)]

use nalgebra::{Point2, Point3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_lrp::{LegRecoveryPlanner, LrpParams, TerrainGrid};
use tca_robot::{
    CarriagePose, ElbowBranch, Grid, HeightField, JointPosition, LegKinematics, LegParams,
};

/// Map resolution the LRP asks the LTM Manager for.
pub const MAP_RES_M: f64 = 0.05;

pub fn planner() -> LegRecoveryPlanner {
    LegRecoveryPlanner::new(LegParams::default(), LrpParams::default()).unwrap()
}

pub fn kin() -> LegKinematics {
    LegKinematics::new(&LegParams::default())
}

/// The elevation map of the leg's whole reach around the carriage.
pub fn map_around(terrain: &HeightField, body_y_m: f64) -> TerrainGrid {
    TerrainGrid::elevation_from_height_field(
        terrain,
        Point2::new(0.0, body_y_m - 2.9),
        Point2::new(6.0, body_y_m + 2.9),
        MAP_RES_M,
    )
    .unwrap()
}

/// The joints of a foot resting on the ground at `xy` (the sole on the highest point under
/// the foot disc), on the given elbow branch if it is within the joint limits, else the other.
pub fn planted(
    terrain: &HeightField,
    body_y_m: f64,
    xy: Point2<f64>,
    branch: ElbowBranch,
) -> JointPosition {
    let z = terrain.max_height_in_disc(xy, 0.15);
    let other = match branch {
        ElbowBranch::Positive => ElbowBranch::Negative,
        ElbowBranch::Negative => ElbowBranch::Positive,
    };
    let pose = CarriagePose::level(body_y_m);
    let p = Point3::new(xy.x, xy.y, z);
    kin()
        .inverse_world(&pose, &p, branch)
        .or_else(|_| kin().inverse_world(&pose, &p, other))
        .unwrap()
}

/// The footfall at `xy`: the highest ground under the foot disc.
pub fn footfall(terrain: &HeightField, xy: Point2<f64>) -> Point3<f64> {
    Point3::new(xy.x, xy.y, terrain.max_height_in_disc(xy, 0.15))
}

/// A flat 6 x 8 m terrain at `height` with axis-aligned boxes `(cx, cy, sx, sy, h)`.
pub fn boxes(height: f64, list: &[(f64, f64, f64, f64, f64)]) -> HeightField {
    let grid = Grid::from_fn(Point2::new(0.0, 0.0), 0.02, 301, 401, |_, p| {
        let mut h = height;
        for &(cx, cy, sx, sy, bh) in list {
            if (p.x - cx).abs() <= 0.5 * sx && (p.y - cy).abs() <= 0.5 * sy {
                h = h.max(height + bh);
            }
        }
        h
    })
    .unwrap();
    HeightField::from_grid(grid).unwrap()
}

/// A small random terrain around a carriage at y = 4 m: boxes between a start and a goal
/// footfall on flat sand, some low enough to lift over and some not. Returns the terrain,
/// the start and the goal XY.
pub fn random_scene(seed: u64) -> (HeightField, Point2<f64>, Point2<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let angle = |rng: &mut ChaCha8Rng| rng.random_range(-1.3..1.3);
    let radius = |rng: &mut ChaCha8Rng| rng.random_range(1.3..2.2);
    let column = Point2::new(3.0, 4.0);
    let a0: f64 = std::f64::consts::FRAC_PI_2 + angle(&mut rng);
    let a1: f64 = a0 + rng.random_range(0.8..2.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let (r0, r1) = (radius(&mut rng), radius(&mut rng));
    let start = column + nalgebra::Vector2::new(a0.cos(), a0.sin()) * r0;
    let goal = column + nalgebra::Vector2::new(a1.cos(), a1.sin()) * r1;
    let mut list = Vec::new();
    let n = rng.random_range(3..7);
    let mut tries = 0;
    while list.len() < n && tries < 200 {
        tries += 1;
        let t: f64 = rng.random_range(0.2..0.8);
        let mid = start
            + (goal - start) * t
            + nalgebra::Vector2::new(rng.random_range(-0.8..0.8), rng.random_range(-0.8..0.8));
        let (sx, sy) = (rng.random_range(0.2..0.7), rng.random_range(0.2..0.7));
        let h = if rng.random_bool(0.3) {
            rng.random_range(1.05..1.4)
        } else {
            rng.random_range(0.1..0.8)
        };
        let clear = |p: Point2<f64>| {
            (p.x - mid.x).abs() > 0.5 * sx + 0.55 || (p.y - mid.y).abs() > 0.5 * sy + 0.55
        };
        if clear(start) && clear(goal) && (mid - column).norm() > 0.3 {
            list.push((mid.x, mid.y, sx, sy, h));
        }
    }
    (boxes(0.0, &list), start, goal)
}
