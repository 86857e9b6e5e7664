//! `hexapod-walls`: the mixed terrain of Belter and Skrzypczyński's planning experiments
//! at the small hexapod's scale. X 0..5 m, Y -1.5..1.5 m, 0.02 m cells, start (0.5, 0)
//! facing +X, goal (4.5, 0).
//!
//! A wall 0.1 m thick across the whole width at x = 2.7..2.8 m: 0.15 m high south of
//! y = 0.4 m (the robot can climb it) and 0.35 m high north of it (it cannot). A steep
//! hill (0.45 m high, 0.4 m radius, slopes up to 60°) stands on the straight line between
//! the start and the wall, so the way goes round it and then over the low wall. Around
//! them, drawn from the seed: two wide hills with mild slopes, small sharp hills,
//! depressions, flagstones and stones, and a relief of ±1 cm. The ground is level within
//! 0.4 m of the start and the goal and within 0.4 m of the wall on either side.

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_robot::{HeightField, TerrainError};

use crate::CourseStart;
use crate::relief::{Layout, Waves, bump, normalise, start_blend};

/// Sampling layout.
pub(crate) const LAYOUT: Layout = Layout {
    origin: Point2::new(0.0, -1.5),
    cell_m: 0.02,
    nx: 251,
    ny: 151,
};

/// Start pose.
pub(crate) const START: CourseStart = CourseStart {
    x_m: 0.5,
    y_m: 0.0,
    yaw_rad: 0.0,
};

/// Goal point.
pub(crate) const GOAL: [f64; 2] = [4.5, 0.0];

/// The wall's extent along X, metres.
pub const WALL_X_M: (f64, f64) = (2.7, 2.8);
/// North of this Y the wall is high, south of it low, metres.
pub const WALL_SPLIT_Y_M: f64 = 0.4;
/// Height of the wall the robot can climb, metres.
pub const LOW_WALL_M: f64 = 0.15;
/// Height of the wall it cannot, metres.
pub const HIGH_WALL_M: f64 = 0.35;
/// Centre, radius and height of the steep hill, metres.
pub const STEEP_HILL: ([f64; 2], f64, f64) = ([1.6, 0.0], 0.4, 0.45);

/// Radius of the level ground around the start, the goal and along the wall, metres.
const CLEAR_M: f64 = 0.4;

fn protected(p: Point2<f64>, r: f64) -> bool {
    let start = Point2::new(START.x_m, START.y_m);
    let goal = Point2::new(GOAL[0], GOAL[1]);
    let (hill, hr, _) = STEEP_HILL;
    (p - start).norm() < CLEAR_M + r
        || (p - goal).norm() < CLEAR_M + r
        || (p.x > WALL_X_M.0 - CLEAR_M - r && p.x < WALL_X_M.1 + CLEAR_M + r)
        || (p - Point2::new(hill[0], hill[1])).norm() < hr + r
}

/// What a body path across `hexapod-walls` does at the course's landmarks.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallsChecks {
    /// The path crosses (or stands on) the wall south of [`WALL_SPLIT_Y_M`]: the 15 cm one.
    pub over_low_wall: bool,
    /// The path crosses (or stands on) the wall north of it: the 35 cm one.
    pub over_high_wall: bool,
    /// The least horizontal distance from the path to the steep hill's top, metres.
    pub nearest_to_hill_m: f64,
}

impl WallsChecks {
    /// Checks a body path, world `[x, y]` in metres, point by point (segments between
    /// consecutive points count as crossed).
    pub fn of_path(path: &[[f64; 2]]) -> WallsChecks {
        let (mut low, mut high) = (false, false);
        let (x0, x1) = WALL_X_M;
        for w in path.windows(2) {
            let (a, b) = (w[0], w[1]);
            let on_or_across = (a[0] < x1 && b[0] >= x0) || (b[0] < x1 && a[0] >= x0);
            if on_or_across {
                if a[1].max(b[1]) >= WALL_SPLIT_Y_M {
                    high = true;
                } else {
                    low = true;
                }
            }
        }
        let ([hx, hy], _, _) = STEEP_HILL;
        let nearest = path
            .iter()
            .map(|p| (p[0] - hx).hypot(p[1] - hy))
            .fold(f64::INFINITY, f64::min);
        WallsChecks {
            over_low_wall: low,
            over_high_wall: high,
            nearest_to_hill_m: nearest,
        }
    }

