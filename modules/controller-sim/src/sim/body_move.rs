//! `bodyMove`: propel the carriage along the rails with the foot planted (§4.2, §4.3).

use std::time::Duration;

use nalgebra::{Point3, Vector2};
use rand::Rng;
use tca_robot::{Joint, JointPosition};

use super::LegSimulator;
use super::body_move_law::BodyMoveLaw;
use super::drive::{Drive, DriveState};
use super::error::{Result, SimError};
use super::faults::{FaultKind, happens};
use super::report::BodyMoveReport;
use super::trajectory::JointTrajectory;

/// Gain pulling the foot's lateral (carriage X) position back onto the planted point, 1/s.
const LATERAL_GAIN_PER_S: f64 = 2.0;
/// Upper bound on control cycles of one body move (a stall guard: 2 hours at 60 Hz).
const MAX_CYCLES: usize = 432_000;

/// A fault drawn for this body move, striking when the carriage has covered a fraction of
/// the distance.
#[derive(Clone, Copy)]
struct Planned {
    slip_at: Option<f64>,
    drop_at: Option<f64>,
    trip_at: Option<(f64, Joint)>,
}

impl LegSimulator {
    /// Joints near `q` whose unloaded deflected foot is at `target` horizontally (carriage
    /// frame; the vertical axis is set by the force servo afterwards).
    fn relieved_joints(
        &self,
        target: &Point3<f64>,
        q: &JointPosition,
    ) -> std::result::Result<JointPosition, tca_robot::KinematicsError> {
        let scale = self.faults.compliance_scale;
        let mut relieved = self.kin.inverse_nearest(target, q)?;
        if scale > 0.0 {
            for _ in 0..6 {
                let d = scale * self.kin.deflection(&relieved, &nalgebra::Vector3::zeros());
                let aim = Point3::new(target.x - d.x, target.y - d.y, target.z);
                relieved = self.kin.inverse_nearest(&aim, &relieved)?;
            }
        }
        Ok(relieved)
    }

