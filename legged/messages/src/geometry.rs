//! Points and poses in the world frame.

use serde::{Deserialize, Serialize};

/// A point in the world frame (X east, Y north, Z up), metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldPoint {
    /// East.
    pub x_m: f64,
    /// North.
    pub y_m: f64,
    /// Up.
    pub z_m: f64,
}

/// The body's pose in the world frame: its origin and its roll, pitch and yaw (about X, Y
/// and Z, applied in that order), metres and radians.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// East.
    pub x_m: f64,
    /// North.
    pub y_m: f64,
    /// Up.
    pub z_m: f64,
    /// Rotation about X.
    pub roll_rad: f64,
    /// Rotation about Y.
    pub pitch_rad: f64,
    /// Rotation about Z (0: body x pointing east).
    pub yaw_rad: f64,
}

impl Pose {
    /// The pose as `[x, y, z, roll, pitch, yaw]`, the order walk reports use.
    pub fn to_array(&self) -> [f64; 6] {
        [
            self.x_m,
            self.y_m,
            self.z_m,
            self.roll_rad,
            self.pitch_rad,
            self.yaw_rad,
        ]
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.to_array().iter().all(|v| v.is_finite())
    }
}