    /// Whether the path does what the course asks: over the low wall, never over the
    /// high one, and round the steep hill (never over its top half, within its radius).
    pub fn as_intended(&self) -> bool {
        let (_, radius, _) = STEEP_HILL;
        self.over_low_wall && !self.over_high_wall && self.nearest_to_hill_m > radius
    }

    /// For people.
    pub fn describe(&self) -> String {
        let yes = |b: bool| if b { "yes" } else { "no" };
        format!(
            "crosses the 15 cm wall: {}, the 35 cm wall: {}, nearest the steep hill's top {:.2} m",
            yes(self.over_low_wall),
            yes(self.over_high_wall),
            self.nearest_to_hill_m
        )
    }
}

/// Builds the course from `seed`.
pub(crate) fn walls(seed: u64) -> Result<HeightField, TerrainError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5741_4c4c_5352_5254);
    let n = LAYOUT.nx * LAYOUT.ny;
    let node = |i: usize| LAYOUT.node(i % LAYOUT.nx, i / LAYOUT.nx);
    // Relief of ±1 cm, faded out over the level places.
    let waves = Waves::new(&mut rng, 10, 0.3, 1.5);
    let mut relief: Vec<f64> = (0..n).map(|i| waves.at(node(i))).collect();
    normalise(&mut relief, 0.01);
    let mut h: Vec<f64> = (0..n)
        .map(|i| {
            let p = node(i);
            let d = clear_distance(p);
            relief[i] * start_blend(d, 0.0, 0.15)
        })
        .collect();
    // Features: (centre, radius, height) of raised-cosine domes (negative: depressions),
    // cones, and flat-topped flagstones.
    let add_dome = |h: &mut Vec<f64>, c: Point2<f64>, r: f64, height: f64| {
        for (i, v) in h.iter_mut().enumerate() {
            let d = (node(i) - c).norm() / r;
            if d < 1.0 {
                *v += height * bump(d);
            }
        }
    };
    let (hill, hr, hh) = STEEP_HILL;
    add_dome(&mut h, Point2::new(hill[0], hill[1]), hr, hh);
    let draw = |rng: &mut ChaCha8Rng, r: f64| -> Option<Point2<f64>> {
        for _ in 0..50 {
            let p = Point2::new(rng.random_range(0.3..4.7), rng.random_range(-1.2..1.2));
            if !protected(p, r) {
                return Some(p);
            }
        }
        None
    };
    // Two wide hills with mild slopes (at most about 17°).
    for _ in 0..2 {
        let r = rng.random_range(0.5..0.7);
        let height = rng.random_range(0.08..0.12);
        if let Some(c) = draw(&mut rng, r) {
            add_dome(&mut h, c, r, height);
        }
    }
    // Depressions.
    for _ in 0..4 {
        let r = rng.random_range(0.15..0.3);
        let depth = rng.random_range(0.03..0.07);
        if let Some(c) = draw(&mut rng, r) {
            add_dome(&mut h, c, r, -depth);
        }
    }
    // Small sharp hills: cones.
    for _ in 0..8 {
        let r = rng.random_range(0.05..0.1);
        let height = rng.random_range(0.04..0.08);
        if let Some(c) = draw(&mut rng, r) {
            for (i, v) in h.iter_mut().enumerate() {
                let d = (node(i) - c).norm() / r;
                if d < 1.0 {
                    *v += height * (1.0 - d);
                }
            }
        }
    }
    // Flagstones: flat-topped slabs 2-4 cm thick.
    for _ in 0..12 {
        let (a, b): (f64, f64) = (rng.random_range(0.12..0.3), rng.random_range(0.12..0.3));
        let top = rng.random_range(0.02..0.04);
        if let Some(c) = draw(&mut rng, a.max(b)) {
            for (i, v) in h.iter_mut().enumerate() {
                let p = node(i);
                if (p.x - c.x).abs() <= a / 2.0 && (p.y - c.y).abs() <= b / 2.0 {
                    *v = v.max(top);
                }
            }
        }
    }
    // Stones.
    for _ in 0..40 {
        let r = rng.random_range(0.02..0.05);
        let height = rng.random_range(0.01..0.04_f64).min(r);
        if let Some(c) = draw(&mut rng, r) {
            add_dome(&mut h, c, r, height);
        }
    }
    // The wall, last, on level ground.
    for (i, v) in h.iter_mut().enumerate() {
        let p = node(i);
        if p.x >= WALL_X_M.0 - 1e-9 && p.x <= WALL_X_M.1 + 1e-9 {
            *v = if p.y >= WALL_SPLIT_Y_M {
                HIGH_WALL_M
            } else {
                LOW_WALL_M
            };
        }
    }
    HeightField::new(LAYOUT.origin, LAYOUT.cell_m, LAYOUT.nx, LAYOUT.ny, h)
}

