//! The ground a legged walk happens on: a built-in course or a terrain file, and the checks
//! on where the robot starts and where it is sent.

use std::path::PathBuf;

use anyhow::Context as _;
use nalgebra::Point2;
use tca_legged_courses::Course;
use tca_legged_model::RobotModel;
use tca_robot::HeightField;

/// Which terrain.
#[derive(Clone, Debug, PartialEq)]
pub enum LeggedTerrain {
    /// A built-in course, by name and seed.
    Course {
        /// The course's name (`tca course list`).
        name: String,
        /// Its seed.
        seed: u64,
    },
    /// An ESRI ASCII grid (`.asc`).
    File(PathBuf),
}

/// A terrain loaded, with the start and goal it suggests (a course's own).
#[derive(Clone, Debug)]
pub struct LoadedTerrain {
    /// The height field.
    pub field: HeightField,
    /// A course's start `[x, y, yaw]`, if a course.
    pub start: Option<[f64; 3]>,
    /// A course's goal, if a course.
    pub goal: Option<Point2<f64>>,
    /// For people.
    pub describe: String,
}

impl LeggedTerrain {
    /// The course a robot walks when none is given: its own scale's rough ground.
    pub fn default_for(model: &RobotModel, seed: u64) -> Self {
        let name = if max_reach(model) < 0.6 {
            "hexapod-rough"
        } else {
            "rough"
        };
        LeggedTerrain::Course {
            name: name.into(),
            seed,
        }
    }

    /// Loads it; an unknown course or an unreadable file says what to do.
    pub fn load(&self) -> anyhow::Result<LoadedTerrain> {
        match self {
            LeggedTerrain::Course { name, seed } => {
                let c = Course::builtin(name, *seed).map_err(|e| anyhow::anyhow!("{e}"))?;
                Ok(LoadedTerrain {
                    describe: format!("course {name} (seed {seed})"),
                    start: Some([c.start.x_m, c.start.y_m, c.start.yaw_rad]),
                    goal: Some(c.goal),
                    field: c.terrain,
                })
            }
            LeggedTerrain::File(path) => {
                let field = tca_robot::terrain::asc::read_height_field(path, tca_robot::terrain::asc::NoData::Refuse)
                    .with_context(|| {
                        format!(
                            "cannot use {} as a terrain; give an ESRI ASCII grid (.asc) of heights in metres",
                            path.display()
                        )
                    })?;
                Ok(LoadedTerrain {
                    describe: format!("terrain {}", path.display()),
                    start: None,
                    goal: None,
                    field,
                })
            }
        }
    }
}

/// Refuses a place (start or goal) where the robot would not fit on the terrain: not a
/// number, or with a foot of the neutral stance, the body turned to `yaw_rad`, off the
/// terrain's edge.
pub fn check_place(
    what: &str,
    p: Point2<f64>,
    yaw_rad: f64,
    terrain: &HeightField,
    model: &RobotModel,
) -> anyhow::Result<()> {
    let (lo, hi) = terrain.extent();
    if !(p.x.is_finite() && p.y.is_finite() && yaw_rad.is_finite()) {
        anyhow::bail!(
            "the {what} ({}, {}) facing {yaw_rad} rad is not a place; give X,Y in metres (and a yaw in radians)",
            p.x,
            p.y
        );
    }
    let (s, c) = yaw_rad.sin_cos();
    let feet = model
        .foot_positions(&model.neutral_posture())
        .unwrap_or_default();
    for (f, leg) in feet.iter().zip(model.legs()) {
        let r = leg.foot_radius();
        let (x, y) = (p.x + c * f.x - s * f.y, p.y + s * f.x + c * f.y);
        if x - r < lo.x || x + r > hi.x || y - r < lo.y || y + r > hi.y {
            anyhow::bail!(
                "the {what} ({:.2}, {:.2}) is too near the edge of the terrain, which spans X {:.2}..{:.2} m and Y {:.2}..{:.2} m: standing there facing {:.0}°, foot {} would be at ({x:.2}, {y:.2}), off the terrain; give a {what} farther inside",
                p.x,
                p.y,
                lo.x,
                hi.x,
                lo.y,
                hi.y,
                yaw_rad.to_degrees(),
                leg.name()
            );
        }
    }
    Ok(())
}

/// How far the robot's standing feet reach from the body's origin, horizontally, metres:
/// the farthest foot in the neutral posture, plus its contact radius.
pub fn footprint_radius(model: &RobotModel) -> f64 {
    let feet = model
        .foot_positions(&model.neutral_posture())
        .unwrap_or_default();
    feet.iter()
        .zip(model.legs())
        .map(|(f, leg)| f.x.hypot(f.y) + leg.foot_radius())
        .fold(0.0, f64::max)
}

/// The longest leg's reach bound, metres.
pub fn max_reach(model: &RobotModel) -> f64 {
    model
        .legs()
        .iter()
        .map(|l| l.reach_bound())
        .fold(0.0, f64::max)
}
