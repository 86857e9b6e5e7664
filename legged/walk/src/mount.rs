//! Where the scanner sits on a walking robot: on a mast over the body origin, high enough
//! and pitched so that its vertical field of view spans the ground from behind the rearmost
//! foot to two standing heights ahead of the foremost one.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use tca_legged_model::RobotModel;

/// The share of the vertical field of view the ground span is fitted into (the rest is a
/// margin at both ends).
const FOV_USED: f64 = 0.92;

/// The ground span the scanner must see, metres along body x: `(behind, ahead)` of the body
/// origin, both positive.
pub fn ground_span(model: &RobotModel) -> (f64, f64) {
    let h = model.neutral_height().max(0.01);
    let feet = model
        .foot_positions(&model.neutral_posture())
        .unwrap_or_default();
    let r = model
        .legs()
        .iter()
        .map(|l| l.foot_radius())
        .fold(0.0, f64::max);
    let rear = feet.iter().map(|f| -f.x).fold(0.0, f64::max);
    let front = feet.iter().map(|f| f.x).fold(0.0, f64::max);
    (rear + 2.0 * r + 0.1 * h, front + 2.0 * h)
}

/// The mount `body <- scanner` for a scanner with this vertical field of view (radians): on a
/// mast over the body origin at least two standing heights above it, pitched down so that
/// the ground span ([`ground_span`]) fills the field of view on level ground.
pub fn mast_mount(model: &RobotModel, vertical_fov_rad: f64) -> Isometry3<f64> {
    let h = model.neutral_height().max(0.01);
    let (behind, ahead) = ground_span(model);
    let fov = (vertical_fov_rad * FOV_USED).clamp(0.1, 3.0);
    // Angles from straight down to the span's two ends shrink as the mast rises.
    let spread = |height: f64| (ahead / height).atan() + (behind / height).atan();
    let (mut lo, mut hi) = (1e-3 * h, 1e3 * h);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if spread(mid) > fov {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let above_ground = hi.max(3.0 * h);
    let boresight_from_down =
        0.5 * ((ahead / above_ground).atan() - (behind / above_ground).atan());
    let pitch_down = std::f64::consts::FRAC_PI_2 - boresight_from_down;
    Isometry3::from_parts(
        Translation3::new(0.0, 0.0, above_ground - h),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), pitch_down),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_field_of_view_spans_from_behind_the_rear_feet_to_ahead_of_the_front_ones() {
        for name in ["ambler", "hexapod", "athlete"] {
            let model = RobotModel::builtin(name).expect("a shipped robot");
            let fov = 60f64.to_radians();
            let mount = mast_mount(&model, fov);
            let (behind, ahead) = ground_span(&model);
            let h = model.neutral_height();
            let height = mount.translation.vector.z + h;
            // The boresight and the two edges of the field of view, in the body's x-z plane.
            let down = |angle: f64| {
                let d = mount.rotation
                    * (UnitQuaternion::from_axis_angle(&Vector3::y_axis(), angle) * Vector3::x());
                assert!(d.z < 0.0, "{name}: an edge of the view looks up");
                height * d.x / -d.z
            };
            let (near, far) = (down(fov / 2.0), down(-fov / 2.0));
            println!(
                "{name}: mast {height:.2} m above the ground, sees x {near:.2}..{far:.2} m, needs -{behind:.2}..{ahead:.2} m"
            );
            assert!(
                near <= -behind + 1e-9,
                "{name}: sees from {near:.2}, not behind {behind:.2}"
            );
            assert!(
                far >= ahead - 1e-9,
                "{name}: sees to {far:.2}, not {ahead:.2}"
            );
        }
    }
}