/// Distance from a point to the nearest level place (start, goal, the band along the
/// wall), zero inside one.
fn clear_distance(p: Point2<f64>) -> f64 {
    let start = Point2::new(START.x_m, START.y_m);
    let goal = Point2::new(GOAL[0], GOAL[1]);
    let ds = ((p - start).norm() - CLEAR_M).max(0.0);
    let dg = ((p - goal).norm() - CLEAR_M).max(0.0);
    let dw = if p.x < WALL_X_M.0 - CLEAR_M {
        WALL_X_M.0 - CLEAR_M - p.x
    } else if p.x > WALL_X_M.1 + CLEAR_M {
        p.x - WALL_X_M.1 - CLEAR_M
    } else {
        0.0
    };
    ds.min(dg).min(dw)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Course;

    #[test]
    fn walls_hill_and_level_places_are_where_the_docs_say() {
        for seed in [1, 2, 3] {
            let c = Course::builtin("hexapod-walls", seed).unwrap();
            let t = &c.terrain;
            let (lo, hi) = t.extent();
            assert!((hi.x - lo.x - 5.0).abs() < 1e-9 && (hi.y - lo.y - 3.0).abs() < 1e-9);
            assert_eq!(c.start, START);
            assert_eq!(c.robot_hint, "hexapod");
            assert!((t.height_at(2.75, 0.0) - LOW_WALL_M).abs() < 1e-9);
            assert!((t.height_at(2.75, -1.4) - LOW_WALL_M).abs() < 1e-9);
            assert!((t.height_at(2.75, 1.0) - HIGH_WALL_M).abs() < 1e-9);
            assert!((t.height_at(2.75, 1.5) - HIGH_WALL_M).abs() < 1e-9);
            let (hill, _, hh) = STEEP_HILL;
            assert!(t.height_at(hill[0], hill[1]) >= hh - 0.02);
            // Level around the start, the goal and in front of the wall.
            for p in [
                (0.5, 0.0),
                (0.8, 0.1),
                (4.5, 0.0),
                (4.2, -0.1),
                (2.4, 0.0),
                (3.1, -0.5),
            ] {
                assert!(t.height_at(p.0, p.1).abs() < 1e-9, "{p:?} seed {seed}");
            }
        }
        let a = Course::builtin("hexapod-walls", 1).unwrap();
        let b = Course::builtin("hexapod-walls", 2).unwrap();
        assert_ne!(a.terrain.grid().cells(), b.terrain.grid().cells());
    }

    #[test]
    fn the_shipped_asc_is_seed_one() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/data/hexapod-walls-1.asc");
        let back = tca_robot::terrain::asc::read_height_field(
            path,
            tca_robot::terrain::asc::NoData::Refuse,
        )
        .unwrap();
        let built = Course::builtin("hexapod-walls", 1).unwrap();
        assert_eq!(back.grid().nx(), built.terrain.grid().nx());
        for (a, b) in back.grid().cells().iter().zip(built.terrain.grid().cells()) {
            assert!((a - b).abs() < 1e-9);
        }
    }
}
