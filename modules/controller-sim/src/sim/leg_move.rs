//! `legMove`: joint-space way-points, checked against the true terrain along the way, with
//! the optional transition mode on the last segment.

use std::time::Duration;

use nalgebra::{Point2, Point3};
use rand::Rng;
use tca_robot::{Joint, JointPosition};

use super::LegSimulator;
use super::error::{Result, SimError};
use super::faults::{gaussian, happens};
use super::report::{Contact, MoveReport, PathSample};
use super::trajectory::JointTrajectory;

/// How far along its motion the foot is probed to tell a touch-down from a strike, metres.
const CONTACT_PROBE_M: f64 = 0.02;
/// A contact is a strike when the terrain rises more than the foot descends over the probe
/// by this much, metres.
const STRIKE_TOLERANCE_M: f64 = 0.01;
/// Bisection steps locating a contact in time.
const BISECTION_STEPS: usize = 40;

/// How a move ends before its last sample.
enum Stop {
    /// Transition reached its force: the leg stops here, foot planted.
    Pressed { t: f64, contact: Point3<f64> },
    /// An error; the leg stops at `t`.
    Fault { t: f64, error: SimError },
}

impl LegSimulator {
    /// `legMove`: moves the leg through joint-space way-points (§4.2). All joints arrive at
    /// each way-point together; segments are joined by constant-acceleration blends at the
    /// joint limits. With `transition`, the last segment stops when the foot meets the ground
    /// and the force reaches the set point ([`set_trans_force`](Self::set_trans_force)); reaching
    /// the last way-point first is a [`SimError::NoContact`].
    ///
    /// The path is checked against the true terrain at least every
    /// `simulation.collision_step_m` of foot travel; a strike stops the leg at the contact
    /// A foot that stands on the ground leaves it straight up: when the first way-point
    /// lifts the foot and also moves it sideways, a pure lift to the first way-point's
    /// height goes first, so the loaded foot is never dragged (a move planned ahead starts
    /// from where the leg was expected to be, which compliance leaves a few centimetres
    /// off).
    fn lift_first(&self, waypoints: &[JointPosition]) -> Option<Vec<JointPosition>> {
        let first = waypoints.first()?;
        let now = self.joints;
        let on_ground = self.planted.is_some() || self.gap(&self.free_foot(&now)) <= 0.0;
        let sideways = (first.shoulder_rad - now.shoulder_rad).abs() > 1e-6
            || (first.elbow_rad - now.elbow_rad).abs() > 1e-6;
        if !(on_ground && sideways && first.vertical_m < now.vertical_m) {
            return None;
        }
        let lift = JointPosition::new(now.shoulder_rad, now.elbow_rad, first.vertical_m);
        Some(
            std::iter::once(lift)
                .chain(waypoints.iter().copied())
                .collect(),
        )
    }