    /// `bodyMove`: propels the carriage to world `target_y_m` with the foot planted.
    ///
    /// The foot is first pressed to the compression force (800 lb) and relieved to the
    /// traction force (500 lb). Then the shoulder and elbow are driven at the control rate
    /// (~60 Hz) by the [`BodyMoveLaw`] set with
    /// [`set_body_move_law`](Self::set_body_move_law):
    ///
    /// - [`BodyMoveLaw::Servo`] (the default): the carriage speed is a clipped linear
    ///   function of the position error, the joint rates come from the inverse Jacobian
    ///   (scaled down to the joint speed limits), the foot's position across the rails is
    ///   held, and the move ends within `position_tolerance_m` of the target. A foot that
    ///   slides `slip_detect_m` is noticed and fails the move ([`SimError::Slip`]).
    /// - [`BodyMoveLaw::OpenLoop`]: the joints go along a straight line in joint space to
    ///   the angles the rigid kinematics give for the target, and the move ends there,
    ///   wherever the carriage has got to.
    ///
    /// The carriage goes where the compliant leg pulls it against the rails' friction, and
    /// the foot slides where the pull passes its traction (see the `drive` module). Then
    /// the strain left in the leg is relieved by moving the joints onto the foot's real
    /// position (§4.2, §7.1 item 4). It fails with [`SimError::ExtensionLimit`] (saying how
    /// far it got) before a joint passes its limits or the leg reaches full extension. A
    /// target beyond the rails, or a foot in the air, is refused and nothing moves.
    pub fn body_move(&mut self, target_y_m: f64) -> Result<BodyMoveReport> {
        if !target_y_m.is_finite() {
            return Err(SimError::NotFinite {
                what: format!("body move target y = {target_y_m}"),
            });
        }
        let rails = self.params.rails;
        if target_y_m < rails.y_min_m || target_y_m > rails.y_max_m {
            return Err(SimError::BeyondRails {
                target_y_m,
                min_y_m: rails.y_min_m,
                max_y_m: rails.y_max_m,
            });
        }
        let Some(mut foot) = self.planted else {
            return Err(SimError::FootNotPlanted);
        };
        let faults = self.faults;
        self.body_moves += 1;
        let mut planned = Planned {
            slip_at: happens(&mut self.rng, faults.slip_probability)
                .then(|| self.rng.random_range(0.1..0.9)),
            drop_at: happens(&mut self.rng, faults.force_drop_probability)
                .then(|| self.rng.random_range(0.1..0.9)),
            trip_at: happens(&mut self.rng, faults.limit_switch_probability).then(|| {
                (
                    self.rng.random_range(0.0..1.0),
                    Joint::ALL[self.rng.random_range(0..3)],
                )
            }),
        };
        let mut slip_distance_m = faults.slip_distance_m;
        if let Some(fault) = faults.scheduled.filter(|f| f.body_move == self.body_moves) {
            tracing::debug!(%fault, "injecting a scheduled fault");
            match fault.kind {
                FaultKind::Slip => {
                    planned.slip_at = Some(0.5);
                    // Far enough to be noticed.
                    slip_distance_m =
                        slip_distance_m.max(2.0 * self.params.body_move.slip_detect_m);
                }
                FaultKind::ForceDrop => planned.drop_at = Some(0.5),
                FaultKind::LimitSwitch => planned.trip_at = Some((0.5, Joint::Elbow)),
            }
        }
        let bm = self.params.body_move;
        let start_y = self.carriage.y_m;
        let law = self.body_move_law;
        tracing::debug!(start_y, target_y_m, %law, "bodyMove");
        let open_loop = match law {
            BodyMoveLaw::Servo => None,
            BodyMoveLaw::OpenLoop => Some(self.open_loop_trajectory(start_y, target_y_m)?),
        };

        // 1. Compress the ground, then relieve to the traction force.
        let mut elapsed = 0.0;
        let compressed = self.vertical_for_force(&self.joints, &foot, bm.compress_force_n);
        if compressed > self.kin.limits(Joint::Vertical).max {
            return Err(SimError::ExtensionLimit {
                reached_y_m: start_y,
                target_y_m,
                joint: Joint::Vertical,
            });
        }
        elapsed += self.vertical_move_s(compressed);
        self.joints.vertical_m = compressed;
        let traction = self.vertical_for_force(&self.joints, &foot, bm.traction_force_n);
        elapsed += self.vertical_move_s(traction);
        self.joints.vertical_m = traction;

        // 2. Propel.
        let dt = 1.0 / bm.control_rate_hz;
        let distance = (target_y_m - start_y).abs().max(1e-9);
        let direction = (target_y_m - start_y).signum();
        let carriage_x = self.kin.carriage().x_m;
        let mut q = self.joints;
        let x_hold = self.kin.forward(&q).x;
        let mut y = start_y;
        let mut drive = Drive::new(
            self.drive_compliance(&q),
            self.params.rails.friction_n,
            self.params.rails.breakaway_friction_n,
            self.params.contact.friction_coefficient * bm.traction_force_n,
            carriage_x,
            &DriveState {
                carriage_y_m: y,
                foot,
            },
            self.unloaded_tip(&q),
        );
        let mut t = 0.0;
        let mut slip_left = 0.0;
        let mut injected = 0.0;
        let mut cycles = 0usize;
        let outcome: Result<()> = loop {
            if cycles >= MAX_CYCLES {
                break Err(SimError::ExtensionLimit {
                    reached_y_m: y,
                    target_y_m,
                    joint: Joint::Elbow,
                });
            }
            let mut next = q;
            match &open_loop {
                None => {
                    let error = target_y_m - y;
                    if error.abs() <= bm.position_tolerance_m {
                        break Ok(());
                    }
                    let speed =
                        (bm.gain_per_s * error).clamp(-bm.max_speed_m_per_s, bm.max_speed_m_per_s);
                    let fk = self.kin.forward(&q);
                    let wanted = Vector2::new(LATERAL_GAIN_PER_S * (x_hold - fk.x), -speed);
                    let Ok(mut rates) = self.kin.joint_rates_for(&q, &wanted) else {
                        break Err(SimError::ExtensionLimit {
                            reached_y_m: y,
                            target_y_m,
                            joint: Joint::Elbow,
                        });
                    };
                    let limit = |j: Joint| self.kin.limits(j).max_speed;
                    let over = (rates.x.abs() / limit(Joint::Shoulder))
                        .max(rates.y.abs() / limit(Joint::Elbow));
                    if over > 1.0 {
                        rates /= over;
                    }
                    next.shoulder_rad += rates.x * dt;
                    next.elbow_rad += rates.y * dt;
                }
                Some(trajectory) => {
                    if t >= trajectory.duration_s() {
                        break Ok(());
                    }
                    t = (t + dt).min(trajectory.duration_s());
                    let p = trajectory.position_at(t);
                    next.shoulder_rad = p.shoulder_rad;
                    next.elbow_rad = p.elbow_rad;
                }
            }
            // The force servo keeps the traction force on the foot.
            next.vertical_m = self.vertical_for_force(&next, &foot, bm.traction_force_n);
            if let Some(joint) = self.leaves_safe_range(&next) {
                break Err(SimError::ExtensionLimit {
                    reached_y_m: y,
                    target_y_m,
                    joint,
                });
            }
            let tip = self.unloaded_tip(&next);
            if slip_left > 0.0 {
                // An injected slip: the foot gives way along the rails as the joints pull.
                let s = (self.unloaded_tip(&q).y - tip.y).abs().min(slip_left);
                foot.y -= s * direction;
                slip_left -= s;
                injected += s;
            }
            drive.set_compliance(self.drive_compliance(&next));
            let state = drive.step(
                carriage_x,
                DriveState {
                    carriage_y_m: y,
                    foot,
                },
                tip,
            );
            y = state.carriage_y_m;
            foot = state.foot;
            q = next;
            let force = drive.force_n();
            self.lateral_force_n = [force.x, force.y];
            cycles += 1;
            elapsed += dt;
            let progress = (y - start_y).abs() / distance;
            if let Some((at, joint)) = planned.trip_at
                && progress >= at
            {
                break Err(SimError::LimitSwitch {
                    joint,
                    position: q.get(joint),
                });
            }
            if planned.drop_at.is_some_and(|at| progress >= at) {
                let before = bm.traction_force_n;
                q.vertical_m = self.vertical_for_force(&q, &foot, 0.0);
                self.lateral_force_n = [0.0; 2];
                break Err(SimError::ForceDropOff {
                    carriage_y_m: y,
                    force_before_n: before,
                    force_after_n: 0.0,
                });
            }
            if let Some(at) = planned.slip_at
                && progress >= at
                && injected == 0.0
                && slip_left == 0.0
            {
                slip_left = slip_distance_m;
            }
            // The servo compares the carriage's motion with the joints': a foot that has
            // slid is noticed. The open-loop procedure watches nothing.
            let slid = injected + drive.slid_m();
            if open_loop.is_none() && slid >= bm.slip_detect_m {
                break Err(SimError::Slip {
                    slid_m: slid,
                    carriage_y_m: y,
                });
            }
        };
        let foot_slid_m = injected + drive.slid_m();
        self.joints = q;
        self.planted = Some(foot);
        self.carriage.y_m = y;
        if let Err(error) = outcome {
            self.clock += Duration::from_secs_f64(elapsed);
            tracing::debug!(%error, "bodyMove stopped");
            return Err(error);
        }

        // 3. Relieve the strain: put the joints where the leg, deflected as it is when
        //    unloaded, matches the foot.
        let fk = self.kin.forward(&q);
        let real = self.carriage.to_carriage(self.kin.carriage(), &foot);
        let strain = (self.unloaded_tip(&q) - Vector2::new(real.x, real.y)).norm();
        if let Ok(mut relieved) = self.relieved_joints(&Point3::new(real.x, real.y, fk.z), &q) {
            relieved.vertical_m = self.vertical_for_force(&relieved, &foot, bm.traction_force_n);
            elapsed += JointTrajectory::plan(&self.kin, &q, &[relieved]).duration_s();
            self.joints = relieved;
        }
        self.lateral_force_n = [0.0; 2];
        self.clock += Duration::from_secs_f64(elapsed);
        Ok(BodyMoveReport {
            duration: Duration::from_secs_f64(elapsed),
            start_y_m: start_y,
            final_y_m: y,
            strain_relieved_m: strain,
            control_cycles: cycles,
            law: self.body_move_law,
            target_y_m,
            foot_slid_m,
        })
    }

