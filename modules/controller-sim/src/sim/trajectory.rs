//! Joint-space trajectories through way-points (§4.2): the slowest joint sets each
//! segment's duration and the others are scaled to arrive with it; constant-velocity
//! segments are joined by constant-acceleration blends at the joint limits.
//!
//! This is the linear-segments-with-parabolic-blends scheme: segment `i` (from way-point
//! `i-1` to `i`) is traversed at a constant joint velocity `v_i`, and around each way-point
//! all joints blend from `v_i` to `v_{i+1}` over a common blend time `tb_i` centred on the
//! way-point's time. The start and the end are exact and at rest; intermediate way-points are
//! passed within the blend, at most `|v_{i+1} - v_i| * tb_i / 8` away per joint. Where blends
//! would overlap, the segment is slowed down until they fit.

use std::time::Duration;

use tca_robot::{Joint, JointPosition, LegKinematics};

/// A planned joint-space trajectory from a start through way-points.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTrajectory {
    /// Way-points, the start first (consecutive duplicates removed).
    vias: Vec<[f64; 3]>,
    /// Velocity of segment i (into via i) for i = 1..n; index 0 and n+1 are rest.
    vel: Vec<[f64; 3]>,
    /// Blend time around each via.
    blend: Vec<f64>,
    /// Time of each via (the blend's centre), the start's blend beginning at time 0.
    via_time: Vec<f64>,
    duration_s: f64,
    max_speed: [f64; 3],
    max_accel: [f64; 3],
}

