//! Body moves: the body along a straight line (orientation by slerp) over the standing
//! feet, which stay where they are.

use nalgebra::{Isometry3, Point3, Translation3};
use tca_legged_model::IkOptions;
use tca_stability::{margin_along_path, stability_margin};

use crate::error::{MoveCommand, MoveError};
use crate::pose::is_finite;
use crate::report::MoveReport;
use crate::sim::LeggedSim;

const CMD: MoveCommand = MoveCommand::Body;

/// One planned sample of a body move.
struct Planned {
    body: Isometry3<f64>,
    posture: Vec<Vec<f64>>,
    /// Move time at the sample, seconds.
    t: f64,
}

impl LeggedSim {
    /// Moves the body to `target` (world frame) in a straight line, its orientation
    /// turning by slerp, with the standing feet fixed in the world and each standing leg's
    /// joints following by inverse kinematics; swinging legs keep their joints. The
    /// duration is what the slowest joint needs.
    ///
    /// Refused before moving (nothing moves) with fewer than three feet standing, when a
    /// standing foot would leave its leg's workspace anywhere along the move, or when the
    /// centre of mass would come closer than `min_body_margin_m` to the edge of the support
    /// polygon (outside it for the default 0). A link hitting the terrain (or a swinging
    /// foot driven into it) counts a collision and stops the body just before.
    pub fn body_move(&mut self, target: &Isometry3<f64>) -> Result<MoveReport, MoveError> {
        if self.fallen {
            return Err(MoveError::Fallen { command: CMD });
        }
        if !is_finite(target) {
            return Err(MoveError::Refused {
                command: CMD,
                leg: None,
                reason: "the target pose has a number that is not finite".into(),
            });
        }
        let standing = self.stance.iter().filter(|&&s| s).count();
        if standing < 3 {
            if self.params.refuse_unstable_moves {
                return Err(MoveError::Unstable {
                    command: CMD,
                    leg: None,
                    margin_m: f64::NEG_INFINITY,
                    reason: format!("only {standing} feet stand; a body move needs at least three"),
                });
            }
            self.counters.moves += 1;
            return Err(self.tip_over(CMD, f64::NEG_INFINITY));
        }
        let model = self.model.clone();
        let start = self.body;
        let dp = (target.translation.vector - start.translation.vector).norm();
        let angle = start.rotation.angle_to(&target.rotation);
        let extent = self
            .anchors
            .iter()
            .map(|a| (a - Point3::from(start.translation.vector)).norm())
            .fold(0.0, f64::max);
        let n = (((dp + angle * extent) / self.params.collision_step_m).ceil() as usize)
            .clamp(1, 100_000);
        let support = self.support(&self.stance);
        let tol = self.params.contact_tolerance_m;
        let unstable = |margin: f64, min: f64| MoveError::Unstable {
            command: CMD,
            leg: None,
            margin_m: margin,
            reason: format!(
                "along the move the centre of mass would come within {margin:.3} m of the edge \
                 of the support polygon (the minimum is {min:.3} m, negative is outside)"
            ),
        };
        // Plan: inverse kinematics of every standing leg at every sample.
        let mut plan: Vec<Planned> = Vec::with_capacity(n);
        let mut path = vec![self.centre_of_mass()];
        let mut posture = self.posture.clone();
        let mut t = 0.0;
        for k in 1..=n {
            let f = k as f64 / n as f64;
            let body = Isometry3::from_parts(
                Translation3::from(start.translation.vector.lerp(&target.translation.vector, f)),
                start.rotation.slerp(&target.rotation, f),
            );
            let inverse = body.inverse();
            let mut dt: f64 = 0.0;
            for (i, leg) in model.legs().iter().enumerate() {
                if !self.stance[i] {
                    continue;
                }
                let foot = inverse * self.anchors[i];
                // A standing foot held within the contact tolerance of where it stands is
                // held: a planner's solution at the edge of the workspace then holds here too.
                let tolerance_m = IkOptions::default().tolerance_m.max(tol);
                let mut options = IkOptions::starting_at(&posture[i]);
                options.random_starts = 0;
                options.tolerance_m = tolerance_m;
                let solution = leg
                    .inverse_kinematics(&foot, &options)
                    .or_else(|_| {
                        let mut options = IkOptions::starting_at(&posture[i]);
                        options.tolerance_m = tolerance_m;
                        leg.inverse_kinematics(&foot, &options)
                    })
                    .map_err(|e| MoveError::JointLimit {
                        command: CMD,
                        leg: leg.name().to_owned(),
                        reason: format!(
                            "its standing foot would leave the leg's workspace {:.0} % of \
                             the way along the move ({e})",
                            100.0 * f
                        ),
                    })?;
                for ((j, a), b) in leg.joints().iter().zip(&posture[i]).zip(&solution.joints) {
                    dt = dt.max((b - a).abs() / j.limits().velocity);
                }
                posture[i] = solution.joints;
            }
            t += dt;
            let com = self.com_at(&body, &posture);
            path.push(com);
            // Refuse at the first sample where the margin falls short, before solving
            // the rest of the move.
            let margin = stability_margin(&support, com);
            if crate::sim::short_of(margin, self.params.min_body_margin_m)
                && self.params.refuse_unstable_moves
            {
                return Err(unstable(margin, self.params.min_body_margin_m));
            }
            plan.push(Planned {
                body,
                posture: posture.clone(),
                t,
            });
        }
        let min_margin = margin_along_path(&support, &path)
            .map(|m| m.margin_m)
            .unwrap_or(f64::NEG_INFINITY);
        // Carry it out, checking the terrain at every sample.
        let mut report = self.begin_move(min_margin);
        let mut self_contact = false;
        for p in plan {
            report.samples += 1;
            let mut hits = self.link_contacts(&p.body, &p.posture, None);
            for (i, leg) in model.legs().iter().enumerate() {
                if !self.stance[i] && self.clearance(&p.body, i, &p.posture[i]) < -tol {
                    let at = p.body
                        * leg
                            .foot_position(&p.posture[i])
                            .unwrap_or_else(|_| Point3::origin());
                    hits.push((leg.foot_link().to_owned(), at));
                }
            }
            if !self_contact && let Ok(Some(contact)) = model.self_contact(&p.posture) {
                // Counted once a move; the move goes on.
                tracing::debug!(first = %contact.first, second = %contact.second, "parts of the robot touched");
                self.counters.self_collisions += 1;
                self_contact = true;
            }
            if let Some((link, at)) = hits.first().cloned() {
                self.counters.collisions += hits.len() as u32;
                self.last = Some(report);
                let leg = model
                    .link(&link)
                    .and_then(|l| l.leg())
                    .and_then(|i| model.legs().get(i))
                    .map(|l| l.name().to_owned());
                return Err(MoveError::Collision {
                    command: CMD,
                    leg,
                    link,
                    at,
                });
            }
            let margin = stability_margin(&support, self.com_at(&p.body, &p.posture));
            self.body = p.body;
            self.posture = p.posture;
            self.advance(&mut report, p.t);
            if crate::sim::short_of(margin, 0.0) {
                self.last = Some(report);
                return Err(self.tip_over(CMD, margin));
            }
        }
        self.last = Some(report.clone());
        Ok(report)
    }
}
