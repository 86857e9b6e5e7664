//! Leg moves: joint-space straight segments, the foot lifted at the start and (with a
//! transition) put down at ground contact.

use tca_legged_model::JointKind;
use tca_stability::margin_along_path;

use crate::error::{MoveCommand, MoveError};
use crate::report::{FootEvent, MoveReport};
use crate::sim::LeggedSim;

/// One straight joint-space segment of a leg move.
struct Segment {
    from: Vec<f64>,
    to: Vec<f64>,
    /// Move time at its start, seconds.
    t0: f64,
    /// Its duration, seconds.
    duration: f64,
    /// Collision samples along it.
    samples: usize,
}

impl Segment {
    fn at(&self, f: f64) -> Vec<f64> {
        self.from
            .iter()
            .zip(&self.to)
            .map(|(a, b)| a + (b - a) * f)
            .collect()
    }
}

/// A sample of a move that the leg reached: its joints and the move time.
struct Reached {
    q: Vec<f64>,
    t: f64,
}

const CMD: MoveCommand = MoveCommand::Leg;

/// How far a point of the leg can travel per unit of each joint's motion along a segment
/// from `a` to `b`: for a revolute joint the largest distance from its axis to the foot
/// sphere's far side or to a later joint, at either end (the slides between move linearly,
/// so the ends bound it); 1 for a prismatic joint. Summed over the joints times their
/// motion, it bounds how far the foot and the joints move, and so the links between them.
fn levers(leg: &tca_legged_model::Leg, a: &[f64], b: &[f64]) -> Vec<f64> {
    let joints = leg.joints();
    let mut levers: Vec<f64> = joints
        .iter()
        .map(|j| match j.kind() {
            JointKind::Prismatic { .. } => 1.0,
            JointKind::Revolute { .. } => 0.0,
        })
        .collect();
    for q in [a, b] {
        let (Ok(frames), Ok(foot)) = (leg.joint_frames(q), leg.foot_position(q)) else {
            return vec![leg.reach_bound(); leg.dof()];
        };
        for (k, j) in joints.iter().enumerate() {
            let JointKind::Revolute { axis } = j.kind() else {
                continue;
            };
            let frame = &frames[k];
            let origin = nalgebra::Point3::from(frame.translation.vector);
            let axis = frame.rotation * axis.into_inner();
            let off_axis = |p: nalgebra::Point3<f64>| {
                let d = p - origin;
                (d - axis * d.dot(&axis)).norm()
            };
            let mut lever = off_axis(foot) + leg.foot_radius();
            for later in &frames[k..] {
                lever = lever.max(off_axis(nalgebra::Point3::from(later.translation.vector)));
            }
            levers[k] = levers[k].max(lever);
        }
    }
    levers
}

