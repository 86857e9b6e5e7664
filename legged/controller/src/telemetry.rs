//! Telemetry: the robot's state as `legged.telemetry` reports it, at rest or part-way through a
//! move carried out in wall-clock time, and the loop that publishes it at a set rate.
//!
//! At rest the sample is the simulator's state. During a paced move (see
//! [`LeggedControllerConfig::speed`](crate::LeggedControllerConfig::speed)) it is interpolated
//! between the states before and after the move: a leg move's joints along its way-points,
//! each segment taking as long as its slowest joint needs (the simulator's own timing), the
//! leg in the air until the move ends; a body move's pose along the straight line between its
//! ends, the legs' joints likewise. Feet standing during a move stay where they stand.

use std::time::Duration;

use nalgebra::{Isometry3, Point2, Point3, Translation3, Vector3};
use tca_legged_messages::{LegStateReply, Telemetry};
use tca_legged_model::RobotModel;
use tca_legged_sim::{LeggedSim, isometry_to_pose, world_point};
use tca_stability::{stability_margin, support_polygon};
use tokio::time::Instant;

/// Standard gravity, m/s².
const G: f64 = 9.80665;

/// The robot's state at one moment, enough for a telemetry sample.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Snapshot {
    /// The simulator's motion clock, seconds.
    pub(crate) clock_s: f64,
    /// The body, world frame.
    pub(crate) body: Isometry3<f64>,
    /// Every leg's joints.
    pub(crate) posture: Vec<Vec<f64>>,
    /// Which feet stand.
    pub(crate) stance: Vec<bool>,
    /// Where each standing foot touches the ground, world frame (the support polygon's
    /// corners).
    pub(crate) touch: Vec<Point3<f64>>,
}

impl Snapshot {
    /// The simulator's state now.
    pub(crate) fn of(sim: &LeggedSim) -> Self {
        let state = sim.support_state();
        Snapshot {
            clock_s: sim.clock_s(),
            body: sim.body(),
            posture: sim.posture().to_vec(),
            stance: sim.stance(),
            touch: state
                .feet
                .iter()
                .map(|f| Point3::new(f.at.x_m, f.at.y_m, f.at.z_m))
                .collect(),
        }
    }

    /// The telemetry sample of this state.
    pub(crate) fn sample(&self, model: &RobotModel, seq: u64) -> Telemetry {
        let standing = self.stance.iter().filter(|s| **s).count();
        let weight = model.total_mass() * G;
        let legs = model
            .legs()
            .iter()
            .enumerate()
            .map(|(i, leg)| {
                let q = self.posture.get(i).cloned().unwrap_or_default();
                let centre = leg
                    .foot_position(&q)
                    .map(|p| self.body * p)
                    .unwrap_or_else(|_| Point3::new(f64::NAN, f64::NAN, f64::NAN));
                let stance = self.stance.get(i).copied().unwrap_or(false);
                LegStateReply {
                    leg: leg.name().to_owned(),
                    joints: q,
                    foot: world_point(&(centre - Vector3::z() * leg.foot_radius())),
                    stance,
                    force_n: if stance {
                        weight / standing.max(1) as f64
                    } else {
                        0.0
                    },
                }
            })
            .collect();
        let com = model
            .centre_of_mass(&self.posture)
            .map(|m| self.body * m.centre)
            .unwrap_or_else(|_| Point3::new(f64::NAN, f64::NAN, f64::NAN));
        let feet: Vec<Point2<f64>> = self
            .touch
            .iter()
            .zip(&self.stance)
            .filter(|(_, s)| **s)
            .map(|(p, _)| Point2::new(p.x, p.y))
            .collect();
        Telemetry {
            seq,
            t_s: self.clock_s,
            body: isometry_to_pose(&self.body),
            com: world_point(&com),
            margin_m: stability_margin(&support_polygon(&feet), com),
            legs,
        }
    }
}

