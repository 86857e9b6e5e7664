//! A small wheeled base with differential drive (the Pioneer 3-DX's role).

use tca_nav_sensing::{Attitude, Pose2};
use tca_robot::HeightField;

use crate::{Base, Motion};

/// The base's geometry and limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheeledParams {
    /// Distance between the two driven wheels, m.
    pub wheel_separation_m: f64,
    /// Fastest wheel speed, m/s.
    pub max_wheel_mps: f64,
    /// Highest step a wheel climbs, m.
    pub max_step_m: f64,
    /// Tilt at which the base tips over, rad.
    pub tip_over_rad: f64,
}

impl WheeledParams {
    /// A Pioneer-like base: wheels 0.33 m apart, up to 0.3 m/s, climbs 50 mm (the danger map's critical step), tips at 30°.
    pub const PIONEER: WheeledParams = WheeledParams {
        wheel_separation_m: 0.33,
        max_wheel_mps: 0.3,
        max_step_m: 0.05,
        tip_over_rad: std::f64::consts::FRAC_PI_6,
    };
}

/// The base's own controller: forward and turn speeds into wheel speeds (saturated
/// together so the turn radius is kept), integrated over the true terrain. A wheel that
/// would climb more than `max_step_m` within one integration step blocks the motion.
#[derive(Debug, Clone)]
pub struct WheeledBase<'t> {
    params: WheeledParams,
    terrain: &'t HeightField,
    pose: Pose2,
}

impl<'t> WheeledBase<'t> {
    /// A base standing at `start` on `terrain`.
    pub fn new(params: WheeledParams, terrain: &'t HeightField, start: Pose2) -> Self {
        Self {
            params,
            terrain,
            pose: start,
        }
    }

    fn wheel_points(&self, p: &Pose2) -> [(f64, f64); 2] {
        let h = 0.5 * self.params.wheel_separation_m;
        let (s, c) = p.yaw.sin_cos();
        [(p.x - s * h, p.y + c * h), (p.x + s * h, p.y - c * h)]
    }
}

impl Base for WheeledBase<'_> {
    fn name(&self) -> &str {
        "wheeled"
    }

    fn true_pose(&self) -> Pose2 {
        self.pose
    }

    fn attitude(&self) -> Attitude {
        Attitude::level(self.terrain.height_at(self.pose.x, self.pose.y))
    }

    fn drive(&mut self, forward_mps: f64, turn_rps: f64, dt_s: f64) -> Motion {
        let p = self.params;
        let half = 0.5 * p.wheel_separation_m;
        let (mut l, mut r) = (forward_mps - turn_rps * half, forward_mps + turn_rps * half);
        let m = l.abs().max(r.abs());
        if m > p.max_wheel_mps {
            l *= p.max_wheel_mps / m;
            r *= p.max_wheel_mps / m;
        }
        let (v, w) = (0.5 * (l + r), (r - l) / p.wheel_separation_m);
        let steps = ((v.abs() * dt_s / 0.01).ceil() as usize).max(1);
        let h = dt_s / steps as f64;
        let mut motion = Motion {
            pose: self.pose,
            ..Motion::default()
        };
        for _ in 0..steps {
            let next = self.pose.moved(v * h, 0.0, w * h);
            let before = self.wheel_points(&self.pose);
            let after = self.wheel_points(&next);
            let climb = before.iter().zip(after.iter()).any(|(a, b)| {
                (self.terrain.height_at(b.0, b.1) - self.terrain.height_at(a.0, a.1)).abs()
                    > p.max_step_m
            });
            if climb {
                motion.collided = true;
                break;
            }
            self.pose = next;
            let n = self.terrain.normal_at(next.x, next.y);
            if n.z.acos() > p.tip_over_rad {
                motion.fell = true;
            }
        }
        motion.pose = self.pose;
        motion
    }
}