    /// with a [`SimError::Collision`]. Bad way-points are refused and the leg does not move.
    pub fn leg_move(
        &mut self,
        waypoints: &[JointPosition],
        transition: bool,
    ) -> Result<MoveReport> {
        self.validate_waypoints(waypoints)?;
        let lifted = self.lift_first(waypoints);
        let waypoints = lifted.as_deref().unwrap_or(waypoints);
        let traj = JointTrajectory::plan(&self.kin, &self.joints, waypoints);
        let total = traj.duration_s();
        let dt = self.sample_step(&traj);
        let last_segment = traj.last_segment_start_s();
        let trip = if happens(&mut self.rng, self.faults.limit_switch_probability) {
            let joint = Joint::ALL[self.rng.random_range(0..3)];
            Some((self.rng.random_range(0.0..=total), joint))
        } else {
            None
        };
        tracing::debug!(
            segments = traj.segments(),
            duration_s = total,
            transition,
            "legMove"
        );

        // Is the foot on the ground at the start? Then it stays pinned until it lifts off.
        let start_free = self.free_foot(&self.joints);
        let (start_gap, start_height) = self.gap_and_height(&start_free);
        let mut rest: Option<Point3<f64>> = self.planted.or_else(|| {
            (start_gap <= 0.0).then(|| Point3::new(start_free.x, start_free.y, start_height))
        });
        // Where the leg's kinematic foot was when the contact began: a drag is the leg moving
        // sideways from there while loaded. (The pinned foot itself may sit a little off the
        // kinematic one, by the compliance deflection left from a body move.)
        let mut anchor = Point2::new(start_free.x, start_free.y);

        let period = self.params.simulation.report_period_s;
        let mut path = vec![PathSample {
            time: Duration::ZERO,
            joints: self.joints,
            foot_world: self.true_foot_position(),
        }];
        let mut next_report = period;
        let mut t_prev = 0.0;
        let mut k = 0usize;
        let stop = loop {
            k += 1;
            let t = (k as f64 * dt).min(total);
            if let Some((t_trip, joint)) = trip
                && t_trip <= t
            {
                let position = traj.position_at(t_trip).get(joint);
                break Some(Stop::Fault {
                    t: t_trip,
                    error: SimError::LimitSwitch { joint, position },
                });
            }
            let q = traj.position_at(t);
            let foot = self.free_foot(&q);
            let (gap, height) = self.gap_and_height(&foot);
            if let Some(r) = rest {
                if gap > 0.0 {
                    rest = None;
                } else {
                    let slid = (Point2::new(foot.x, foot.y) - anchor).norm();
                    if slid > self.params.simulation.drag_tolerance_m {
                        let error = SimError::Collision {
                            foot_world: r,
                            terrain_height_m: height,
                            joints: q,
                            dragged: true,
                        };
                        break Some(Stop::Fault { t, error });
                    }
                    if transition
                        && t >= last_segment
                        && self.force_against(&r, &q) >= self.trans_force_n
                    {
                        let ts = self.bisect(t_prev, t, |s, tt| {
                            s.force_against(&r, &traj.position_at(tt)) >= s.trans_force_n
                        });
                        break Some(Stop::Pressed { t: ts, contact: r });
                    }
                }
            } else if gap <= 0.0 {
                let tc = self.bisect(t_prev, t, |s, tt| {
                    s.gap(&s.free_foot(&traj.position_at(tt))) <= 0.0
                });
                let qc = traj.position_at(tc);
                let fc = self.free_foot(&qc);
                let (_, hc) = self.gap_and_height(&fc);
                if transition && tc >= last_segment && self.is_touchdown(&traj, tc, &fc) {
                    // Keep pressing along the path until the force reaches the set point.
                    rest = Some(Point3::new(fc.x, fc.y, fc.z.max(hc)));
                    anchor = Point2::new(fc.x, fc.y);
                    t_prev = tc;
                    continue;
                }
                let error = SimError::Collision {
                    foot_world: fc,
                    terrain_height_m: hc,
                    joints: qc,
                    dragged: false,
                };
                break Some(Stop::Fault { t: tc, error });
            }
            if t >= next_report && t < total {
                path.push(PathSample {
                    time: secs(t),
                    joints: q,
                    foot_world: rest.unwrap_or(foot),
                });
                next_report += period;
            }
            if t >= total {
                break None;
            }
            t_prev = t;
        };

        match stop {
            Some(Stop::Fault { t, error }) => {
                self.joints = traj.position_at(t);
                self.planted = match error {
                    // A struck foot stands against the terrain, unloaded.
                    SimError::Collision { dragged: false, .. } => None,
                    _ => rest,
                };
                self.clock += secs(t);
                tracing::debug!(%error, "legMove stopped");
                Err(error)
            }
            Some(Stop::Pressed { t, contact }) => {
                self.joints = traj.position_at(t);
                self.planted = Some(contact);
                self.clock += secs(t);
                let force_n = self.vertical_force_n();
                path.push(PathSample {
                    time: secs(t),
                    joints: self.joints,
                    foot_world: contact,
                });
                self.apply_joint_noise()?;
                Ok(MoveReport {
                    duration: secs(t),
                    path,
                    contact: Some(Contact {
                        foot_world: contact,
                        force_n,
                    }),
                    final_joints: self.joints,
                })
            }
            None => {
                self.joints = traj.position_at(total);
                self.planted = rest;
                self.clock += secs(total);
                path.push(PathSample {
                    time: secs(total),
                    joints: self.joints,
                    foot_world: self.true_foot_position(),
                });
                if transition {
                    let error = SimError::NoContact {
                        force_n: self.vertical_force_n(),
                        set_point_n: self.trans_force_n,
                        joints: self.joints,
                    };
                    tracing::debug!(%error, "legMove stopped");
                    return Err(error);
                }
                self.apply_joint_noise()?;
                Ok(MoveReport {
                    duration: secs(total),
                    path,
                    contact: None,
                    final_joints: self.joints,
                })
            }
        }
    }

