//! Imaging from a multi-legged robot's body.
//!
//! A legged robot's Controller reports its body pose as a [`Pose`] (`legged.bodyPose`:
//! position and roll, pitch, yaw about X, Y, Z, the yaw applied last). An ISM configured with
//! [`PoseSource::LeggedBody`] asks for that pose at every `acquireImage` and images from the
//! scanner mounted on that body ([`VirtualScanner::on_body`]), at any position and
//! orientation. The image's chain is then `locus <- scanner <- body <- global` with *body*
//! the legged robot's body frame (x forward, y left, z up): `S_T_B` is the inverse of the
//! mount, `B_T_G` the inverse of the body pose, so the LTM and the map viewers read the
//! image exactly as a single-leg one ([`crate::ImageFrames::body_origin_world`] is the body
//! origin).
//!
//! # The mast
//!
//! [`BodyDimensions::mast_mount`] places the scanner on a mast over the body origin, two
//! standing heights above it (about three standing heights above the ground), pitched down so
//! that the vertical field of view is centred between the ground under the rear of the body
//! and the ground two leg reaches ahead of its front (the leg reach taken as the standing
//! height: 2.6 m for the Ambler, 0.24 m for the hexapod). With the Perceptron's 60° x 60°
//! field that covers, on level ground, from behind the body to past two leg reaches ahead,
//! and across the body's width plus a leg reach on each side, for a body of any size: the
//! geometry scales with the standing height. The Perceptron's 0.98 cm range counts and
//! 4 mm noise suit both the Ambler's 0.1 m cells and the hexapod's 0.02 m ones.

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use tca_legged_messages::Pose;
use tca_robot::HeightField;

use crate::module::IsmConfig;
use crate::scanner::VirtualScanner;
use crate::spec::SensorSpec;

/// Where the ISM gets the pose of the body its scanners are mounted on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PoseSource {
    /// The single-leg robot's carriage: `bodyPosition` (rails position, roll, pitch).
    #[default]
    Carriage,
    /// A multi-legged robot's body: `legged.bodyPose` (any position, roll, pitch, yaw).
    LeggedBody,
}

/// The size of a legged robot's body, for mounting its scanner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyDimensions {
    /// Length along body x, metres.
    pub length_m: f64,
    /// Width along body y, metres.
    pub width_m: f64,
    /// Height of the body origin above level ground when standing, metres.
    pub standing_height_m: f64,
}

impl BodyDimensions {
    /// The Ambler's body: 1.6 m long, 2.8 m wide, standing 2.6 m high.
    pub const AMBLER: BodyDimensions = BodyDimensions {
        length_m: 1.6,
        width_m: 2.8,
        standing_height_m: 2.6,
    };

    /// The small hexapod's body: 0.3 m long, 0.2 m wide, standing 0.242 m high.
    pub const HEXAPOD: BodyDimensions = BodyDimensions {
        length_m: 0.3,
        width_m: 0.2,
        standing_height_m: 0.242,
    };

    /// Checks that every dimension is a positive, finite length.
    pub fn check(&self) -> crate::Result<()> {
        let all = [self.length_m, self.width_m, self.standing_height_m];
        if all.iter().all(|v| v.is_finite() && *v > 0.0) {
            Ok(())
        } else {
            Err(crate::IsmError::Config(format!(
                "body dimensions must be positive lengths in metres, got {self:?}"
            )))
        }
    }

    /// The leg reach assumed for the mount: the standing height, metres.
    pub fn leg_reach_m(&self) -> f64 {
        self.standing_height_m
    }

    /// Height of the scanner above the body origin: two standing heights, metres.
    pub fn mast_height_m(&self) -> f64 {
        2.0 * self.standing_height_m
    }

    /// How far down from level the scanner's boresight points, radians: midway between the
    /// ground under the rear of the body and the ground two leg reaches ahead of its front,
    /// seen from the mast.
    pub fn mast_pitch_rad(&self) -> f64 {
        let above_ground = self.mast_height_m() + self.standing_height_m;
        let near = above_ground.atan2(-0.5 * self.length_m);
        let far = above_ground.atan2(0.5 * self.length_m + 2.0 * self.leg_reach_m());
        0.5 * (near + far)
    }

    /// The mount `body <- scanner`: on the mast over the body origin, looking forward and
    /// down by [`BodyDimensions::mast_pitch_rad`].
    pub fn mast_mount(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(0.0, 0.0, self.mast_height_m()),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), self.mast_pitch_rad()),
        )
    }
}

/// `world <- body` of a legged body pose (roll, pitch, yaw about X, Y, Z, the yaw last).
pub fn world_from_body(pose: &Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(pose.x_m, pose.y_m, pose.z_m),
        UnitQuaternion::from_euler_angles(pose.roll_rad, pose.pitch_rad, pose.yaw_rad),
    )
}

impl IsmConfig {
    /// The ISM of a simulated legged robot: a virtual Perceptron on the mast of a body of
    /// `body`'s size ([`BodyDimensions::mast_mount`]), looking at `terrain`, its default noise
    /// seeded by `seed`, the body pose asked of the Controller as `legged.bodyPose`. Bad body
    /// dimensions are reported when the module connects.
    pub fn legged_simulated(terrain: Arc<HeightField>, body: &BodyDimensions, seed: u64) -> Self {
        let config = Self::new().with_pose_source(PoseSource::LeggedBody);
        if let Err(e) = body.check() {
            return config.with_error(e.to_string());
        }
        config.with_sensor(
            VirtualScanner::on_body(SensorSpec::perceptron(), terrain, body.mast_mount())
                .with_seed(seed),
        )
    }
}
