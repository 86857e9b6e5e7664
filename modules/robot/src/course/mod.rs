//! Obstacle courses in the 11 x 6 m test pit: lists of primitive features rendered into a
//! height field.
//!
//! Sand features (rolling sand, hills, trenches) shape the sand surface; objects (boxes,
//! cones, rocks) rest on the sand at their centre. The feature list is public so that tests
//! and tools can ask where things are ("where is the big box").

mod builtin;
mod random;

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::terrain::{HeightField, TerrainError, samples_covering};

pub use random::RandomCourseOptions;

/// Size of the test pit along world X (across), metres.
pub const PIT_SIZE_X_M: f64 = 6.0;
/// Size of the test pit along world Y (along the rails), metres.
pub const PIT_SIZE_Y_M: f64 = 11.0;
/// Resolution at which courses are rendered by default, metres.
pub const DEFAULT_RESOLUTION_M: f64 = 0.02;

/// The shape of one terrain feature. Positions are world XY, metres; heights are above the
/// sand under the feature's centre (objects) or relative to the nominal sand (sand features).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FeatureKind {
    /// An axis-aligned box resting on the sand.
    Box {
        /// Centre of the footprint.
        center: Point2<f64>,
        /// Side along X, metres.
        size_x_m: f64,
        /// Side along Y, metres.
        size_y_m: f64,
        /// Height above the sand, metres.
        height_m: f64,
    },
    /// A traffic cone (pylon): a pointed cone standing on the sand.
    Cone {
        /// Centre of the base.
        center: Point2<f64>,
        /// Radius of the base, metres.
        base_radius_m: f64,
        /// Height, metres.
        height_m: f64,
    },
    /// A styrofoam rock: a smooth raised-cosine bump on the sand.
    Rock {
        /// Centre.
        center: Point2<f64>,
        /// Radius of the footprint, metres.
        radius_m: f64,
        /// Height, metres.
        height_m: f64,
    },
    /// A trench dug into the sand: an axis-aligned opening whose walls slope down over
    /// `wall_m` to a flat floor `depth_m` below the surrounding sand.
    Trench {
        /// Lower corner of the opening.
        min: Point2<f64>,
        /// Upper corner of the opening.
        max: Point2<f64>,
        /// Depth of the floor, metres.
        depth_m: f64,
        /// Horizontal run of each wall, metres.
        wall_m: f64,
    },
    /// A hill of sand: a raised-cosine bump added to the sand surface.
    Hill {
        /// Centre.
        center: Point2<f64>,
        /// Radius of the footprint, metres.
        radius_m: f64,
        /// Height, metres.
        height_m: f64,
    },
    /// Gently rolling sand over the whole pit:
    /// `amplitude * (sin(2 pi x / wavelength + phase) + sin(2 pi y / (1.3 wavelength) + 2 phase)) / 2`.
    RollingSand {
        /// Amplitude, metres.
        amplitude_m: f64,
        /// Wavelength along X, metres.
        wavelength_m: f64,
        /// Phase, radians.
        phase_rad: f64,
    },
}

/// A named terrain feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Feature {
    /// Name, unique within its course (e.g. `"sun-box"`, `"pylon-2-3"`).
    pub name: String,
    /// Shape and placement.
    pub kind: FeatureKind,
}

impl Feature {
    /// A named feature.
    pub fn new(name: impl Into<String>, kind: FeatureKind) -> Self {
        Self {
            name: name.into(),
            kind,
        }
    }

    /// The XY rectangle (min, max) the feature changes, or `None` for features covering
    /// the whole pit (rolling sand).
    pub fn footprint(&self) -> Option<(Point2<f64>, Point2<f64>)> {
        let around = |c: &Point2<f64>, rx: f64, ry: f64| {
            Some((
                Point2::new(c.x - rx, c.y - ry),
                Point2::new(c.x + rx, c.y + ry),
            ))
        };
        match &self.kind {
            FeatureKind::Box {
                center,
                size_x_m,
                size_y_m,
                ..
            } => around(center, 0.5 * size_x_m, 0.5 * size_y_m),
            FeatureKind::Cone {
                center,
                base_radius_m: r,
                ..
            }
            | FeatureKind::Rock {
                center,
                radius_m: r,
                ..
            }
            | FeatureKind::Hill {
                center,
                radius_m: r,
                ..
            } => around(center, *r, *r),
            FeatureKind::Trench { min, max, .. } => Some((*min, *max)),
            FeatureKind::RollingSand { .. } => None,
        }
    }

