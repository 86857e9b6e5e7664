//! Navigation parameters of walking robots.

use tca_legged_model::RobotModel;
use tca_nav_danger_map::{DangerError, DangerParams};
use tca_nav_navigator::NavParams;
use tca_nav_sensing::CameraMount;

use crate::stepper::{foot_spread_m, footprint_radius_m};

/// The shipped hexapod's danger file (`nav/danger-map/robots/hexapod.toml`).
pub const HEXAPOD_DANGER: &str = include_str!("../../danger-map/robots/hexapod.toml");

/// The navigation parameters of a walking robot, scaled to its size: the paper's danger
/// parameters over a circle as wide as the robot stands (or `danger`), a camera on the
/// front of the body looking 0.5 rad down, and speeds a walking robot keeps up with.
///
/// The camera sits ahead of the body's origin by 55 % of the farthest neutral foot's
/// reach forward and 40 % of the standing height above it. The loop runs once a second,
/// as the paper's did on the DLR Crawler, so that the terrain map's ageing (in frames)
/// spans as much ground as it did there; the body walks at most 4 cm/s and turns
/// 0.3 rad/s for a robot whose feet stand 0.33 m from its centre (the shipped hexapod),
/// lengths and speeds scaling with the robot.
pub fn legged_params(model: &RobotModel, danger: Option<DangerParams>) -> NavParams {
    let s = foot_spread_m(model).max(1e-3) / 0.33;
    let reach_forward = model
        .legs()
        .iter()
        .filter_map(|l| l.foot_position(&l.neutral()).ok())
        .map(|p| p.x)
        .fold(0.0, f64::max);
    let mount = CameraMount {
        forward_m: 0.55 * reach_forward,
        height_m: 0.4 * model.neutral_height(),
        pitch_down_rad: 0.5,
    };
    let danger = danger.unwrap_or_else(|| DangerParams::paper(2.0 * footprint_radius_m(model)));
    let mut params = NavParams::new(danger, mount, 0.04 * s);
    params.max_turn_rps = 0.3;
    params.frame_period_s = 1.0;
    // A command holds for a whole second: a turn gain of 0.45/s closes 45 % of a heading
    // error per frame (90 % in exploration turns, which turn at twice the gain), so that
    // neither overshoots.
    params.turn_gain = 0.45;
    params
}

/// The shipped hexapod's navigation parameters: [`legged_params`] with its danger file.
pub fn hexapod_params(model: &RobotModel) -> Result<NavParams, DangerError> {
    let danger = DangerParams::from_toml(HEXAPOD_DANGER, "nav/danger-map/robots/hexapod.toml")?;
    Ok(legged_params(model, Some(danger)))
}