impl JointTrajectory {
    /// Plans the trajectory from `start` through `waypoints` with the joint speed and
    /// acceleration limits of `kin`. Way-points must be finite (checked by the caller).
    pub fn plan(kin: &LegKinematics, start: &JointPosition, waypoints: &[JointPosition]) -> Self {
        let max_speed = Joint::ALL.map(|j| kin.limits(j).max_speed);
        let max_accel = Joint::ALL.map(|j| kin.limits(j).max_accel);
        let mut vias = vec![start.to_array()];
        for w in waypoints {
            let w = w.to_array();
            if vias
                .last()
                .is_some_and(|last| (0..3).any(|j| (w[j] - last[j]).abs() > 1e-12))
            {
                vias.push(w);
            }
        }
        let n = vias.len() - 1;
        // Segment durations from the slowest joint.
        let mut seg = vec![0.0; n + 1];
        for i in 1..=n {
            seg[i] = (0..3)
                .map(|j| (vias[i][j] - vias[i - 1][j]).abs() / max_speed[j])
                .fold(0.0, f64::max);
        }
        let velocities = |seg: &[f64]| -> Vec<[f64; 3]> {
            let mut vel = vec![[0.0; 3]; n + 2];
            for i in 1..=n {
                for j in 0..3 {
                    vel[i][j] = (vias[i][j] - vias[i - 1][j]) / seg[i];
                }
            }
            vel
        };
        let blends = |vel: &[[f64; 3]]| -> Vec<f64> {
            (0..=n)
                .map(|i| {
                    (0..3)
                        .map(|j| (vel[i + 1][j] - vel[i][j]).abs() / max_accel[j])
                        .fold(0.0, f64::max)
                })
                .collect()
        };
        // Slow down segments whose blends would overlap, until none do.
        for pass in 0..2000 {
            let vel = velocities(&seg);
            let blend = blends(&vel);
            let mut changed = false;
            for i in 1..=n {
                let need = 0.5 * (blend[i - 1] + blend[i]);
                if seg[i] < need * (1.0 - 1e-12) {
                    seg[i] = if pass < 50 {
                        (seg[i] * need).sqrt().max(seg[i] * 1.0001)
                    } else {
                        seg[i] * 1.01
                    };
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        let vel = velocities(&seg);
        let blend = blends(&vel);
        let mut via_time = vec![0.5 * blend[0]; n + 1];
        for i in 1..=n {
            via_time[i] = via_time[i - 1] + seg[i];
        }
        let duration_s = via_time[n] + 0.5 * blend[n];
        Self {
            vias,
            vel,
            blend,
            via_time,
            duration_s,
            max_speed,
            max_accel,
        }
    }

    /// Total time of the move.
    pub fn duration(&self) -> Duration {
        Duration::from_secs_f64(self.duration_s)
    }

    /// Total time of the move, seconds.
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// Number of segments (way-points after removing ones equal to their predecessor).
    pub fn segments(&self) -> usize {
        self.vias.len() - 1
    }

    /// Time at which the motion toward the last way-point begins (the start of the blend
    /// into the last segment), seconds.
    pub fn last_segment_start_s(&self) -> f64 {
        let n = self.segments();
        if n <= 1 {
            0.0
        } else {
            self.via_time[n - 1] - 0.5 * self.blend[n - 1]
        }
    }

    /// Time of way-point `i` (0 = start) at the centre of its blend, seconds.
    pub fn via_time_s(&self, i: usize) -> Option<f64> {
        self.via_time.get(i).copied()
    }

    /// Largest joint speed of any segment, per joint (rad/s or m/s).
    pub fn peak_speeds(&self) -> [f64; 3] {
        let mut peak = [0.0_f64; 3];
        for v in &self.vel {
            for j in 0..3 {
                peak[j] = peak[j].max(v[j].abs());
            }
        }
        peak
    }

    /// Joint position at time `t_s` (clamped to the move).
    pub fn position_at(&self, t_s: f64) -> JointPosition {
        JointPosition::from_array(self.eval(t_s).0)
    }

    /// Joint velocity at time `t_s`.
    pub fn velocity_at(&self, t_s: f64) -> [f64; 3] {
        self.eval(t_s).1
    }

    fn eval(&self, t_s: f64) -> ([f64; 3], [f64; 3]) {
        let n = self.segments();
        let t = if t_s.is_nan() {
            0.0
        } else {
            t_s.clamp(0.0, self.duration_s)
        };
        // Inside a blend?
        for i in 0..=n {
            let half = 0.5 * self.blend[i];
            if half > 0.0 && (t - self.via_time[i]).abs() <= half {
                let d = t - (self.via_time[i] - half);
                let mut p = [0.0; 3];
                let mut v = [0.0; 3];
                for j in 0..3 {
                    let a = (self.vel[i + 1][j] - self.vel[i][j]) / self.blend[i];
                    p[j] = self.vias[i][j] - self.vel[i][j] * half
                        + self.vel[i][j] * d
                        + 0.5 * a * d * d;
                    v[j] = self.vel[i][j] + a * d;
                }
                return (p, v);
            }
        }
        // On a linear segment (or at rest before the first / after the last via).
        if t <= self.via_time[0] {
            return (self.vias[0], [0.0; 3]);
        }
        for i in 1..=n {
            if t <= self.via_time[i] {
                let since = t - self.via_time[i - 1];
                let p = std::array::from_fn(|j| self.vias[i - 1][j] + self.vel[i][j] * since);
                return (p, self.vel[i]);
            }
        }
        (self.vias[n], [0.0; 3])
    }

    /// The joint speed and acceleration limits used.
    pub fn limits(&self) -> ([f64; 3], [f64; 3]) {
        (self.max_speed, self.max_accel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_robot::LegParams;

    fn kin() -> LegKinematics {
        LegKinematics::new(&LegParams::default())
    }

    #[test]
    fn pure_vertical_move_takes_distance_over_speed_plus_a_blend() {
        let start = JointPosition::new(0.5, 1.0, 3.2);
        let end = JointPosition::new(0.5, 1.0, 3.56);
        let t = JointTrajectory::plan(&kin(), &start, &[end]);
        // 0.36 m at 3.6 cm/s = 10 s, plus half of each 0.72 s blend (0.036 / 0.05).
        assert!((t.duration_s() - 10.72).abs() < 1e-9, "{}", t.duration_s());
        assert_eq!(t.position_at(0.0), start);
        assert_eq!(t.position_at(t.duration_s()), end);
        assert!((t.velocity_at(5.0)[2] - 0.036).abs() < 1e-12);
    }

    #[test]
    fn short_moves_become_triangular() {
        let start = JointPosition::new(0.5, 1.0, 3.2);
        let end = JointPosition::new(0.5, 1.0, 3.21);
        let t = JointTrajectory::plan(&kin(), &start, &[end]);
        // d = 0.01 m, a = 0.05 m/s^2: accelerate half way and brake, 2 sqrt(d / a).
        assert!(
            (t.duration_s() - 2.0 * (0.01f64 / 0.05).sqrt()).abs() < 1e-6,
            "{}",
            t.duration_s()
        );
        let peak = t.velocity_at(0.5 * t.duration_s())[2];
        assert!(peak < 0.036);
        assert!((t.position_at(t.duration_s()).vertical_m - 3.21).abs() < 1e-12);
    }

    #[test]
    fn joints_move_together_and_respect_their_limits() {
        let k = kin();
        let start = JointPosition::new(0.0, 1.0, 3.2);
        let wps = [
            JointPosition::new(0.0, 1.0, 3.0),
            JointPosition::new(1.0, 0.4, 3.0),
            JointPosition::new(1.0, 0.4, 3.5),
        ];
        let t = JointTrajectory::plan(&k, &start, &wps);
        let (vmax, amax) = t.limits();
        let dt = 0.01;
        let mut prev = t.velocity_at(0.0);
        let mut s = 0.0;
        while s <= t.duration_s() {
            let v = t.velocity_at(s);
            for j in 0..3 {
                assert!(
                    v[j].abs() <= vmax[j] * (1.0 + 1e-9),
                    "speed of joint {j} at {s}"
                );
                assert!(
                    (v[j] - prev[j]).abs() / dt <= amax[j] * 1.01 + 1e-9,
                    "acceleration of joint {j} at {s}"
                );
            }
            prev = v;
            s += dt;
        }
        // On the middle segment's straight part all joints are at the same fraction.
        let (t1, t2) = (t.via_time_s(1).unwrap(), t.via_time_s(2).unwrap());
        let mid = t.position_at(0.5 * (t1 + t2));
        let f_shoulder = (mid.shoulder_rad - 0.0) / 1.0;
        let f_elbow = (mid.elbow_rad - 1.0) / (0.4 - 1.0);
        assert!(
            (f_shoulder - f_elbow).abs() < 1e-9,
            "{f_shoulder} vs {f_elbow}"
        );
        assert_eq!(t.position_at(t.duration_s()), wps[2]);
        // The elbow (0.6 rad at 0.15 rad/s = 4 s) is faster than the shoulder (1 rad at
        // 0.1 rad/s = 10 s): the shoulder sets the middle segment's duration.
        assert!((t2 - t1 - 10.0).abs() < 1e-9, "{}", t2 - t1);
    }

    #[test]
    fn repeated_way_points_are_ignored() {
        let start = JointPosition::new(0.0, 1.0, 3.2);
        let t = JointTrajectory::plan(&kin(), &start, &[start, start]);
        assert_eq!(t.segments(), 0);
        assert_eq!(t.duration_s(), 0.0);
        assert_eq!(t.position_at(1.0), start);
    }
}