    /// The open-loop procedure's plan: the joints that, by the rigid kinematics, put the
    /// carriage at `target_y_m` over the foot where the joints say it is, reached along a
    /// straight line in joint space. Refused before anything moves if those joints are
    /// outside the safe range.
    fn open_loop_trajectory(&self, start_y: f64, target_y_m: f64) -> Result<JointTrajectory> {
        let q = self.joints;
        let fk = self.kin.forward(&q);
        let aim = Point3::new(fk.x, fk.y - (target_y_m - start_y), fk.z);
        let unreachable = |joint| SimError::ExtensionLimit {
            reached_y_m: start_y,
            target_y_m,
            joint,
        };
        let mut end = self
            .kin
            .inverse_nearest(&aim, &q)
            .map_err(|_| unreachable(Joint::Elbow))?;
        end.vertical_m = q.vertical_m;
        if let Some(joint) = self.leaves_safe_range(&end) {
            return Err(unreachable(joint));
        }
        Ok(JointTrajectory::plan(&self.kin, &q, &[end]))
    }

    /// Where the joints `q` put an unloaded foot, horizontally: carriage X and Y relative
    /// to the carriage (rigid kinematics plus the deflection under the leg's own weight).
    fn unloaded_tip(&self, q: &JointPosition) -> Vector2<f64> {
        let mut p = self.kin.forward(q);
        let scale = self.faults.compliance_scale;
        if scale > 0.0 {
            p += scale * self.kin.deflection(q, &nalgebra::Vector3::zeros());
        }
        Vector2::new(p.x, p.y)
    }

