//! Random obstacle courses from a seed.
//!
//! A random course first reserves a clear footfall region (a 50 cm radius disc) every
//! ~1.3 m along the walk, at a random X, then scatters features that keep out of those
//! discs and do not overlap each other. So any seed gives a course a sensible planner can
//! walk, and the same seed always gives the same course.

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{Course, Feature, FeatureKind, PIT_SIZE_X_M};

/// Options of a random course.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomCourseOptions {
    /// Number of objects (boxes, cones, rocks) to try to place.
    pub objects: usize,
    /// Largest number of trenches.
    pub max_trenches: usize,
    /// Largest number of sand hills.
    pub max_hills: usize,
    /// Tallest object, metres (keep it under 1 m so the leg can lift over everything, or
    /// above to make the leg go around).
    pub max_object_height_m: f64,
    /// Deepest trench, metres.
    pub max_trench_depth_m: f64,
    /// Largest amplitude of the rolling sand, metres.
    pub max_rolling_amplitude_m: f64,
}

impl Default for RandomCourseOptions {
    fn default() -> Self {
        Self {
            objects: 14,
            max_trenches: 2,
            max_hills: 1,
            max_object_height_m: 0.8,
            max_trench_depth_m: 0.8,
            max_rolling_amplitude_m: 0.04,
        }
    }
}

/// Radius of the reserved footfall discs, metres.
const RESERVED_RADIUS_M: f64 = 0.5;
/// Y of the first reserved footfall and the spacing between them, metres.
const FIRST_FOOTFALL_Y_M: f64 = 2.2;
const FOOTFALL_SPACING_M: f64 = 1.3;
const FOOTFALLS: usize = 7;

pub(super) fn generate(seed: u64, options: &RandomCourseOptions) -> Course {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut features = Vec::new();
    let amplitude = rng.random_range(0.0..=options.max_rolling_amplitude_m.max(0.0));
    features.push(Feature::new(
        "rolling-sand",
        FeatureKind::RollingSand {
            amplitude_m: amplitude,
            wavelength_m: rng.random_range(2.0..4.0),
            phase_rad: rng.random_range(0.0..std::f64::consts::TAU),
        },
    ));
    let reserved: Vec<Point2<f64>> = (0..FOOTFALLS)
        .map(|k| {
            Point2::new(
                rng.random_range(1.0..PIT_SIZE_X_M - 1.0),
                FIRST_FOOTFALL_Y_M + FOOTFALL_SPACING_M * k as f64 + rng.random_range(-0.2..0.2),
            )
        })
        .collect();
    let mut placed: Vec<(Point2<f64>, Point2<f64>)> = Vec::new();
    let mut try_place = |feature: Feature, features: &mut Vec<Feature>| {
        let Some((lo, hi)) = feature.footprint() else {
            return;
        };
        let margin = 0.05;
        let (lo, hi) = (
            Point2::new(lo.x - margin, lo.y - margin),
            Point2::new(hi.x + margin, hi.y + margin),
        );
        let inside_pit = lo.x >= 0.1 && lo.y >= 1.6 && hi.x <= PIT_SIZE_X_M - 0.1 && hi.y <= 10.8;
        let clear_of_footfalls = reserved
            .iter()
            .all(|c| rect_disc_distance(lo, hi, *c) > RESERVED_RADIUS_M);
        let clear_of_others = placed
            .iter()
            .all(|(a, b)| lo.x > b.x || hi.x < a.x || lo.y > b.y || hi.y < a.y);
        if inside_pit && clear_of_footfalls && clear_of_others {
            placed.push((lo, hi));
            features.push(feature);
        }
    };
    let attempts = 60;
    let trenches = rng.random_range(0..=options.max_trenches);
    for i in 0..trenches {
        for _ in 0..attempts {
            let (len, width) = (rng.random_range(0.8..2.5), rng.random_range(0.3..0.6));
            let (x, y) = (
                rng.random_range(0.2..PIT_SIZE_X_M - 0.2 - len),
                rng.random_range(2.0..10.0),
            );
            let depth = rng.random_range(0.1..=options.max_trench_depth_m.max(0.1));
            let before = features.len();
            try_place(
                Feature::new(
                    format!("trench-{}", i + 1),
                    FeatureKind::Trench {
                        min: Point2::new(x, y),
                        max: Point2::new(x + len, y + width),
                        depth_m: depth,
                        wall_m: rng.random_range(0.05..0.2),
                    },
                ),
                &mut features,
            );
            if features.len() > before {
                break;
            }
        }
    }
    let hills = rng.random_range(0..=options.max_hills);
    for i in 0..hills {
        for _ in 0..attempts {
            let r = rng.random_range(0.5..1.1);
            let before = features.len();
            try_place(
                Feature::new(
                    format!("hill-{}", i + 1),
                    FeatureKind::Hill {
                        center: Point2::new(
                            rng.random_range(0.5..5.5),
                            rng.random_range(2.0..10.0),
                        ),
                        radius_m: r,
                        height_m: rng.random_range(0.1..0.4),
                    },
                ),
                &mut features,
            );
            if features.len() > before {
                break;
            }
        }
    }
    let max_h = options.max_object_height_m.max(0.1);
    for i in 0..options.objects {
        for _ in 0..attempts {
            let center = Point2::new(rng.random_range(0.3..5.7), rng.random_range(1.8..10.6));
            let pick: f64 = rng.random();
            let kind = if pick < 0.35 {
                FeatureKind::Cone {
                    center,
                    base_radius_m: rng.random_range(0.12..0.2),
                    height_m: rng.random_range(0.3..=max_h.max(0.3)),
                }
            } else if pick < 0.65 {
                FeatureKind::Rock {
                    center,
                    radius_m: rng.random_range(0.15..0.35),
                    height_m: rng.random_range(0.08..=0.3_f64.min(max_h).max(0.08)),
                }
            } else {
                FeatureKind::Box {
                    center,
                    size_x_m: rng.random_range(0.3..0.8),
                    size_y_m: rng.random_range(0.3..0.8),
                    height_m: rng.random_range(0.15..=max_h.max(0.15)),
                }
            };
            let name = match kind {
                FeatureKind::Cone { .. } => format!("cone-{}", i + 1),
                FeatureKind::Rock { .. } => format!("rock-{}", i + 1),
                _ => format!("box-{}", i + 1),
            };
            let before = features.len();
            try_place(Feature::new(name, kind), &mut features);
            if features.len() > before {
                break;
            }
        }
    }
    Course {
        name: format!("random {seed}"),
        features,
    }
}

/// Distance from a point to an axis-aligned rectangle (0 inside).
fn rect_disc_distance(lo: Point2<f64>, hi: Point2<f64>, c: Point2<f64>) -> f64 {
    let dx = (lo.x - c.x).max(0.0).max(c.x - hi.x);
    let dy = (lo.y - c.y).max(0.0).max(c.y - hi.y);
    (dx * dx + dy * dy).sqrt()
}
