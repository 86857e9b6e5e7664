//! The foot-level search along a CG route: depth first, each move advancing the CG one
//! cell or moving, placing or lifting one foot, tried in a fixed order of priority.

use std::collections::HashSet;

use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use tca_stability::support_polygon;

use crate::grid::CgCell;
use crate::space::CgSpace;
use crate::validity::{foot_interval, min_body_height};

/// A foot cell: column and row on the CG grid.
pub type FootCell = (i32, i32);

/// Where the robot stands: its place on the route and each foot (`None`: lifted).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Stance {
    /// Index of the CG cell on the route.
    pub k: usize,
    /// Each leg's foot cell, `None` for a foot held up.
    pub feet: Vec<Option<FootCell>>,
}

/// One move of the foot-level plan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum FootStep {
    /// The CG moves to the route's next cell, the feet staying where they are; the body
    /// stands at `body_z` (world Z of its origin) there.
    Advance {
        /// The CG cell reached.
        to: CgCell,
        /// A body height at which every standing foot reaches its ground.
        body_z: f64,
    },
    /// A foot is put down (from the air, or moved from another cell).
    Place {
        /// The leg.
        leg: usize,
        /// Where it was (`None`: in the air).
        from: Option<FootCell>,
        /// Where it goes.
        to: FootCell,
    },
    /// A foot is lifted and kept up.
    Lift {
        /// The leg.
        leg: usize,
        /// Where it stood.
        from: FootCell,
    },
}

/// Budgets of the search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SearchParams {
    /// Footholds tried per foot and reason, best first.
    pub candidates: usize,
    /// Route cells ahead over which a foothold's usefulness is counted.
    pub lookahead: usize,
    /// Foot moves allowed between two CG advances.
    pub moves_between_advances: usize,
    /// Nodes expanded without getting further along the route before the search gives up
    /// on the next cell (the time-out that feeds back to the route planner).
    pub stall_nodes: usize,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams {
            candidates: 4,
            lookahead: 40,
            moves_between_advances: 12,
            stall_nodes: 4_000,
        }
    }
}

/// A plan of foot moves along a route.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootPlan {
    /// The route followed.
    pub route: Vec<CgCell>,
    /// The stance it starts from.
    pub start: Stance,
    /// The moves, in order.
    pub steps: Vec<FootStep>,
    /// Search nodes expanded.
    pub nodes: usize,
}

impl FootPlan {
    /// The stances after each step, the start first.
    pub fn stances(&self) -> Vec<Stance> {
        let mut s = self.start.clone();
        let mut out = vec![s.clone()];
        for step in &self.steps {
            apply(&mut s, step);
            out.push(s.clone());
        }
        out
    }
}

/// Applies a step to a stance.
pub fn apply(s: &mut Stance, step: &FootStep) {
    match *step {
        FootStep::Advance { .. } => s.k += 1,
        FootStep::Place { leg, to, .. } => s.feet[leg] = Some(to),
        FootStep::Lift { leg, .. } => s.feet[leg] = None,
    }
}

/// How a search failed.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchFailure {
    /// The furthest route index any stance reached.
    pub furthest: usize,
    /// The steps leading to the first stance that reached it.
    pub steps_to_furthest: Vec<FootStep>,
    /// Nodes expanded.
    pub nodes: usize,
}

/// A check of each move the search considers, beyond CG-space's own tests: for example
/// that the real robot can carry it out (reach along the way, contacts between its legs,
/// its parts against the terrain). The search calls it before it enters a stance, with the
/// route cells of both stances; a move it refuses is not taken from that stance.
pub trait MoveCheck {
    /// Whether the move `step` from `from` (at route cell `from_cell`) to `to` (at
    /// `to_cell`) can be carried out.
    fn check(
        &self,
        from: &Stance,
        from_cell: CgCell,
        step: &FootStep,
        to: &Stance,
        to_cell: CgCell,
    ) -> bool;
}

/// A leg's reach at a foot cell: the lowest and highest contact-centre heights (body z) and
/// the quadrant (see [`RangeCell`](crate::robot::RangeCell)).
type Reach = (f64, f64, u8);

