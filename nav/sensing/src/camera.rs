//! A simulated depth camera: the depth image a stereo pair would give.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_robot::HeightField;

use crate::{Pose2, gaussian};

/// Why a camera could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SensingError {
    /// A camera parameter is out of range.
    #[error("camera parameter `{name}` = {value} is not valid: {expected}")]
    BadParam {
        /// The parameter.
        name: &'static str,
        /// The value.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
}

/// The camera's optics and its stereo-like errors.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraParams {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Horizontal field of view, rad (square pixels: the vertical one follows).
    pub hfov_rad: f64,
    /// Farthest return, m; beyond it pixels are invalid.
    pub max_range_m: f64,
    /// Range noise factor `k`: the depth's standard deviation is `k * z²` (stereo's error
    /// grows with the square of the distance), 1/m.
    pub noise_per_m: f64,
    /// Fraction of pixels without texture, invalid wherever they fall.
    pub untextured_fraction: f64,
}

impl CameraParams {
    /// A small stereo camera: 160 x 120 pixels, 60° across, returns up to 4 m, noise
    /// 0.004 z² (a 0.1 m baseline, 500 pixel focal length, 0.2 pixel disparity error),
    /// 5 % untextured pixels.
    pub fn stereo_default() -> Self {
        Self {
            width: 160,
            height: 120,
            hfov_rad: 60f64.to_radians(),
            max_range_m: 4.0,
            noise_per_m: 0.004,
            untextured_fraction: 0.05,
        }
    }

    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), SensingError> {
        let bad = |name, value, expected| {
            Err(SensingError::BadParam {
                name,
                value,
                expected,
            })
        };
        if self.width == 0 || self.height == 0 {
            return bad(
                "width x height",
                (self.width * self.height) as f64,
                "at least 1 x 1 pixels",
            );
        }
        if !(self.hfov_rad > 0.0 && self.hfov_rad < std::f64::consts::PI) {
            return bad("hfov_rad", self.hfov_rad, "an angle between 0 and pi");
        }
        if !(self.max_range_m.is_finite() && self.max_range_m > 0.0) {
            return bad(
                "max_range_m",
                self.max_range_m,
                "a finite range greater than 0",
            );
        }
        if !(self.noise_per_m.is_finite() && self.noise_per_m >= 0.0) {
            return bad(
                "noise_per_m",
                self.noise_per_m,
                "a finite factor of at least 0",
            );
        }
        if !(0.0..1.0).contains(&self.untextured_fraction) {
            return bad(
                "untextured_fraction",
                self.untextured_fraction,
                "a fraction in [0, 1)",
            );
        }
        Ok(())
    }

    /// Focal length, pixels.
    pub fn focal_px(&self) -> f64 {
        0.5 * self.width as f64 / (0.5 * self.hfov_rad).tan()
    }

    /// The unit ray through pixel (u, v) in the camera frame (x along the optical axis,
    /// y left, z up) scaled so that its x is 1.
    fn ray(&self, u: usize, v: usize) -> Vector3<f64> {
        let f = self.focal_px();
        let cx = 0.5 * self.width as f64;
        let cy = 0.5 * self.height as f64;
        Vector3::new(1.0, -(u as f64 + 0.5 - cx) / f, -(v as f64 + 0.5 - cy) / f)
    }
}

/// Where the camera sits on the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraMount {
    /// Ahead of the robot's reference point, m.
    pub forward_m: f64,
    /// Above the robot's reference point, m: the ground under the centre of a wheeled
    /// base, the body's origin of a legged robot (see [`Attitude`]).
    pub height_m: f64,
    /// Downward tilt of the optical axis from the robot's x axis, rad.
    pub pitch_down_rad: f64,
}

/// What a robot measures of its pose besides the planar pose its odometry estimates: the
/// height of its reference point and its tilt. Drift is planar: the height and tilt are
/// taken as known (an inclinometer and the visual odometry's six degrees of freedom give
/// them well; the paper's own remedy for tilt drift is such a sensor).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Attitude {
    /// Height of the reference point, m.
    pub z_m: f64,
    /// Roll about the robot's x axis, rad.
    pub roll_rad: f64,
    /// Pitch about the robot's y axis, rad (positive: nose down, as REP 103 has it).
    pub pitch_rad: f64,
}

