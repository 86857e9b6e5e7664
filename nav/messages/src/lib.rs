//! The vocabulary of stereo-camera navigation on rough terrain: what the navigator, the
//! ISM (depth camera and visual odometry), the LTM Manager (terrain and danger maps) and a
//! base's Controller say to each other.
//!
//! Every name is in the `nav.` namespace. SI units and radians; the world frame has X east,
//! Y north, Z up, and a planar pose is `[x, y, yaw]` with the yaw from east toward north.
//!
//! | name | class | from → to |
//! | --- | --- | --- |
//! | `nav.drive` | query → [`Driven`] | navigator → Controller: forward and turn speeds held for a while |
//! | `nav.truePose` | query → [`PlanarPose`] | simulated sensors → simulated Controller (the simulation's truth; the navigator never asks) |
//! | `nav.simStatus` | query → [`SimStatusReply`] | the run's judge → simulated Controller: true poses, distance, collisions, falls |
//! | `nav.acquireDepth` | query → [`DepthFrame`] | navigator → ISM: a depth image and the odometry's estimate |
//! | `nav.insertDepth` | query → [`DangerChanges`] | navigator → LTM Manager: a frame into the maps, the cells whose danger changed |
//! | `nav.dangerMap` | query → [`DangerGrid`] | anyone → LTM Manager: the whole danger map |
//! | `nav.navigate` | goal | user → navigator: drive to a goal given relative to the start |
//! | `nav.frame` | inform | navigator → whoever listens: one frame's estimate, plan and command |

use serde::{Deserialize, Serialize};
use tca_messages::message;

/// A planar pose: position, m, and heading, rad (from east toward north).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
pub struct PlanarPose {
    /// East, m.
    pub x_m: f64,
    /// North, m.
    pub y_m: f64,
    /// Heading, rad.
    pub yaw_rad: f64,
}

/// Query: drive at these speeds for `duration_s` (a frame).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Drive {
    /// Forward speed, m/s.
    pub forward_mps: f64,
    /// Turn speed, rad/s (positive to the left).
    pub turn_rps: f64,
    /// How long the speeds hold, s.
    pub duration_s: f64,
}
message!(Drive: query "nav.drive" -> Driven);

/// The answer to [`Drive`]: what happened (the pose is not told: the navigator knows only
/// its odometry).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Driven {
    /// The base met something it could not cross and stayed where it was.
    pub collided: bool,
    /// The base tipped over.
    pub fell: bool,
}

/// Query: the base's true pose. Only simulated sensors ask it (a simulated camera must be
/// placed where the base really is); a navigator never does.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruePose;
message!(TruePose: query "nav.truePose" -> PlanarPose);

/// Query: the simulated base's record so far (the simulation's truth, for judging a run).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimStatus;
message!(SimStatus: query "nav.simStatus" -> SimStatusReply);

/// The answer to [`SimStatus`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimStatusReply {
    /// The true pose now.
    pub pose: PlanarPose,
    /// The true pose at the start of every drive, in order.
    pub poses: Vec<PlanarPose>,
    /// True distance travelled, m.
    pub distance_m: f64,
    /// Drives blocked by a step the base cannot climb.
    pub collisions: u64,
    /// Drives in which the base tipped over.
    pub falls: u64,
}

/// Query: take one depth image now.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AcquireDepth;
message!(AcquireDepth: query "nav.acquireDepth" -> DepthFrame);

/// A depth image with the pose the odometry estimates it was taken from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DepthFrame {
    /// Frames taken before this one.
    pub frame: u64,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Row-major depths along the optical axis, m; 0 where a pixel has no depth (no texture,
    /// no return).
    pub depth_m: Vec<f32>,
    /// The odometry's estimate of the base's pose when the image was taken.
    pub estimate: PlanarPose,
    /// Height of the base's reference point, m: the ground under a wheeled base's centre,
    /// a legged robot's body origin (height and tilt are measured; drift is planar).
    pub base_z_m: f64,
    /// Roll of the base, rad (0 for a base whose camera is stabilised).
    pub base_roll_rad: f64,
    /// Pitch of the base, rad (positive nose down).
    pub base_pitch_rad: f64,
}

