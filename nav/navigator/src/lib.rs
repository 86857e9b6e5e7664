//! Navigation on rough terrain after Chilian and Hirschmüller, "Stereo Camera Based
//! Navigation of Mobile Robots on Rough Terrain".
//!
//! Each frame of the loop ([`Navigator::step`]):
//!
//! 1. the pose is the odometry's estimate; within `goal_tolerance_m` of the goal the robot
//!    stops;
//! 2. the depth image's points, placed with the estimated pose, are inserted into the
//!    frame-aged terrain map, and the danger map is recomputed over that patch plus a
//!    robot-sized border;
//! 3. changed dangers go to D* Lite; if any changed cell is on or next to the planned
//!    path, the path is replanned (counted in [`Navigator::replans`]);
//! 4. motion control: an exploration turn (±ε around the bearing of a path cell within
//!    `map_range_m` whose certainty is below 1, under the paper's spacing rules, or of
//!    one too little known for a danger at all, once per spacing travelled), or the
//!    proportional follower toward a point ahead on the path (or the farthest path cell
//!    in line of sight).
//!
//! The navigator commands a forward and a turn speed and never learns which robot obeys
//! them ([`Base`]); [`run`] closes the loop in simulation with a depth camera, drifting
//! odometry and the true terrain for the report.

mod base;
mod courses;
mod navigator;
mod perceived;
mod picture;
mod presets;
mod run;
mod wheeled;

pub use base::{Base, Motion};
pub use courses::{Course, course_by_name, hill_course, ramps_course};
pub use navigator::{Command, NavError, NavParams, Navigator, STILL_M, STILL_RAD};
pub use perceived::{CellChange, Inserted, PerceivedMap};
pub use picture::write_picture;
pub use presets::{WHEELED_MOUNT, wheeled_params};
pub use run::{
    LastReplan, RunOptions, RunReport, run, true_danger_map, true_map_path_m, untraversable_along,
};
pub use tca_nav_danger_map::DangerParams;
pub use tca_nav_sensing::{Attitude, CameraMount, Pose2};
pub use tca_nav_terrain_map::MatchParams;
pub use wheeled::{WheeledBase, WheeledParams};