/// A move being carried out in wall-clock time.
#[derive(Clone, Debug)]
pub(crate) struct Motion {
    /// When it started.
    pub(crate) started: Instant,
    /// How long it takes on the wall clock.
    pub(crate) wall: Duration,
    /// The state before it.
    pub(crate) before: Snapshot,
    /// The state after it.
    pub(crate) after: Snapshot,
    /// For a leg move: the leg and its joint-space path (its joints before, then the
    /// way-points), each point with the move time it is reached at, seconds.
    pub(crate) leg_path: Option<(usize, TimedPath)>,
}

/// A joint-space path, each point (its joints) with the move time it is reached at, seconds.
pub(crate) type TimedPath = Vec<(f64, Vec<f64>)>;

impl Motion {
    /// The state `elapsed` into the move.
    pub(crate) fn at(&self, elapsed: Duration) -> Snapshot {
        let f = if self.wall.is_zero() {
            1.0
        } else {
            (elapsed.as_secs_f64() / self.wall.as_secs_f64()).clamp(0.0, 1.0)
        };
        if f >= 1.0 {
            return self.after.clone();
        }
        let (a, b) = (&self.before, &self.after);
        let duration_s = b.clock_s - a.clock_s;
        let body = lerp_pose(&a.body, &b.body, f);
        let mut stance = a.stance.clone();
        let posture = match &self.leg_path {
            Some((leg, path)) => {
                let mut p = b.posture.clone();
                if let Some(q) = p.get_mut(*leg) {
                    *q = along(path, f * duration_s);
                }
                if let Some(s) = stance.get_mut(*leg) {
                    *s = false;
                }
                p
            }
            None => a
                .posture
                .iter()
                .zip(&b.posture)
                .map(|(qa, qb)| lerp(qa, qb, f))
                .collect(),
        };
        Snapshot {
            clock_s: a.clock_s + f * duration_s,
            body,
            posture,
            stance,
            touch: a.touch.clone(),
        }
    }
}

/// The move time each point of a leg's joint-space path is reached at: each segment as long
/// as its slowest joint needs at its top speed (the simulator's timing).
pub(crate) fn timed_path(
    model: &RobotModel,
    leg: usize,
    start: &[f64],
    waypoints: &[Vec<f64>],
) -> Option<Vec<(f64, Vec<f64>)>> {
    let joints = model.legs().get(leg)?.joints();
    let mut t = 0.0;
    let mut path = vec![(0.0, start.to_vec())];
    let mut from = start;
    for wp in waypoints {
        if wp.len() != joints.len() {
            return None;
        }
        let segment = joints
            .iter()
            .zip(from)
            .zip(wp)
            .map(|((j, a), b)| (b - a).abs() / j.limits().velocity)
            .fold(0.0, f64::max);
        t += segment;
        path.push((t, wp.clone()));
        from = wp;
    }
    Some(path)
}

/// The joints `t` seconds along a timed path (held at its last point after its end).
fn along(path: &[(f64, Vec<f64>)], t: f64) -> Vec<f64> {
    for pair in path.windows(2) {
        let ((t0, a), (t1, b)) = (&pair[0], &pair[1]);
        if t <= *t1 {
            let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
            return lerp(a, b, f.clamp(0.0, 1.0));
        }
    }
    path.last().map(|(_, q)| q.clone()).unwrap_or_default()
}

fn lerp(a: &[f64], b: &[f64], f: f64) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + (y - x) * f).collect()
}