/// Query: put a depth frame into the terrain map and recompute the danger of what it saw.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InsertDepth {
    /// The frame.
    pub frame: DepthFrame,
}
message!(InsertDepth: query "nav.insertDepth" -> DangerChanges);

/// One cell's danger as the LTM Manager assesses it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellDangerMsg {
    /// Column.
    pub ix: u32,
    /// Row.
    pub iy: u32,
    /// Danger in `[0, 1]` (1 where unknown); `None` where the cell cannot be crossed.
    pub danger: Option<f64>,
    /// The known fraction of the robot's circle around the cell, `[0, 1]`.
    pub certainty: f64,
}

/// The answer to [`InsertDepth`]: the cells whose danger or certainty changed, the pose
/// the frame was placed with, and the map's frame count.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DangerChanges {
    /// Frames in the map so far.
    pub frames: u64,
    /// The pose the frame was placed with: the odometry's estimate, corrected by the LTM
    /// Matcher when it is on (the navigator steers by it).
    pub estimate: PlanarPose,
    /// Whether the LTM Matcher corrected the pose with this frame.
    pub registered: bool,
    /// The changed cells.
    pub cells: Vec<CellDangerMsg>,
}

/// Query: the whole danger map.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DangerMapQuery;
message!(DangerMapQuery: query "nav.dangerMap" -> DangerGrid);

/// The danger map, row by row from the south-west cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DangerGrid {
    /// Centre of cell (0, 0), east, m.
    pub origin_x_m: f64,
    /// Centre of cell (0, 0), north, m.
    pub origin_y_m: f64,
    /// Cell side, m.
    pub resolution_m: f64,
    /// Columns.
    pub nx: u32,
    /// Rows.
    pub ny: u32,
    /// Danger per cell (row-major), `[0, 1]`; a negative value where the cell cannot be
    /// crossed.
    pub danger: Vec<f32>,
    /// Certainty per cell (row-major), `[0, 1]`.
    pub certainty: Vec<f32>,
    /// Frames in the map so far.
    pub frames: u64,
}

/// Goal: drive to the point `dx_m` east and `dy_m` north of where the base starts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Navigate {
    /// East of the start, m.
    pub dx_m: f64,
    /// North of the start, m.
    pub dy_m: f64,
    /// Frames before the goal fails.
    pub max_frames: u64,
}
message!(Navigate: goal "nav.navigate");

/// What one frame of the navigator's loop decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum FrameOutcome {
    /// It commanded the speeds of the frame.
    Drive,
    /// The estimate is at the goal; nothing more is commanded.
    Reached,
    /// The map as perceived has no traversable path to the goal; the goal fails.
    NoPath,
    /// The robot has not moved for many frames while told to; the goal fails.
    NoProgress,
}

/// Inform: one frame of the navigator's loop.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NavFrame {
    /// Frame number, from 0.
    pub frame: u64,
    /// The pose the navigator steers by: the odometry's estimate, corrected by the LTM
    /// Matcher when it is on.
    pub estimate: PlanarPose,
    /// The goal, world frame `[x, y]`.
    pub goal: [f64; 2],
    /// The planned path, world frame `[x, y]` per cell.
    pub path: Vec<[f64; 2]>,
    /// What the frame decided.
    pub outcome: FrameOutcome,
    /// Forward speed commanded, m/s (0 unless the outcome is [`FrameOutcome::Drive`]).
    pub forward_mps: f64,
    /// Turn speed commanded, rad/s.
    pub turn_rps: f64,
    /// Replans so far.
    pub replans: u64,
    /// Exploration turns so far.
    pub exploration_turns: u64,
    /// Frames the LTM Matcher corrected so far.
    pub registrations: u64,
    /// Cells whose danger this frame changed.
    pub changed_cells: u64,
    /// Wall time the frame's computing took (acquiring the image, mapping, danger,
    /// planning and control, with the bus's round trips), s.
    pub loop_s: f64,
}
message!(NavFrame: inform "nav.frame");

#[cfg(test)]
mod tests;
