//! What the simulator's tests share: robots on flat ground, and swings built by inverse
//! kinematics.

#![allow(dead_code, unreachable_pub)]

use std::sync::Arc;

use nalgebra::{Point2, Vector3};
use tca_legged_model::{IkOptions, RobotModel};
use tca_legged_sim::{LeggedSim, SimParams, StartPose};
use tca_robot::HeightField;

pub const ROBOTS: [&str; 3] = ["ambler", "hexapod", "athlete"];

pub fn model(name: &str) -> Arc<RobotModel> {
    Arc::new(RobotModel::builtin(name).expect("built-in robot"))
}

/// Flat ground at z = 0 six standing heights around the origin, 25 cells per height.
pub fn flat_for(model: &RobotModel) -> Arc<HeightField> {
    let h = model.neutral_height();
    let s = 6.0 * h;
    Arc::new(
        HeightField::flat(Point2::new(-s, -s), Point2::new(s, s), h / 25.0, 0.0)
            .expect("flat ground"),
    )
}

pub const ORIGIN: StartPose = StartPose {
    x_m: 0.0,
    y_m: 0.0,
    yaw_rad: 0.0,
};

/// The robot standing at the origin of flat ground.
pub fn standing(name: &str) -> LeggedSim {
    let m = model(name);
    let t = flat_for(&m);
    let p = SimParams::for_model(&m);
    LeggedSim::new(m, t, ORIGIN, p).expect("stands on flat ground")
}

pub fn standing_on(
    name: &str,
    terrain: HeightField,
    params: impl FnOnce(&mut SimParams),
) -> LeggedSim {
    let m = model(name);
    let mut p = SimParams::for_model(&m);
    params(&mut p);
    LeggedSim::new(m, Arc::new(terrain), ORIGIN, p).expect("stands")
}

/// Joint way-points that take the foot of `leg` through body-frame offsets from where it
/// is now (body level, so body z is up), solved by inverse kinematics one from the other.
pub fn through(sim: &LeggedSim, leg: usize, offsets: &[Vector3<f64>]) -> Vec<Vec<f64>> {
    let l = &sim.model().legs()[leg];
    let mut q = sim.posture()[leg].clone();
    let foot = l.foot_position(&q).expect("foot");
    offsets
        .iter()
        .map(|d| {
            q = l
                .inverse_kinematics(&(foot + d), &IkOptions::starting_at(&q))
                .expect("reachable way-point")
                .joints;
            q.clone()
        })
        .collect()
}

/// A swing of `leg`: up by `lift`, forward by `forward`, then down to `sink` below the
/// ground it stood on (for a transition move), all as fractions of the standing height.
pub fn swing(sim: &LeggedSim, leg: usize, lift: f64, forward: f64, sink: f64) -> Vec<Vec<f64>> {
    let h = sim.model().neutral_height();
    through(
        sim,
        leg,
        &[
            Vector3::new(0.0, 0.0, lift * h),
            Vector3::new(forward * h, 0.0, lift * h),
            Vector3::new(forward * h, 0.0, -sink * h),
        ],
    )
}