fn lerp_pose(a: &Isometry3<f64>, b: &Isometry3<f64>, f: f64) -> Isometry3<f64> {
    let t = a.translation.vector.lerp(&b.translation.vector, f);
    let r = a.rotation.slerp(&b.rotation, f);
    Isometry3::from_parts(Translation3::from(t), r)
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use nalgebra::Point2 as P2;
    use tca_legged_sim::{SimParams, StartPose};
    use tca_robot::HeightField;

    fn sim() -> LeggedSim {
        let model = Arc::new(RobotModel::builtin("hexapod").unwrap());
        let ground =
            Arc::new(HeightField::flat(P2::new(-2.0, -2.0), P2::new(2.0, 2.0), 0.02, 0.0).unwrap());
        let params = SimParams::for_model(&model);
        LeggedSim::new(
            model,
            ground,
            StartPose {
                x_m: 0.0,
                y_m: 0.0,
                yaw_rad: 0.0,
            },
            params,
        )
        .unwrap()
    }

    #[test]
    fn at_rest_a_sample_is_the_simulators_state() {
        let sim = sim();
        let model = sim.model().clone();
        let t = Snapshot::of(&sim).sample(&model, 7);
        assert_eq!(t.seq, 7);
        assert_eq!(t.t_s, sim.clock_s());
        assert_eq!(t.body, isometry_to_pose(&sim.body()));
        assert!(
            (t.margin_m - sim.margin()).abs() < 1e-9,
            "{} vs {}",
            t.margin_m,
            sim.margin()
        );
        let com = sim.centre_of_mass();
        assert!((t.com.x_m - com.x).abs() < 1e-9 && (t.com.z_m - com.z).abs() < 1e-9);
        let total: f64 = t.legs.iter().map(|l| l.force_n).sum();
        assert!(
            (total - model.total_mass() * G).abs() < 1e-6,
            "forces add up to the weight"
        );
        for (i, l) in t.legs.iter().enumerate() {
            let s = sim.leg_state(&l.leg).unwrap();
            assert_eq!(l.joints, s.joints);
            assert!((l.foot.z_m - s.foot.z_m).abs() < 1e-9);
            assert_eq!(l.stance, sim.stance()[i]);
            assert!((l.force_n - s.force_n).abs() < 1e-9);
        }
    }

    #[test]
    fn a_leg_move_is_sampled_along_its_way_points_with_the_leg_in_the_air() {
        let mut sim = sim();
        let model = sim.model().clone();
        let before = Snapshot::of(&sim);
        let leg = 0;
        let name = model.legs()[leg].name().to_owned();
        let q0 = sim.posture()[leg].clone();
        // Lift the foot: whichever way of the second joint raises it.
        let l = &model.legs()[leg];
        let raised = |d: f64| {
            let mut q = q0.clone();
            q[1] += d;
            let z = l.foot_position(&q).unwrap().z;
            (z, q)
        };
        let (za, qa) = raised(0.3);
        let (zb, qb) = raised(-0.3);
        let up = if za > zb { qa } else { qb };
        let waypoints = vec![up.clone()];
        let report = sim.leg_move(&name, &waypoints, false).unwrap();
        let after = Snapshot::of(&sim);
        let path = timed_path(&model, leg, &q0, &waypoints).unwrap();
        let planned = path.last().unwrap().0;
        assert!(
            (planned - report.duration_s).abs() < 1e-9,
            "the simulator's timing: {planned} vs {}",
            report.duration_s
        );
        let motion = Motion {
            started: Instant::now(),
            wall: Duration::from_secs(2),
            before: before.clone(),
            after: after.clone(),
            leg_path: Some((leg, path.clone())),
        };
        // Half-way in time the leg is half-way up.
        let mid = motion.at(Duration::from_secs(1));
        for ((a, b), c) in mid.posture[leg].iter().zip(&q0).zip(&up) {
            assert!((a - (b + c) / 2.0).abs() < 1e-9, "{:?}", mid.posture[leg]);
        }
        assert!(!mid.stance[leg], "the leg is in the air");
        let sample = mid.sample(&model, 1);
        assert_eq!(sample.legs[leg].force_n, 0.0);
        assert!((sample.t_s - (before.clock_s + report.duration_s / 2.0)).abs() < 1e-9);
        let rest = before.sample(&model, 0).legs[leg].foot.z_m;
        let top = after.sample(&model, 2).legs[leg].foot.z_m;
        assert!(rest < sample.legs[leg].foot.z_m && sample.legs[leg].foot.z_m < top);
        // At the end, the state after.
        assert_eq!(motion.at(Duration::from_secs(3)), after);
        assert_eq!(motion.at(Duration::ZERO).posture[leg], q0);
    }
}