/// The geometry the search asks about, for one route.
pub struct FootSearch<'a> {
    space: &'a CgSpace,
    route: &'a [CgCell],
    min_h: Vec<f64>,
    params: SearchParams,
    /// Per heading bin and leg: the range as a dense square of side `2 * half + 1`.
    lookup: Vec<Vec<Vec<Option<Reach>>>>,
    half: i32,
    check: Option<&'a dyn MoveCheck>,
}

impl<'a> FootSearch<'a> {
    /// A search along `route` (every cell valid) in `space`.
    pub fn new(space: &'a CgSpace, route: &'a [CgCell], params: SearchParams) -> Self {
        let robot = space.robot();
        let half = robot
            .headings
            .iter()
            .flat_map(|t| t.legs.iter().flatten())
            .map(|c| c.di.abs().max(c.dj.abs()))
            .max()
            .unwrap_or(0);
        let side = (2 * half + 1) as usize;
        let lookup = robot
            .headings
            .iter()
            .map(|t| {
                t.legs
                    .iter()
                    .map(|cells| {
                        let mut dense = vec![None; side * side];
                        for c in cells {
                            dense[((c.dj + half) as usize) * side + (c.di + half) as usize] =
                                Some((c.z_lo, c.z_hi, c.quadrant));
                        }
                        dense
                    })
                    .collect()
            })
            .collect();
        let min_h = route
            .iter()
            .map(|c| {
                min_body_height(
                    robot,
                    &robot.headings[usize::from(c.it)],
                    space.foot(),
                    c.ix,
                    c.iy,
                )
                .unwrap_or(f64::INFINITY)
            })
            .collect();
        FootSearch {
            space,
            route,
            min_h,
            params,
            lookup,
            half,
            check: None,
        }
    }

    /// The search with a check of every move it considers.
    pub fn with_check(mut self, check: Option<&'a dyn MoveCheck>) -> Self {
        self.check = check;
        self
    }

    /// Leg `leg`'s reach interval and quadrant for a foot cell seen from route cell `k`.
    fn range(&self, leg: usize, k: usize, f: FootCell) -> Option<Reach> {
        let cg = self.route[k];
        let (di, dj) = (f.0 - cg.ix, f.1 - cg.iy);
        if di.abs() > self.half || dj.abs() > self.half {
            return None;
        }
        let side = (2 * self.half + 1) as usize;
        self.lookup[usize::from(cg.it)][leg]
            [((dj + self.half) as usize) * side + (di + self.half) as usize]
    }