    /// Centre of the feature's footprint (the pit's centre for rolling sand).
    pub fn center(&self) -> Point2<f64> {
        match self.footprint() {
            Some((lo, hi)) => nalgebra::center(&lo, &hi),
            None => Point2::new(0.5 * PIT_SIZE_X_M, 0.5 * PIT_SIZE_Y_M),
        }
    }

    /// Whether the feature's footprint contains the XY point.
    pub fn contains(&self, p: Point2<f64>) -> bool {
        self.footprint()
            .is_none_or(|(lo, hi)| p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y)
    }

    /// Whether the feature is an object resting on the sand (box, cone, rock).
    pub fn is_object(&self) -> bool {
        matches!(
            self.kind,
            FeatureKind::Box { .. } | FeatureKind::Cone { .. } | FeatureKind::Rock { .. }
        )
    }

    /// Change of the sand surface at `p` (sand features only; zero for objects).
    fn sand_offset(&self, p: Point2<f64>) -> f64 {
        match &self.kind {
            FeatureKind::RollingSand {
                amplitude_m,
                wavelength_m,
                phase_rad,
            } => {
                let k = std::f64::consts::TAU / wavelength_m;
                amplitude_m
                    * 0.5
                    * ((k * p.x + phase_rad).sin() + (k / 1.3 * p.y + 2.0 * phase_rad).sin())
            }
            FeatureKind::Hill {
                center,
                radius_m,
                height_m,
            } => height_m * bump((p - center).norm() / radius_m),
            FeatureKind::Trench {
                min,
                max,
                depth_m,
                wall_m,
            } => {
                let inside = (p.x - min.x)
                    .min(max.x - p.x)
                    .min(p.y - min.y)
                    .min(max.y - p.y);
                if inside <= 0.0 {
                    0.0
                } else if *wall_m <= 0.0 {
                    -depth_m
                } else {
                    -depth_m * (inside / wall_m).min(1.0)
                }
            }
            _ => 0.0,
        }
    }

    /// Height of an object's surface above its base at `p`, or `None` outside it.
    fn object_height(&self, p: Point2<f64>) -> Option<f64> {
        match &self.kind {
            FeatureKind::Box {
                center,
                size_x_m,
                size_y_m,
                height_m,
            } => ((p.x - center.x).abs() <= 0.5 * size_x_m
                && (p.y - center.y).abs() <= 0.5 * size_y_m)
                .then_some(*height_m),
            FeatureKind::Cone {
                center,
                base_radius_m,
                height_m,
            } => {
                let d = (p - center).norm() / base_radius_m;
                (d <= 1.0).then(|| height_m * (1.0 - d))
            }
            FeatureKind::Rock {
                center,
                radius_m,
                height_m,
            } => {
                let d = (p - center).norm() / radius_m;
                (d <= 1.0).then(|| height_m * bump(d))
            }
            _ => None,
        }
    }
}

/// Raised cosine: 1 at 0, 0 at 1 and beyond, smooth.
fn bump(d: f64) -> f64 {
    if d >= 1.0 {
        0.0
    } else {
        0.5 + 0.5 * (std::f64::consts::PI * d).cos()
    }
}

/// Why a course could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CourseError {
    /// No such built-in course.
    #[error("there is no built-in obstacle course {0}; the built-in courses are 1, 2, 3 and 4")]
    UnknownCourse(u32),
    /// Rendering failed (bad resolution).
    #[error(transparent)]
    Terrain(#[from] TerrainError),
}