    /// Horizontal compliance of the leg at the extension of `q`, metres per newton.
    fn drive_compliance(&self, q: &JointPosition) -> f64 {
        let vertical_max = self.kin.limits(Joint::Vertical).max;
        self.faults.compliance_scale
            * self.params.compliance.lateral_m_per_n
            * (q.vertical_m / vertical_max)
    }

    /// Vertical extension that presses a foot pinned at `foot` with `force_n`, the
    /// shoulder and elbow as in `q`.
    fn vertical_for_force(&self, q: &JointPosition, foot: &Point3<f64>, force_n: f64) -> f64 {
        let free_z = self.free_foot(q).z;
        // Extending the vertical axis lowers the free foot one for one.
        q.vertical_m + (free_z - foot.z) + force_n / self.params.contact.stiffness_n_per_m
    }

    /// Time of a pure vertical move of the leg to `vertical_m`, seconds.
    fn vertical_move_s(&self, vertical_m: f64) -> f64 {
        let mut target = self.joints;
        target.vertical_m = vertical_m;
        JointTrajectory::plan(&self.kin, &self.joints, &[target]).duration_s()
    }

    /// The first joint outside its soft limits, or the elbow too close to straight.
    fn leaves_safe_range(&self, q: &JointPosition) -> Option<Joint> {
        for joint in Joint::ALL {
            if !self.kin.limits(joint).contains(q.get(joint)) {
                return Some(joint);
            }
        }
        (q.elbow_rad.abs() < self.params.body_move.min_abs_elbow_rad).then_some(Joint::Elbow)
    }
}