impl Attitude {
    /// A level robot whose reference point is at `z_m` (a wheeled base's camera, which is
    /// taken as stabilised in roll and pitch, over ground of that height).
    pub fn level(z_m: f64) -> Self {
        Self {
            z_m,
            roll_rad: 0.0,
            pitch_rad: 0.0,
        }
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.z_m.is_finite() && self.roll_rad.is_finite() && self.pitch_rad.is_finite()
    }
}

impl CameraMount {
    /// The camera's pose in the world for a robot at the planar pose `pose` with the
    /// height and tilt `attitude`.
    pub fn camera_pose(&self, pose: &Pose2, attitude: &Attitude) -> Isometry3<f64> {
        let body = Isometry3::from_parts(
            Translation3::new(pose.x, pose.y, attitude.z_m),
            UnitQuaternion::from_euler_angles(attitude.roll_rad, attitude.pitch_rad, pose.yaw),
        );
        let on_body = Isometry3::from_parts(
            Translation3::new(self.forward_m, 0.0, self.height_m),
            UnitQuaternion::from_euler_angles(0.0, self.pitch_down_rad, 0.0),
        );
        body * on_body
    }
}

/// A depth image: per pixel the depth along the optical axis, m, or `None` (invalid).
#[derive(Debug, Clone, PartialEq)]
pub struct DepthImage {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Row-major depths.
    pub depth: Vec<Option<f64>>,
}

impl DepthImage {
    /// The valid pixels no farther than `max_use_m` as world points, placed with the
    /// camera pose `pose` (the estimated one, for mapping).
    pub fn points(
        &self,
        params: &CameraParams,
        pose: &Isometry3<f64>,
        max_use_m: f64,
    ) -> Vec<Point3<f64>> {
        let mut out = Vec::with_capacity(self.depth.len());
        for v in 0..self.height {
            for u in 0..self.width {
                if let Some(d) = self.depth[v * self.width + u] {
                    let p = params.ray(u, v) * d;
                    if p.norm() <= max_use_m {
                        out.push(pose * Point3::from(p));
                    }
                }
            }
        }
        out
    }

    /// Number of valid pixels.
    pub fn valid(&self) -> usize {
        self.depth.iter().filter(|d| d.is_some()).count()
    }
}

/// A seeded depth camera.
#[derive(Debug, Clone)]
pub struct DepthCamera {
    params: CameraParams,
    rng: ChaCha8Rng,
}

impl DepthCamera {
    /// A camera; `seed` fixes its noise.
    pub fn new(params: CameraParams, seed: u64) -> Result<Self, SensingError> {
        params.validate()?;
        Ok(Self {
            params,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0xCA3E_7A00),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &CameraParams {
        &self.params
    }

    /// The depth image of `terrain` seen from the (true) camera pose `pose`.
    pub fn capture(&mut self, terrain: &HeightField, pose: &Isometry3<f64>) -> DepthImage {
        let p = &self.params;
        let origin = Point3::from(pose.translation.vector);
        let mut depth = Vec::with_capacity(p.width * p.height);
        for v in 0..p.height {
            for u in 0..p.width {
                let ray = p.ray(u, v);
                let dir = pose.rotation * ray;
                let untextured = self.rng.random_bool(p.untextured_fraction);
                let hit = terrain.cast_ray(&origin, &dir, p.max_range_m);
                let d = match hit {
                    Some(h) if !untextured && h.range_m > 0.0 => {
                        let z = h.range_m / ray.norm();
                        // Delivered as a camera delivers depth: a 32-bit float per pixel.
                        let noisy =
                            f64::from((z + p.noise_per_m * z * z * gaussian(&mut self.rng)) as f32);
                        (noisy > 0.0).then_some(noisy)
                    }
                    _ => None,
                };
                depth.push(d);
            }
        }
        DepthImage {
            width: p.width,
            height: p.height,
            depth,
        }
    }
}
