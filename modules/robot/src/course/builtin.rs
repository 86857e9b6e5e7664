//! The built-in obstacle courses 1-4 of §7, laid out in the 11 x 6 m pit.
//!
//! The carriage walks along +Y from about y = 1 m to 9-10 m with the leg's column at
//! x = 3 m; the foot reaches x in about [0.5, 5.5]. Every course leaves room for a 70 cm
//! clear footfall every ~1.5 m along its length. "Right-hand side" is +X (as seen by the
//! scanner, which looks along +Y).

use nalgebra::Point2;

use super::{Course, Feature, FeatureKind};

/// Traffic cone (pylon): 18 cm base radius, 70 cm tall.
const PYLON_RADIUS_M: f64 = 0.18;
const PYLON_HEIGHT_M: f64 = 0.70;

fn boxed(name: &str, x: f64, y: f64, size_x_m: f64, size_y_m: f64, height_m: f64) -> Feature {
    Feature::new(
        name,
        FeatureKind::Box {
            center: Point2::new(x, y),
            size_x_m,
            size_y_m,
            height_m,
        },
    )
}

fn pylon(name: String, x: f64, y: f64) -> Feature {
    Feature::new(
        name,
        FeatureKind::Cone {
            center: Point2::new(x, y),
            base_radius_m: PYLON_RADIUS_M,
            height_m: PYLON_HEIGHT_M,
        },
    )
}

fn rock(name: &str, x: f64, y: f64, radius_m: f64, height_m: f64) -> Feature {
    Feature::new(
        name,
        FeatureKind::Rock {
            center: Point2::new(x, y),
            radius_m,
            height_m,
        },
    )
}

fn trench(name: &str, min: (f64, f64), max: (f64, f64), depth_m: f64, wall_m: f64) -> Feature {
    Feature::new(
        name,
        FeatureKind::Trench {
            min: Point2::new(min.0, min.1),
            max: Point2::new(max.0, max.1),
            depth_m,
            wall_m,
        },
    )
}

fn rolling(amplitude_m: f64, wavelength_m: f64, phase_rad: f64) -> Feature {
    Feature::new(
        "rolling-sand",
        FeatureKind::RollingSand {
            amplitude_m,
            wavelength_m,
            phase_rad,
        },
    )
}

/// Course 1 (Summer 1989, Figure 12): level and gently rolling sand, two trenches and a few
/// small obstacles.
pub(super) fn course_1() -> Course {
    Course {
        name: "course 1".into(),
        features: vec![
            rolling(0.05, 3.0, 0.3),
            trench("trench-1", (0.5, 3.4), (2.6, 3.9), 0.30, 0.15),
            trench("trench-2", (3.4, 6.6), (5.5, 7.1), 0.25, 0.15),
            rock("rock-1", 1.6, 2.3, 0.20, 0.15),
            rock("rock-2", 4.5, 4.6, 0.25, 0.20),
            rock("rock-3", 2.1, 8.2, 0.20, 0.15),
            boxed("box-1", 1.2, 5.6, 0.40, 0.30, 0.25),
            Feature::new(
                "cone-1",
                FeatureKind::Cone {
                    center: Point2::new(4.2, 8.9),
                    base_radius_m: 0.12,
                    height_m: 0.30,
                },
            ),
        ],
    }
}

/// Rows of the steeplechase: (y, x positions).
const STEEPLECHASE: [(f64, &[f64]); 4] = [
    (3.2, &[0.9, 2.3, 3.7, 5.1]),
    (4.8, &[1.6, 3.0, 4.4]),
    (6.4, &[0.9, 2.3, 3.7, 5.1]),
    (8.0, &[1.6, 3.0, 4.4]),
];

/// Course 2 (Autumn 1989, Figures 13-14): the steeplechase of pylons in rows across the pit
/// (the foot lands between rows and steps over them), boxes and styrofoam rocks.
pub(super) fn course_2() -> Course {
    let mut features = vec![rolling(0.02, 3.5, 0.4)];
    for (row, (y, xs)) in STEEPLECHASE.iter().enumerate() {
        for (i, &x) in xs.iter().enumerate() {
            features.push(pylon(format!("pylon-{}-{}", row + 1, i + 1), x, *y));
        }
    }
    features.extend([
        boxed("box-1", 1.3, 5.6, 0.50, 0.40, 0.40),
        boxed("box-2", 4.6, 7.2, 0.60, 0.40, 0.50),
        rock("rock-1", 2.0, 4.0, 0.25, 0.20),
        rock("rock-2", 4.3, 4.0, 0.20, 0.15),
        rock("rock-3", 2.8, 8.9, 0.30, 0.25),
        rock("rock-4", 3.6, 5.6, 0.30, 0.20),
    ]);
    Course {
        name: "course 2".into(),
        features,
    }
}

/// Course 3 (Figure 15): course 2 plus the large box ("Sun") at the beginning, taller than
/// the foot can lift (1.2 m against 1.0 m), so the leg must go around it.
pub(super) fn course_3() -> Course {
    let mut course = course_2();
    course.name = "course 3".into();
    course
        .features
        .push(boxed("sun-box", 3.3, 2.1, 0.90, 0.60, 1.20));
    course
}

/// Course 4 (Figure 17): course 3 on the right-hand side (x >= 3 m) and on the left a new
/// constellation: pylons too closely spaced for the foot, a hill of sand and a trench too
/// deep to reach the bottom (0.9 m; the foot reaches 0.5 m below the sand).
pub(super) fn course_4() -> Course {
    let mut features: Vec<Feature> = course_3()
        .features
        .into_iter()
        .filter(|f| f.footprint().is_none() || f.center().x >= 3.0)
        .collect();
    for r in 0..4 {
        for c in 0..3 {
            features.push(pylon(
                format!("dense-pylon-{}-{}", r + 1, c + 1),
                0.8 + 0.35 * c as f64,
                2.9 + 0.35 * r as f64,
            ));
        }
    }
    features.push(Feature::new(
        "sand-hill",
        FeatureKind::Hill {
            center: Point2::new(1.5, 6.0),
            radius_m: 1.1,
            height_m: 0.5,
        },
    ));
    features.push(trench("deep-trench", (0.3, 8.0), (2.8, 8.7), 0.90, 0.05));
    Course {
        name: "course 4".into(),
        features,
    }
}
