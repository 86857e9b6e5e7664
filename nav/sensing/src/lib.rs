//! Simulated sensing for rough-terrain navigation, standing in for the stereo camera of
//! Chilian and Hirschmüller, "Stereo Camera Based Navigation of Mobile Robots on Rough
//! Terrain": its depth images ([`DepthCamera`]) and its visual odometry
//! ([`DriftingOdometry`]), whose error grows with the distance travelled.

mod camera;
mod odometry;
mod pose;

pub use camera::{Attitude, CameraMount, CameraParams, DepthCamera, DepthImage, SensingError};
pub use odometry::DriftingOdometry;
pub use pose::{Pose2, wrap};

/// A standard normal sample (Box–Muller), so that no distribution crate is needed.
pub(crate) fn gaussian(rng: &mut impl rand::Rng) -> f64 {
    let u1: f64 = rng.random_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}
