//! Built-in obstacle courses for multi-legged robots.
//!
//! A course is a terrain ([`HeightField`], world frame: X east, Y north, Z up, metres), a
//! start pose on flat ground and a goal point. Five courses are at the Ambler's scale (about
//! 28 x 14 m, 0.1 m cells, start (3, 0) facing +X, goal (23, 0)): `boulders`, `ditch`,
//! `slope`, `flat` and `rough`; two at the small hexapod's scale (about 3.5 x 1.5 m, 0.02 m
//! cells, start (0.3, 0) facing +X, goal (3.2, 0)): `hexapod-rough` and `hexapod-flat`; and `hexapod-walls` (5 x 3 m, start (0.5, 0), goal
//! (4.5, 0)), the mixed terrain with walls of Belter and Skrzypczyński's planning experiments;
//! and two for CG-space planning at the Ambler's scale (30 x 26 m): `cliff` (a plateau too
//! tall to step, a ramp to one side) and `walled-goal` (a goal no route reaches); and
//! `rock-field` (14 x 14 m, 5 cm cells) for the ATHLETE-like rover's single steps.
//! `COURSES.md` next to this crate describes each one.
//!
//! Every course is a pure function of its name and seed: the same pair always gives the
//! same heights, bit for bit (the random courses draw from ChaCha8 seeded with the seed;
//! `ditch`, `slope` and the flat courses do not depend on it). The ground around every start
//! is level (a disc of 3 m radius at the Ambler's scale, 0.3 m at the hexapod's), so a robot
//! can stand there.
//!
//! ```
//! use tca_legged_courses::{Course, NAMES};
//!
//! let course = Course::builtin("boulders", 7).unwrap();
//! assert!(course.terrain.max_height_m() <= 1.0);
//! assert_eq!((course.start.x_m, course.goal.x), (3.0, 23.0));
//! assert!(NAMES.contains(&"hexapod-rough"));
//! ```

mod ambler;
mod cliff;
mod error;
mod hexapod;
mod relief;
pub mod rocks;
pub mod walls;

#[cfg(test)]
mod tests;

use std::path::Path;

use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use tca_robot::HeightField;
use tca_robot::terrain::asc::write_height_field;

pub use error::CourseError;

/// The built-in course names, in the order of [`Course::ALL`].
pub const NAMES: &[&str] = &[
    "boulders",
    "ditch",
    "slope",
    "flat",
    "rough",
    "hexapod-rough",
    "hexapod-flat",
    "hexapod-walls",
    "cliff",
    "walled-goal",
    "rock-field",
];

/// Where and which way a robot starts on a course (world frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CourseStart {
    /// Body origin X, metres.
    pub x_m: f64,
    /// Body origin Y, metres.
    pub y_m: f64,
    /// Heading about world Z, radians (0 = facing +X).
    pub yaw_rad: f64,
}

/// A built course: its terrain, start, goal and the robot it was made for.
#[derive(Debug, Clone, PartialEq)]
pub struct LeggedCourse {
    /// The course's name (one of [`NAMES`]).
    pub name: String,
    /// The ground.
    pub terrain: HeightField,
    /// Where the robot starts; the ground around it is level.
    pub start: CourseStart,
    /// Where the robot should walk to (world XY, metres).
    pub goal: Point2<f64>,
    /// The shipped robot whose scale the course suits (`"ambler"`, `"hexapod"` or
    /// `"athlete"`).
    pub robot_hint: &'static str,
    /// The seed the course was built from.
    pub seed: u64,
}