    /// Time step between terrain checks: the foot moves at most `collision_step_m` per step.
    fn sample_step(&self, traj: &JointTrajectory) -> f64 {
        let [ws, we, vz] = traj.peak_speeds();
        let (upper, lower) = self.kin.link_lengths_m();
        let foot_speed = ws * (upper + lower) + we * lower + vz;
        if foot_speed > 0.0 {
            self.params.simulation.collision_step_m / foot_speed
        } else {
            f64::INFINITY
        }
    }

    /// Force on a foot pinned at `rest` with the leg at `q`.
    fn force_against(&self, rest: &Point3<f64>, q: &JointPosition) -> f64 {
        (self.params.contact.stiffness_n_per_m * (rest.z - self.free_foot(q).z)).max(0.0)
    }

    /// First time in `(lo, hi]` where `cond` holds, given it fails at `lo` and holds at `hi`.
    fn bisect(&self, mut lo: f64, mut hi: f64, cond: impl Fn(&Self, f64) -> bool) -> f64 {
        for _ in 0..BISECTION_STEPS {
            let mid = 0.5 * (lo + hi);
            if cond(self, mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }

    /// Whether a contact at `tc` is the foot coming down on the ground (a touch-down) rather
    /// than striking the side of something: the vertical axis must be extending, and just
    /// past the contact the terrain must not rise into the foot more than the foot descends.
    fn is_touchdown(&self, traj: &JointTrajectory, tc: f64, contact: &Point3<f64>) -> bool {
        if traj.velocity_at(tc)[2] <= 0.0 {
            return false;
        }
        let delta = 1e-3;
        let before = self.free_foot(&traj.position_at(tc - delta));
        let after = self.free_foot(&traj.position_at(tc + delta));
        let dir = after - before;
        let Some(dir) = dir.try_normalize(1e-12) else {
            return true;
        };
        let probe = contact + dir * CONTACT_PROBE_M;
        let (gap, _) = self.gap_and_height(&probe);
        let descent = contact.z - probe.z;
        -gap <= descent + STRIKE_TOLERANCE_M
    }

    /// Joint positioning noise at the end of a move; a large error is a servo fault.
    fn apply_joint_noise(&mut self) -> Result<()> {
        let noise = self.faults.joint_noise;
        let sigmas = [noise.shoulder_rad, noise.elbow_rad, noise.vertical_m];
        if sigmas.iter().all(|s| *s == 0.0) {
            return Ok(());
        }
        let mut q = self.joints.to_array();
        let mut errors = [0.0; 3];
        for j in 0..3 {
            errors[j] = sigmas[j] * gaussian(&mut self.rng);
            q[j] += errors[j];
        }
        self.joints = JointPosition::from_array(q);
        let sim = &self.params.simulation;
        for (j, joint) in Joint::ALL.into_iter().enumerate() {
            let tolerance = if joint == Joint::Vertical {
                sim.servo_error_m
            } else {
                sim.servo_error_rad
            };
            if errors[j].abs() > tolerance {
                return Err(SimError::ServoError {
                    joint,
                    error: errors[j],
                });
            }
        }
        if self.planted.is_none() {
            let foot = self.free_foot(&self.joints);
            let (gap, height) = self.gap_and_height(&foot);
            if gap < 0.0 {
                return Err(SimError::Collision {
                    foot_world: foot,
                    terrain_height_m: height,
                    joints: self.joints,
                    dragged: false,
                });
            }
        }
        Ok(())
    }
}

fn secs(t: f64) -> Duration {
    Duration::from_secs_f64(t.max(0.0))
}
