//! The moves the foot-level search tries from a stance, in the paper's order of priority,
//! and the footholds it offers a foot, ranked by how many route cells ahead they stay
//! usable. The range maps choose and rank; the search puts each move to the checks on the
//! robot's legs ([`footcheck`](crate::footcheck)) as it comes to it.

use std::rc::Rc;

use nalgebra::{Point2, Point3};
use tca_stability::support_polygon;

use crate::footplan::{FootCell, FootSearch, FootStep, Stance};
use crate::legs::LegPose;
use crate::validity::foot_interval;

/// Advances the search takes from one stance (at different body heights).
const ADVANCES: usize = 2;
/// Footholds offered per foot and reason, as a multiple of the search's `candidates` (the
/// checks on the legs, made as the search comes to each, refuse some).
const LOOK_FACTOR: usize = 4;

impl FootSearch<'_> {
    /// Whether the standing feet (less `skip`) hold the CG `com` (body frame) at route cell
    /// `k` with the margin, on the feet's cell centres.
    fn stable(
        &self,
        k: usize,
        feet: &[Option<FootCell>],
        skip: Option<usize>,
        com: Point3<f64>,
    ) -> bool {
        let pts: Vec<Point2<f64>> = feet
            .iter()
            .enumerate()
            .filter(|(l, _)| Some(*l) != skip)
            .filter_map(|(l, f)| f.map(|f| self.foot_xy(l, f)))
            .collect();
        if pts.len() < 3 {
            return false;
        }
        support_polygon(&pts).signed_distance(self.body(k, 0.0).to_world_xy(com))
            >= self.space.robot().stability_margin_m
    }

    /// How many route cells from `k` on a foothold stays usable for a leg.
    fn usefulness(&self, leg: usize, k: usize, f: FootCell) -> usize {
        if let Some(&u) = self.useful.borrow().get(&(leg, k, f)) {
            return u;
        }
        let u = self.count_useful(leg, k, f);
        self.useful.borrow_mut().insert((leg, k, f), u);
        u
    }

    fn count_useful(&self, leg: usize, k: usize, f: FootCell) -> usize {
        let robot = self.space.robot();
        let Some(g) = self.space.foot().height(f.0, f.1) else {
            return 0;
        };
        let end = (k + self.params.lookahead).min(self.route.len());
        (k..end)
            .take_while(|&j| {
                self.range(leg, j, f).is_some_and(|(z_lo, z_hi, _)| {
                    let (_, b) = foot_interval(g, robot.foot_radius[leg], z_lo, z_hi);
                    b >= self.min_h[j]
                })
            })
            .count()
    }

    /// Footholds for `leg` at the stance's route cell, by the range maps: valid, free, in
    /// range there (with room to rise, the body at the stance's height) and at the next cell,
    /// in quadrant `want` of the next cell (or of this one, `want_at_current`) if given;
    /// best first.
    fn footholds(
        &self,
        s: &Stance,
        leg: usize,
        want: Option<u8>,
        want_at_current: bool,
    ) -> Vec<FootCell> {
        let k = s.k;
        let z = s.body_z();
        let rise = self.space.robot().swing_rise_m;
        let next = (k + 1 < self.route.len()).then_some(k + 1);
        let cg = self.route[k];
        let robot = self.space.robot();
        let table = &robot.headings[usize::from(cg.it)];
        let ahead = self.route[(k + self.params.lookahead).min(self.route.len() - 1)];
        let (ax, ay) = (f64::from(ahead.ix - cg.ix), f64::from(ahead.iy - cg.iy));
        let mut out: Vec<(usize, f64, FootCell)> = Vec::new();
        for c in &table.legs[leg] {
            let f = (cg.ix + c.di, cg.iy + c.dj);
            if Some(f) == s.feet[leg] || !self.space.foot().valid(f.0, f.1) {
                continue;
            }
            if s.feet
                .iter()
                .enumerate()
                .any(|(l, o)| l != leg && *o == Some(f))
            {
                continue;
            }
            if let Some(q) = want {
                let quadrant = if want_at_current {
                    Some(c.quadrant)
                } else {
                    next.and_then(|n| self.range(leg, n, f)).map(|r| r.2)
                };
                if quadrant != Some(q) {
                    continue;
                }
            }
            if let Some(n) = next
                && self.range(leg, n, f).is_none()
            {
                continue;
            }
            if !self
                .foot_heights(leg, k, f)
                .is_some_and(|(a, b)| a + rise <= z && z <= b)
            {
                continue;
            }
            // Ties (near the route's end) go to the foothold farthest along the way ahead.
            let forward = f64::from(c.di) * ax + f64::from(c.dj) * ay;
            out.push((self.usefulness(leg, k, f), forward, f));
        }
        out.sort_by(|a, b| b.0.cmp(&a.0).then(b.1.total_cmp(&a.1)).then(a.2.cmp(&b.2)));
        out.into_iter().map(|(_, _, f)| f).collect()
    }

    /// The moves from a stance, in the order of priority (not yet checked on the legs).
    pub(crate) fn moves(&self, s: &Stance) -> Offer {
        let k = s.k;
        let mut out = Offer::default();
        let Some(n) = (k + 1 < self.route.len()).then_some(k + 1) else {
            return out;
        };
        let Some(poses) = self.poses(s) else {
            return out;
        };
        let com = self.com_of(&poses);
        drop(poses);
        let legs = s.feet.len();
        let in_range_next: Vec<bool> = (0..legs)
            .map(|l| s.feet[l].is_none_or(|f| self.range(l, n, f).is_some()))
            .collect();
        let all_in_range = in_range_next.iter().all(|&b| b);
        let heights_next = all_in_range
            .then(|| self.heights(n, &s.feet, None, None))
            .flatten();
        let stable_next = self.stable(n, &s.feet, None, com);
        // 1. Advance the CG.
        if let Some((lo, hi)) = heights_next
            && stable_next
        {
            let group = out.group(ADVANCES);
            for z in self.preferred_heights(lo, hi) {
                let step = FootStep::Advance {
                    to: self.route[n],
                    body_z: z,
                };
                out.push(step, group);
            }
        }
        let can_lift = |leg: usize| self.stable(k, &s.feet, Some(leg), com);
        // A free foot: the rest hold the CG here and at the next cell.
        let free: Vec<bool> = (0..legs)
            .map(|l| match s.feet[l] {
                None => true,
                Some(_) => can_lift(l) && self.stable(n, &s.feet, Some(l), com),
            })
            .collect();
        let push_places = |out: &mut Offer, leg: usize, want: Option<u8>, current: bool| {
            if s.feet[leg].is_some() && !can_lift(leg) {
                return;
            }
            self.push_candidates(s, out, leg, want, current);
        };
        // 2. Moving is possible leg by leg but unstable: fill a deficient quadrant.
        if all_in_range && !stable_next {
            let mut have = [false; 4];
            for (l, f) in s.feet.iter().enumerate() {
                if let Some(f) = f
                    && let Some((_, _, q)) = self.range(l, n, *f)
                    && q < 4
                {
                    have[usize::from(q)] = true;
                }
            }
            for q in (0..4u8).filter(|&q| !have[usize::from(q)]) {
                for l in (0..legs).filter(|&l| free[l]) {
                    push_places(&mut out, l, Some(q), false);
                }
            }
        }
        // 3. A free foot at the edge of its range moves; 4. or is lifted if it has nowhere.
        let leaving: Vec<usize> = (0..legs)
            .filter(|&l| s.feet[l].is_some() && !in_range_next[l])
            .collect();
        for &l in leaving.iter().filter(|&&l| free[l]) {
            let before = out.list.len();
            push_places(&mut out, l, None, false);
            if out.list.len() == before
                && let Some(from) = s.feet[l]
                && can_lift(l)
            {
                let group = out.group(1);
                out.push(FootStep::Lift { leg: l, from }, group);
            }
        }
        // Feet in the air come down where they will stay useful.
        for l in (0..legs).filter(|&l| s.feet[l].is_none()) {
            push_places(&mut out, l, None, false);
        }
        // 5. A foot about to leave its range that is not free: a free foot goes into its
        // quadrant so that it becomes free.
        for &l in leaving.iter().filter(|&&l| !free[l]) {
            let Some(f) = s.feet[l] else { continue };
            let Some((_, _, q)) = self.range(l, k, f) else {
                continue;
            };
            if q > 3 {
                continue;
            }
            for m in (0..legs).filter(|&m| m != l && free[m]) {
                push_places(&mut out, m, Some(q), true);
            }
        }
        // Last, so that the search stays complete over what it may try: any foot that may
        // lift moves to any of its best footholds, and a foot that heights forbid lifts.
        for l in 0..legs {
            push_places(&mut out, l, None, false);
        }
        if heights_next.is_none() && all_in_range {
            for l in 0..legs {
                if let Some(from) = s.feet[l]
                    && can_lift(l)
                {
                    let group = out.group(1);
                    out.push(FootStep::Lift { leg: l, from }, group);
                }
            }
        }
        out
    }

    /// Offers the placements of `leg` on its best footholds, up to [`LOOK_FACTOR`] times
    /// the search's `candidates`, of which the search takes at most `candidates`.
    fn push_candidates(
        &self,
        s: &Stance,
        out: &mut Offer,
        leg: usize,
        want: Option<u8>,
        current: bool,
    ) {
        let most = LOOK_FACTOR * self.params.candidates;
        let group = out.group(self.params.candidates);
        for f in self.footholds(s, leg, want, current).into_iter().take(most) {
            let step = FootStep::Place {
                leg,
                from: s.feet[leg],
                to: f,
            };
            out.push(step, group);
        }
    }

    /// Whether a move from stance `s` (legs `poses`) passes the checks on the robot's legs.
    pub(crate) fn move_ok(&self, s: &Stance, poses: &[Rc<LegPose>], step: &FootStep) -> bool {
        match *step {
            FootStep::Advance { body_z, .. } => self.advance_ok(s, body_z),
            FootStep::Place { leg, to, .. } => self.place_ok(s, poses, leg, to),
            FootStep::Lift { leg, .. } => self.lift_ok(s, poses, leg),
        }
    }
}

/// The moves offered from a stance, in order, each in a group (the advances; the
/// placements of one foot for one reason; a lift) of which the search enters at most the
/// group's cap: the best few of each kind that pass the checks on the legs.
#[derive(Debug, Default)]
pub(crate) struct Offer {
    /// The moves and their groups.
    pub(crate) list: Vec<(FootStep, usize)>,
    /// Per group, how many of its moves the search may enter.
    pub(crate) caps: Vec<usize>,
}

impl Offer {
    /// A new group of at most `cap` moves.
    fn group(&mut self, cap: usize) -> usize {
        self.caps.push(cap);
        self.caps.len() - 1
    }

    /// Offers a move not offered yet.
    fn push(&mut self, step: FootStep, group: usize) {
        if !self.list.iter().any(|(s, _)| *s == step) {
            self.list.push((step, group));
        }
    }
}