/// One of the built-in courses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Course {
    /// Boulders up to 1.0 m high over x 5..25 m with flat footholds between them (Ambler).
    Boulders,
    /// A ditch 1 m wide and 1 m deep across the whole course at x = 12 m (Ambler).
    Ditch,
    /// A 25° ramp from x = 8 m up to a 2 m high plateau (Ambler).
    Slope,
    /// Level ground (Ambler).
    Flat,
    /// Gentle random relief of ±0.15 m (Ambler).
    Rough,
    /// Pebbles and relief of a few centimetres (hexapod).
    HexapodRough,
    /// Level ground (hexapod).
    HexapodFlat,
    /// Mixed terrain with a climbable 15 cm wall, an unclimbable 35 cm one and a steep
    /// hill to go round (hexapod, 5 x 3 m).
    HexapodWalls,
    /// A 2.5 m plateau across the way with a ramp up to it on one side (Ambler, 30 x 26 m).
    Cliff,
    /// The goal in a yard walled in by a 5 m cliff (Ambler, 30 x 26 m): unreachable.
    WalledGoal,
    /// Rocks of 8-45 cm among the wheels of the ATHLETE-like rover, level under its
    /// starting wheels (14 x 14 m, 5 cm cells).
    RockField,
}

impl Course {
    /// Every built-in course, in the order of [`NAMES`].
    pub const ALL: [Course; 11] = [
        Course::Boulders,
        Course::Ditch,
        Course::Slope,
        Course::Flat,
        Course::Rough,
        Course::HexapodRough,
        Course::HexapodFlat,
        Course::HexapodWalls,
        Course::Cliff,
        Course::WalledGoal,
        Course::RockField,
    ];

    /// The course called `name` (one of [`NAMES`]).
    pub fn from_name(name: &str) -> Result<Course, CourseError> {
        NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
            .ok_or_else(|| CourseError::UnknownCourse {
                name: name.to_owned(),
                known: NAMES.join(", "),
            })
    }

    /// The course's name.
    pub fn name(self) -> &'static str {
        let i = Self::ALL.iter().position(|c| *c == self).unwrap_or(0);
        NAMES[i]
    }

    /// Builds the built-in course `name` from `seed`.
    pub fn builtin(name: &str, seed: u64) -> Result<LeggedCourse, CourseError> {
        Self::from_name(name)?.build(seed)
    }

    /// Builds this course from `seed`.
    pub fn build(self, seed: u64) -> Result<LeggedCourse, CourseError> {
        let terrain = match self {
            Course::Boulders => ambler::boulders(seed)?,
            Course::Ditch => ambler::ditch()?,
            Course::Slope => ambler::slope()?,
            Course::Flat => ambler::flat()?,
            Course::Rough => ambler::rough(seed)?,
            Course::HexapodRough => hexapod::rough(seed)?,
            Course::HexapodFlat => hexapod::flat()?,
            Course::HexapodWalls => walls::walls(seed)?,
            Course::Cliff => cliff::cliff(seed)?,
            Course::WalledGoal => cliff::walled(seed)?,
            Course::RockField => rocks::rock_field(seed)?,
        };
        let (start, goal, robot_hint) = match self {
            Course::HexapodRough | Course::HexapodFlat => {
                (hexapod::START, hexapod::GOAL, "hexapod")
            }
            Course::HexapodWalls => (walls::START, walls::GOAL, "hexapod"),
            Course::Cliff => (cliff::CLIFF_START, cliff::CLIFF_GOAL, "ambler"),
            Course::WalledGoal => (cliff::WALLED_START, cliff::YARD_CENTRE, "ambler"),
            Course::RockField => (rocks::START, rocks::GOAL, "athlete"),
            _ => (ambler::START, ambler::GOAL, "ambler"),
        };
        Ok(LeggedCourse {
            name: self.name().to_owned(),
            terrain,
            start,
            goal: Point2::new(goal[0], goal[1]),
            robot_hint,
            seed,
        })
    }
}

impl std::str::FromStr for Course {
    type Err = CourseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::from_name(s)
    }
}

impl std::fmt::Display for Course {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Builds the course `name` from `seed` and writes its terrain to `path` as an ESRI ASCII
/// grid (`.asc`, readable by `tca_robot::terrain::asc::read_height_field`). Returns the
/// course, for its start and goal.
pub fn write_course(
    name: &str,
    seed: u64,
    path: impl AsRef<Path>,
) -> Result<LeggedCourse, CourseError> {
    let course = Course::builtin(name, seed)?;
    write_height_field(path, &course.terrain)?;
    Ok(course)
}