    /// The body-height interval at route cell `k` for the standing feet (`skip`: a foot
    /// to leave out, `extra`: a foot to add); `None` if a foot is out of range or the
    /// interval is empty.
    fn heights(
        &self,
        k: usize,
        feet: &[Option<FootCell>],
        skip: Option<usize>,
        extra: Option<(usize, FootCell)>,
    ) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (self.min_h[k], f64::INFINITY);
        let robot = self.space.robot();
        let foot = self.space.foot();
        let standing = feet
            .iter()
            .enumerate()
            .filter(|(l, _)| Some(*l) != skip && extra.is_none_or(|(e, _)| e != *l))
            .filter_map(|(l, f)| f.map(|f| (l, f)))
            .chain(extra);
        for (l, f) in standing {
            let (z_lo, z_hi, _) = self.range(l, k, f)?;
            let g = foot.height(f.0, f.1)?;
            let (a, b) = foot_interval(g, robot.foot_radius[l], z_lo, z_hi);
            lo = lo.max(a);
            hi = hi.min(b);
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// The CG's world position at route cell `k`.
    fn cg(&self, k: usize) -> Point2<f64> {
        let c = self.route[k];
        let grid = self.space.grid();
        let (s, co) = grid.theta(c.it).sin_cos();
        let com = self.space.robot().com;
        grid.centre(c.ix, c.iy)
            + nalgebra::Vector2::new(co * com.x - s * com.y, s * com.x + co * com.y)
    }

    /// Whether the standing feet (less `skip`) hold the CG at route cell `k` with the margin.
    fn stable(&self, k: usize, feet: &[Option<FootCell>], skip: Option<usize>) -> bool {
        let grid = self.space.grid();
        let pts: Vec<Point2<f64>> = feet
            .iter()
            .enumerate()
            .filter(|(l, _)| Some(*l) != skip)
            .filter_map(|(_, f)| f.map(|f| grid.centre(f.0, f.1)))
            .collect();
        if pts.len() < 3 {
            return false;
        }
        support_polygon(&pts).signed_distance(self.cg(k)) >= self.space.robot().stability_margin_m
    }

    /// How many route cells from `k` on a foothold stays usable for a leg.
    fn usefulness(&self, leg: usize, k: usize, f: FootCell) -> usize {
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

    /// Footholds for `leg` at route cell `k`: valid, free, in range at `k` and (if there is
    /// one) the next cell, compatible in height with the other standing feet, in quadrant
    /// `want` of the next cell if given; best first.
    fn footholds(
        &self,
        s: &Stance,
        leg: usize,
        want: Option<u8>,
        want_at_current: bool,
    ) -> Vec<FootCell> {
        let k = s.k;
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
            if self.heights(k, &s.feet, None, Some((leg, f))).is_none() {
                continue;
            }
            // Ties (near the route's end) go to the foothold farthest along the way ahead.
            let forward = f64::from(c.di) * ax + f64::from(c.dj) * ay;
            out.push((self.usefulness(leg, k, f), forward, f));
        }
        out.sort_by(|a, b| b.0.cmp(&a.0).then(b.1.total_cmp(&a.1)).then(a.2.cmp(&b.2)));
        out.into_iter()
            .take(self.params.candidates)
            .map(|(_, _, f)| f)
            .collect()
    }

    /// Whether the foot of `leg` may leave the ground now (the rest hold the CG).
    fn can_lift(&self, s: &Stance, leg: usize) -> bool {
        self.stable(s.k, &s.feet, Some(leg))
            && self.heights(s.k, &s.feet, Some(leg), None).is_some()
    }

    /// The moves from a stance, in the order of priority.
    pub fn moves(&self, s: &Stance) -> Vec<FootStep> {
        let k = s.k;
        let mut out: Vec<FootStep> = Vec::new();
        let Some(n) = (k + 1 < self.route.len()).then_some(k + 1) else {
            return out;
        };
        let legs = s.feet.len();
        let in_range_next: Vec<bool> = (0..legs)
            .map(|l| s.feet[l].is_none_or(|f| self.range(l, n, f).is_some()))
            .collect();
        let all_in_range = in_range_next.iter().all(|&b| b);
        let heights_next = all_in_range
            .then(|| self.heights(n, &s.feet, None, None))
            .flatten();
        let stable_next = self.stable(n, &s.feet, None);
        // 1. Advance the CG.
        if let Some((lo, hi)) = heights_next
            && stable_next
        {
            let body_z = if hi.is_finite() { (lo + hi) / 2.0 } else { lo };
            out.push(FootStep::Advance {
                to: self.route[n],
                body_z,
            });
        }
        // A free foot: the rest hold the CG here and at the next cell.
        let free: Vec<bool> = (0..legs)
            .map(|l| match s.feet[l] {
                None => true,
                Some(_) => self.can_lift(s, l) && self.stable(n, &s.feet, Some(l)),
            })
            .collect();
        let push_places = |out: &mut Vec<FootStep>, leg: usize, want: Option<u8>, current: bool| {
            if s.feet[leg].is_some() && !self.can_lift(s, leg) {
                return;
            }
            for f in self.footholds(s, leg, want, current) {
                let step = FootStep::Place {
                    leg,
                    from: s.feet[leg],
                    to: f,
                };
                if !out.contains(&step) {
                    out.push(step);
                }
            }
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
            let before = out.len();
            push_places(&mut out, l, None, false);
            if out.len() == before
                && let Some(from) = s.feet[l]
                && self.can_lift(s, l)
            {
                out.push(FootStep::Lift { leg: l, from });
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
                    && self.can_lift(s, l)
                {
                    let step = FootStep::Lift { leg: l, from };
                    if !out.contains(&step) {
                        out.push(step);
                    }
                }
            }
        }
        out
    }

    /// Depth-first search from `start` to the route's last cell.
    pub fn search(&self, start: Stance) -> Result<FootPlan, SearchFailure> {
        struct Frame {
            stance: Stance,
            moves: Vec<FootStep>,
            next: usize,
            since_advance: usize,
        }
        let last = self.route.len() - 1;
        let mut visited: HashSet<Stance> = HashSet::new();
        visited.insert(start.clone());
        let mut stack = vec![Frame {
            moves: self.moves(&start),
            stance: start.clone(),
            next: 0,
            since_advance: 0,
        }];
        let mut path: Vec<FootStep> = Vec::new();
        let mut nodes = 1usize;
        let (mut furthest, mut furthest_path, mut stall) = (start.k, Vec::new(), 0usize);
        if start.k >= last {
            return Ok(FootPlan {
                route: self.route.to_vec(),
                start,
                steps: Vec::new(),
                nodes,
            });
        }
        while let Some(top) = stack.last_mut() {
            if top.next >= top.moves.len() {
                stack.pop();
                path.pop();
                continue;
            }
            let step = top.moves[top.next];
            top.next += 1;
            let since = if matches!(step, FootStep::Advance { .. }) {
                0
            } else {
                top.since_advance + 1
            };
            if since > self.params.moves_between_advances {
                continue;
            }
            let mut child = top.stance.clone();
            apply(&mut child, &step);
            if visited.contains(&child) {
                continue;
            }
            if let Some(check) = self.check
                && !check.check(
                    &top.stance,
                    self.route[top.stance.k],
                    &step,
                    &child,
                    self.route[child.k],
                )
            {
                // A refused move costs the budget as an expanded node does.
                stall += 1;
                if stall > self.params.stall_nodes {
                    break;
                }
                continue;
            }
            visited.insert(child.clone());
            nodes += 1;
            path.push(step);
            if child.k >= last {
                return Ok(FootPlan {
                    route: self.route.to_vec(),
                    start,
                    steps: path,
                    nodes,
                });
            }
            if child.k > furthest {
                furthest = child.k;
                furthest_path = path.clone();
                stall = 0;
            } else {
                stall += 1;
                if stall > self.params.stall_nodes {
                    break;
                }
            }
            stack.push(Frame {
                moves: self.moves(&child),
                stance: child,
                next: 0,
                since_advance: since,
            });
        }
        Err(SearchFailure {
            furthest,
            steps_to_furthest: furthest_path,
            nodes,
        })
    }

    /// A stance at the route's first cell: each leg on the valid foothold nearest the middle
    /// of its range that agrees in height with the others; `None` if that does not hold the
    /// CG.
    pub fn initial_stance(&self) -> Option<Stance> {
        let robot = self.space.robot();
        let cg = self.route[0];
        let table = &robot.headings[usize::from(cg.it)];
        let mut s = Stance {
            k: 0,
            feet: vec![None; robot.leg_count()],
        };
        for (leg, cells) in table.legs.iter().enumerate() {
            let n = cells.len().max(1) as f64;
            let (mx, my) = cells.iter().fold((0.0, 0.0), |(x, y), c| {
                (x + f64::from(c.di) / n, y + f64::from(c.dj) / n)
            });
            let mut order: Vec<_> = cells.iter().collect();
            order.sort_by(|a, b| {
                let da = (f64::from(a.di) - mx).hypot(f64::from(a.dj) - my);
                let db = (f64::from(b.di) - mx).hypot(f64::from(b.dj) - my);
                da.total_cmp(&db)
            });
            for c in order {
                let f = (cg.ix + c.di, cg.iy + c.dj);
                if self.space.foot().valid(f.0, f.1)
                    && !s.feet.contains(&Some(f))
                    && self.heights(0, &s.feet, None, Some((leg, f))).is_some()
                {
                    s.feet[leg] = Some(f);
                    break;
                }
            }
        }
        self.stable(0, &s.feet, None).then_some(s)
    }

    /// The body-height interval for a stance (`None` if a foot is out of range).
    pub fn stance_heights(&self, s: &Stance) -> Option<(f64, f64)> {
        self.heights(s.k, &s.feet, None, None)
    }

    /// Whether a stance holds the CG with the margin.
    pub fn stance_stable(&self, s: &Stance) -> bool {
        self.stable(s.k, &s.feet, None)
    }
}