/// An obstacle course: named features in the test pit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Course {
    /// Name, e.g. `"course 3"` or `"random 42"`.
    pub name: String,
    /// The features.
    pub features: Vec<Feature>,
}

impl Course {
    /// Built-in obstacle course 1, 2, 3 or 4 (§7).
    pub fn builtin(number: u32) -> Result<Self, CourseError> {
        match number {
            1 => Ok(builtin::course_1()),
            2 => Ok(builtin::course_2()),
            3 => Ok(builtin::course_3()),
            4 => Ok(builtin::course_4()),
            other => Err(CourseError::UnknownCourse(other)),
        }
    }

    /// A random course from a seed, with default options (see [`RandomCourseOptions`]).
    pub fn random(seed: u64) -> Self {
        random::generate(seed, &RandomCourseOptions::default())
    }

    /// A random course from a seed and options.
    pub fn random_with(seed: u64, options: &RandomCourseOptions) -> Self {
        random::generate(seed, options)
    }

    /// The feature with this name.
    pub fn feature(&self, name: &str) -> Option<&Feature> {
        self.features.iter().find(|f| f.name == name)
    }

    /// The features whose names start with `prefix` (e.g. `"pylon-"`).
    pub fn features_named(&self, prefix: &str) -> impl Iterator<Item = &Feature> + '_ {
        let prefix = prefix.to_owned();
        self.features
            .iter()
            .filter(move |f| f.name.starts_with(&prefix))
    }

    /// Height of the sand surface (without objects) at `p`, metres.
    pub fn sand_height_at(&self, p: Point2<f64>) -> f64 {
        self.features
            .iter()
            .filter(|f| !f.is_object())
            .map(|f| f.sand_offset(p))
            .sum()
    }

    /// The course rendered at [`DEFAULT_RESOLUTION_M`] (2 cm) over the whole pit. Fails only
    /// if a feature has a non-finite size or height.
    pub fn height_field(&self) -> Result<HeightField, TerrainError> {
        self.render(DEFAULT_RESOLUTION_M)
    }

    /// The course rendered over the whole pit with samples every `resolution_m`.
    pub fn render(&self, resolution_m: f64) -> Result<HeightField, TerrainError> {
        let min = Point2::origin();
        let (nx, ny) =
            samples_covering(min, Point2::new(PIT_SIZE_X_M, PIT_SIZE_Y_M), resolution_m)?;
        let node =
            |ix: usize, iy: usize| Point2::new(ix as f64 * resolution_m, iy as f64 * resolution_m);
        let mut heights = vec![0.0; nx * ny];
        let index_range = |lo: f64, hi: f64, n: usize| {
            let a = (lo / resolution_m).floor().max(0.0) as usize;
            let b = ((hi / resolution_m).ceil().max(0.0) as usize).min(n - 1);
            a..=b
        };
        // Sand first, then objects resting on it.
        for f in self.features.iter().filter(|f| !f.is_object()) {
            match f.footprint() {
                None => {
                    for (i, h) in heights.iter_mut().enumerate() {
                        *h += f.sand_offset(node(i % nx, i / nx));
                    }
                }
                Some((lo, hi)) => {
                    for iy in index_range(lo.y, hi.y, ny) {
                        for ix in index_range(lo.x, hi.x, nx) {
                            if let Some(h) = heights.get_mut(iy * nx + ix) {
                                *h += f.sand_offset(node(ix, iy));
                            }
                        }
                    }
                }
            }
        }
        for f in self.features.iter().filter(|f| f.is_object()) {
            let base = self.sand_height_at(f.center());
            if let Some((lo, hi)) = f.footprint() {
                for iy in index_range(lo.y, hi.y, ny) {
                    for ix in index_range(lo.x, hi.x, nx) {
                        if let (Some(top), Some(h)) =
                            (f.object_height(node(ix, iy)), heights.get_mut(iy * nx + ix))
                        {
                            *h = h.max(base + top);
                        }
                    }
                }
            }
        }
        HeightField::new(min, resolution_m, nx, ny, heights)
    }
}

#[cfg(test)]
mod tests;
