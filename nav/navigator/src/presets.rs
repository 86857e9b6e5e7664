//! Navigation parameters of the built-in robots.

use tca_nav_danger_map::DangerParams;
use tca_nav_sensing::CameraMount;

use crate::NavParams;

/// The wheeled base's parameters: its danger file (`nav/danger-map/robots/wheeled.toml`),
/// a camera 0.45 m up tilted 0.55 rad down, 0.2 m/s.
pub fn wheeled_params() -> NavParams {
    let danger = DangerParams::from_toml(
        include_str!("../../danger-map/robots/wheeled.toml"),
        "nav/danger-map/robots/wheeled.toml",
    )
    .unwrap_or_else(|_| DangerParams::paper(0.45));
    NavParams::new(danger, WHEELED_MOUNT, 0.2)
}

/// Where the wheeled base's camera sits.
pub const WHEELED_MOUNT: CameraMount = CameraMount {
    forward_m: 0.15,
    height_m: 0.45,
    pitch_down_rad: 0.55,
};