impl LeggedSim {
    /// Moves one leg through joint-space way-points (one value per moving joint each),
    /// every joint arriving at each way-point together, each segment as fast as the
    /// slowest joint allows.
    ///
    /// A standing foot lifts off at the start: refused (nothing moves) unless at least three
    /// other feet stand and the centre of mass stays in their polygon along the whole move.
    /// With `transition` the last segment stops where the foot sphere touches the ground and
    /// the foot stands there; reaching its end in the air is [`MoveError::NoContact`] (the
    /// leg stays there). A link of the leg touching the terrain, or the foot driven into it
    /// before the transition segment, counts a collision and stops the leg just before.
    /// Way-points of the wrong length, not finite, or outside the joint limits are refused.
    pub fn leg_move(
        &mut self,
        leg: &str,
        waypoints: &[Vec<f64>],
        transition: bool,
    ) -> Result<MoveReport, MoveError> {
        if self.fallen {
            return Err(MoveError::Fallen { command: CMD });
        }
        let i = self.leg_index(leg, CMD)?;
        let model = self.model.clone();
        let l = &model.legs()[i];
        let refused = |reason: String| MoveError::Refused {
            command: CMD,
            leg: Some(leg.to_owned()),
            reason,
        };
        if waypoints.is_empty() {
            return Err(refused("no way-points; give at least one".into()));
        }
        for (k, wp) in waypoints.iter().enumerate() {
            if wp.len() != l.dof() {
                return Err(refused(format!(
                    "way-point {k} has {} values, but leg `{leg}` has {} moving joints ({}); \
                     give one value per joint, body outwards",
                    wp.len(),
                    l.dof(),
                    l.joints()
                        .iter()
                        .map(|j| j.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            for (j, v) in l.joints().iter().zip(wp) {
                if !v.is_finite() {
                    return Err(refused(format!(
                        "way-point {k}: joint `{}` is given {v}, not a finite number",
                        j.name()
                    )));
                }
                let lim = j.limits();
                if !lim.contains(*v) {
                    return Err(MoveError::JointLimit {
                        command: CMD,
                        leg: leg.to_owned(),
                        reason: format!(
                            "way-point {k}: joint `{}` at {v:.4} {} is outside its limits \
                             {:.4}..{:.4}",
                            j.name(),
                            j.kind().unit(),
                            lim.lower,
                            lim.upper
                        ),
                    });
                }
            }
        }
        // Segments and their sampling.
        let step = self.params.collision_step_m;
        let mut segments = Vec::with_capacity(waypoints.len());
        let mut from = self.posture[i].clone();
        let mut t0 = 0.0;
        for wp in waypoints {
            let levers = levers(l, &from, wp);
            let mut duration: f64 = 0.0;
            let mut travel: f64 = 0.0;
            for (((j, a), b), lever) in l.joints().iter().zip(&from).zip(wp).zip(&levers) {
                let d = (b - a).abs();
                duration = duration.max(d / j.limits().velocity);
                travel += d * lever;
            }
            let samples = ((travel / step).ceil() as usize).clamp(1, 100_000);
            segments.push(Segment {
                from: from.clone(),
                to: wp.clone(),
                t0,
                duration,
                samples,
            });
            t0 += duration;
            from = wp.clone();
        }
        // Stability of the stance left while the leg moves, along the whole move.
        let mut stance_after = self.stance.clone();
        stance_after[i] = false;
        let standing = stance_after.iter().filter(|&&s| s).count();
        let support = self.support(&stance_after);
        let mut posture = self.posture.clone();
        let mut path = vec![self.com_at(&self.body, &posture)];
        for s in &segments {
            for k in 1..=s.samples {
                posture[i] = s.at(k as f64 / s.samples as f64);
                path.push(self.com_at(&self.body, &posture));
            }
        }
        let min_margin = if standing < 3 {
            f64::NEG_INFINITY
        } else {
            margin_along_path(&support, &path)
                .map(|m| m.margin_m)
                .unwrap_or(f64::NEG_INFINITY)
        };
        let unstable =
            standing < 3 || crate::sim::short_of(min_margin, self.params.min_lift_margin_m);
        if unstable && self.params.refuse_unstable_moves {
            let reason = if standing < 3 {
                format!(
                    "lifting leg `{leg}` would leave {standing} feet standing; at least three \
                     must stand"
                )
            } else {
                format!(
                    "while leg `{leg}` moves the centre of mass would come within {min_margin:.3} m \
                     of the edge of the other feet's support polygon (the minimum is {:.3} m, \
                     negative is outside)",
                    self.params.min_lift_margin_m
                )
            };
            return Err(MoveError::Unstable {
                command: CMD,
                leg: Some(leg.to_owned()),
                margin_m: min_margin,
                reason,
            });
        }
        self.run_leg_move(i, &segments, transition, min_margin)
    }

    fn run_leg_move(
        &mut self,
        i: usize,
        segments: &[Segment],
        transition: bool,
        min_margin: f64,
    ) -> Result<MoveReport, MoveError> {
        let model = self.model.clone();
        let l = &model.legs()[i];
        let tol = self.params.contact_tolerance_m;
        let mut report = self.begin_move(min_margin);
        if self.stance[i] {
            self.sag = self.begin_sag(i);
            self.stance[i] = false;
            self.push_event(&mut report, i, false);
        }
        let support = self.support(&self.stance);
        let standing = self.stance.iter().filter(|&&s| s).count();
        if standing < 3 {
            return Err(self.finish_tip_over(report, f64::NEG_INFINITY));
        }
        let mut reached = Reached {
            q: self.posture[i].clone(),
            t: 0.0,
        };
        let last = segments.len() - 1;
        let mut posture = self.posture.clone();
        // Parts of the robot touching are counted once a move; the move goes on.
        let mut self_contact = None;
        for (k, seg) in segments.iter().enumerate() {
            let in_transition = transition && k == last;
            let mut prev_f = 0.0;
            for n in 1..=seg.samples {
                let f = n as f64 / seg.samples as f64;
                let q = seg.at(f);
                // Where the leg really is: the body and the limb sagging under load.
                let real = self.sagged(i, &q, true);
                self.take_sag(&real);
                let (body, q_real) = (real.body, real.q.clone());
                posture[i] = q_real.clone();
                report.samples += 1;
                if real.drag_m > crate::sag::DRAG_TOLERANCE_M && !in_transition {
                    // A foot still bearing load, moved sideways: dragged across the ground.
                    let at = body
                        * l.foot_position(&q_real)
                            .unwrap_or_else(|_| nalgebra::Point3::origin());
                    tracing::debug!(drag_m = real.drag_m, ?at, "a loaded foot moved sideways");
                    let hits = vec![(l.foot_link().to_owned(), at)];
                    return Err(self.stop_on_collision(report, i, reached, hits));
                }
                let hits = self.link_contacts(&body, &posture, Some(i));
                if !hits.is_empty() {
                    return Err(self.stop_on_collision(report, i, reached, hits));
                }
                if self_contact.is_none()
                    && let Ok(Some(contact)) = self.model.self_contact(&posture)
                {
                    tracing::debug!(first = %contact.first, second = %contact.second, "parts of the robot touched");
                    self.counters.self_collisions += 1;
                    self_contact = Some(contact);
                }
                let clearance = self.clearance(&body, i, &q_real);
                if in_transition && clearance <= 0.0 {
                    // Touch-down between the previous sample and this one.
                    let f = self.contact_fraction(i, seg, prev_f, f);
                    let real = self.sagged(i, &seg.at(f), false);
                    let (body, q_real) = (real.body, real.q);
                    let centre = body
                        * l.foot_position(&q_real)
                            .unwrap_or_else(|_| nalgebra::Point3::origin());
                    // The load returns and the body rises back over the standing feet:
                    // the leg reaches down to where its foot touched.
                    self.posture[i] = if self.sag.take().is_some() {
                        self.reach_to(i, &centre, &seg.at(f))
                    } else {
                        seg.at(f)
                    };
                    self.stance[i] = true;
                    self.anchors[i] = centre;
                    self.advance(&mut report, seg.t0 + f * seg.duration);
                    self.push_event(&mut report, i, true);
                    report.contact = self.contact_point(i);
                    self.last = Some(report.clone());
                    return Ok(report);
                }
                if !in_transition && clearance < -tol {
                    let at = body
                        * l.foot_position(&q_real)
                            .unwrap_or_else(|_| nalgebra::Point3::origin());
                    tracing::debug!(
                        clearance,
                        segment = k,
                        ?at,
                        "a swinging foot went into the ground"
                    );
                    let hits = vec![(l.foot_link().to_owned(), at)];
                    return Err(self.stop_on_collision(report, i, reached, hits));
                }
                // Checked before moving when unstable moves are refused.
                let margin = if self.params.refuse_unstable_moves {
                    0.0
                } else {
                    tca_stability::stability_margin(&support, self.com_at(&self.body, &posture))
                };
                if crate::sim::short_of(margin, 0.0) {
                    self.posture[i] = q;
                    self.advance(&mut report, seg.t0 + f * seg.duration);
                    return Err(self.finish_tip_over(report, margin));
                }
                reached = Reached {
                    q,
                    t: seg.t0 + f * seg.duration,
                };
                prev_f = f;
            }
        }
        self.posture[i] = reached.q;
        let end = segments.last().map(|s| s.t0 + s.duration).unwrap_or(0.0);
        self.advance(&mut report, end);
        self.last = Some(report.clone());
        if transition {
            return Err(MoveError::NoContact {
                leg: l.name().to_owned(),
            });
        }
        Ok(report)
    }

    /// The fraction of `seg` in `[lo, hi]` where the foot touches: clear at `lo` (or
    /// touching already), touching at `hi`.
    fn contact_fraction(&self, i: usize, seg: &Segment, lo: f64, hi: f64) -> f64 {
        let clear = |f: f64| {
            let s = self.sagged(i, &seg.at(f), false);
            self.clearance(&s.body, i, &s.q)
        };
        if clear(lo) <= 0.0 {
            return lo;
        }
        let (mut lo, mut hi) = (lo, hi);
        // 2^-24 of a sample step: far below the contact tolerance.
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if clear(mid) <= 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }

    /// Advances the clock to `t` seconds into the move.
    pub(crate) fn advance(&mut self, report: &mut MoveReport, t: f64) {
        let t = t.max(report.duration_s);
        report.duration_s = t;
        self.clock_s = report.start_s + t;
    }

    pub(crate) fn push_event(&self, report: &mut MoveReport, i: usize, stance: bool) {
        let at = self
            .contact_point(i)
            .unwrap_or_else(nalgebra::Point3::origin);
        report.events.push(FootEvent {
            leg: i,
            leg_name: self.model.legs()[i].name().to_owned(),
            stance,
            at,
            t_s: self.clock_s,
            state: self.support_state(),
        });
    }

    fn stop_on_collision(
        &mut self,
        mut report: MoveReport,
        i: usize,
        reached: Reached,
        hits: Vec<(String, nalgebra::Point3<f64>)>,
    ) -> MoveError {
        self.posture[i] = reached.q;
        self.advance(&mut report, reached.t);
        self.counters.collisions += hits.len() as u32;
        self.last = Some(report);
        let (link, at) = hits
            .into_iter()
            .next()
            .unwrap_or_else(|| (String::new(), nalgebra::Point3::origin()));
        tracing::debug!(%link, ?at, "collision with the terrain");
        MoveError::Collision {
            command: CMD,
            leg: Some(self.model.legs()[i].name().to_owned()),
            link,
            at,
        }
    }

    pub(crate) fn finish_tip_over(&mut self, report: MoveReport, margin: f64) -> MoveError {
        self.last = Some(report);
        self.tip_over(CMD, margin)
    }
}
