//! The foot-level search along a CG route: depth first, each move advancing the CG one
//! cell or moving, placing or lifting one foot, tried in a fixed order of priority
//! ([`footmoves`](crate::footmoves)); each move checked on the robot's own legs
//! ([`footcheck`](crate::footcheck)) before the search takes it.

use rustc_hash::{FxHashMap, FxHashSet};

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::grid::CgCell;
use std::rc::Rc;

use crate::footmoves::Offer;
use crate::legs::{BodyPose, LegPose, Legs};
use crate::space::CgSpace;
use crate::validity::min_body_height;

/// A foot cell: column and row on the CG grid.
pub type FootCell = (i32, i32);

/// Where the robot stands: its place on the route, each foot (`None`: lifted) and the
/// height its body stands at.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Stance {
    /// Index of the CG cell on the route.
    pub k: usize,
    /// Each leg's foot cell, `None` for a foot held up.
    pub feet: Vec<Option<FootCell>>,
    /// World Z of the body origin, millimetres.
    pub z_mm: i32,
    /// Where each foot held up was lifted from (empty, or `None` for a leg, where that is
    /// not known): a lifted foot rides with the body.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held: Vec<Option<Held>>,
}

/// Where a foot held up was lifted: its foot cell, and the route cell and body height the
/// body had then; the foot stays where the lift put it in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Held {
    /// The foot cell it stood on.
    pub from: FootCell,
    /// The route index of the body then.
    pub k: usize,
    /// The body's height then, millimetres.
    pub z_mm: i32,
}

impl Stance {
    /// A stance with no foot known to be held up.
    pub fn new(k: usize, feet: Vec<Option<FootCell>>, z_mm: i32) -> Self {
        Stance {
            k,
            feet,
            z_mm,
            held: Vec::new(),
        }
    }

    /// World Z of the body origin, metres.
    pub fn body_z(&self) -> f64 {
        f64::from(self.z_mm) / 1000.0
    }

    /// Where leg `leg`'s foot was lifted from, if it is held up and that is known.
    pub fn held(&self, leg: usize) -> Option<Held> {
        self.held.get(leg).copied().flatten()
    }

    fn set_held(&mut self, leg: usize, h: Option<Held>) {
        if h.is_some() && self.held.len() < self.feet.len() {
            self.held.resize(self.feet.len(), None);
        }
        if let Some(slot) = self.held.get_mut(leg) {
            *slot = h;
        }
        if self.held.iter().all(Option::is_none) {
            self.held.clear();
        }
    }
}

/// A body height in whole millimetres, as a [`Stance`] holds it.
pub fn millimetres(z: f64) -> i32 {
    (z * 1000.0).round() as i32
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
    /// on the next cell (the time-out that feeds back to the route planner). By default 400:
    /// on long routes most of the planning time goes into searches that stick, and a
    /// search that has not got on within a few hundred nodes seldom does.
    pub stall_nodes: usize,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams {
            candidates: 4,
            lookahead: 40,
            moves_between_advances: 12,
            stall_nodes: 400,
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
    /// How many of the steps move or lift a foot (the rest advance the CG).
    pub fn foot_moves(&self) -> usize {
        self.steps
            .iter()
            .filter(|s| !matches!(s, FootStep::Advance { .. }))
            .count()
    }

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
        FootStep::Advance { body_z, .. } => {
            s.k += 1;
            s.z_mm = millimetres(body_z);
        }
        FootStep::Place { leg, to, .. } => {
            s.feet[leg] = Some(to);
            s.set_held(leg, None);
        }
        FootStep::Lift { leg, from } => {
            s.feet[leg] = None;
            let held = Held {
                from,
                k: s.k,
                z_mm: s.z_mm,
            };
            s.set_held(leg, Some(held));
        }
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

/// A check of the planned moves beyond the search's own: for example that the real robot
/// can carry each out along the way (reach, contacts between its legs, its parts against
/// the terrain), as its controller would plan it. The planner puts each plan the search
/// finds to it move by move, in order, with the route cells of both stances; at the first
/// move it refuses, that move is forbidden from that stance and the search runs again.
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
pub(crate) type Reach = (f64, f64, u8);

/// What the search counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SearchCounts {
    /// Moves the search's own checks on the legs refused.
    pub refused_by_legs: u64,
    /// Moves the outside [`MoveCheck`] refused.
    pub refused_by_check: u64,
    /// Inverse kinematics solved for the legs.
    pub leg_poses: u64,
}

impl SearchCounts {
    /// Adds another search's counts.
    pub fn add(&mut self, other: &SearchCounts) {
        self.refused_by_legs += other.refused_by_legs;
        self.refused_by_check += other.refused_by_check;
        self.leg_poses += other.leg_poses;
    }
}

/// The geometry the search asks about, for one route.
pub struct FootSearch<'a> {
    pub(crate) space: &'a CgSpace,
    pub(crate) route: &'a [CgCell],
    pub(crate) min_h: Vec<f64>,
    pub(crate) params: SearchParams,
    /// Per heading bin and leg: the range as a dense square of side `2 * half + 1`.
    lookup: Vec<Vec<Vec<Option<Reach>>>>,
    half: i32,
    /// Moves (from one stance to another) never to be taken.
    forbidden: FxHashSet<(Stance, Stance)>,
    pub(crate) legs: Legs<'a>,
    /// How many route cells ahead a foothold stays usable, by leg, route index and cell.
    pub(crate) useful: std::cell::RefCell<FxHashMap<(usize, usize, FootCell), usize>>,
    pub(crate) refused_by_legs: std::cell::Cell<u64>,
    refused_by_check: u64,
    /// Where the body stands at the route's first cell, when it is not the cell's centre.
    start_at: Option<(Point2<f64>, f64)>,
    /// Per leg, the foot cell it stands on at the start and where on it.
    pub(crate) start_feet: Vec<Option<(FootCell, Point2<f64>)>>,
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
            forbidden: FxHashSet::default(),
            legs: Legs::new(&robot.model),
            useful: Default::default(),
            refused_by_legs: std::cell::Cell::new(0),
            refused_by_check: 0,
            start_at: None,
            start_feet: Vec::new(),
        }
    }

    /// The search with the robot standing as it does: the body at `at` (world X, Y and
    /// heading) at the route's first cell, and each foot where `feet` puts it (world X, Y)
    /// for as long as it stays on that cell, rather than at the cells' centres.
    pub fn with_start(mut self, at: (Point2<f64>, f64), feet: &[Option<Point2<f64>>]) -> Self {
        let grid = self.space.grid();
        self.start_at = Some(at);
        self.start_feet = feet.iter().map(|p| p.map(|p| (grid.xy_of(p), p))).collect();
        self
    }

    /// Forbids the move from stance `from` to stance `to` in the searches to come (a move
    /// the outside check refused).
    pub fn forbid(&mut self, from: Stance, to: Stance) {
        self.refused_by_check += 1;
        self.forbidden.insert((from, to));
    }

    /// What the search counted so far.
    pub fn counts(&self) -> SearchCounts {
        SearchCounts {
            refused_by_legs: self.refused_by_legs.get(),
            refused_by_check: self.refused_by_check,
            leg_poses: self.legs.solved(),
        }
    }

    /// Leg `leg`'s reach interval and quadrant for a foot cell seen from route cell `k`.
    pub(crate) fn range(&self, leg: usize, k: usize, f: FootCell) -> Option<Reach> {
        let cg = self.route[k];
        let (di, dj) = (f.0 - cg.ix, f.1 - cg.iy);
        if di.abs() > self.half || dj.abs() > self.half {
            return None;
        }
        let side = (2 * self.half + 1) as usize;
        self.lookup[usize::from(cg.it)][leg]
            [((dj + self.half) as usize) * side + (di + self.half) as usize]
    }

    /// The body's pose at route cell `k`, its origin at height `z`.
    pub(crate) fn body(&self, k: usize, z: f64) -> BodyPose {
        if k == 0
            && let Some((at, theta)) = self.start_at
        {
            return BodyPose { at, z, theta };
        }
        let c = self.route[k];
        let grid = self.space.grid();
        BodyPose {
            at: grid.centre(c.ix, c.iy),
            z,
            theta: grid.theta(c.it),
        }
    }

    /// Depth-first search from `start` to the route's last cell.
    pub fn search(&self, start: Stance) -> Result<FootPlan, SearchFailure> {
        struct Frame {
            stance: Stance,
            poses: Vec<Rc<LegPose>>,
            moves: Offer,
            /// Per group of moves, how many the search entered.
            entered: Vec<usize>,
            next: usize,
            since_advance: usize,
        }
        let last = self.route.len() - 1;
        let mut visited: FxHashSet<Stance> = FxHashSet::default();
        visited.insert(start.clone());
        let mut nodes = 1usize;
        if start.k >= last {
            return Ok(FootPlan {
                route: self.route.to_vec(),
                start,
                steps: Vec::new(),
                nodes,
            });
        }
        let mut stack = Vec::new();
        if let Some(poses) = self.poses(&start) {
            let moves = self.moves(&start);
            stack.push(Frame {
                entered: vec![0; moves.caps.len()],
                moves,
                poses,
                stance: start.clone(),
                next: 0,
                since_advance: 0,
            });
        }
        let mut path: Vec<FootStep> = Vec::new();
        let (mut furthest, mut furthest_path, mut stall) = (start.k, Vec::new(), 0usize);
        let mut refusals = 0usize;
        while let Some(top) = stack.last_mut() {
            if top.next >= top.moves.list.len() {
                stack.pop();
                path.pop();
                continue;
            }
            let (step, group) = top.moves.list[top.next];
            top.next += 1;
            if top.entered[group] >= top.moves.caps[group] {
                continue;
            }
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
            if !self.forbidden.is_empty()
                && self
                    .forbidden
                    .contains(&(top.stance.clone(), child.clone()))
            {
                continue;
            }
            if !self.move_ok(&top.stance, &top.poses, &step) {
                // Refused moves cost the budget too, a quarter of a node each.
                refusals += 1;
                if refusals.is_multiple_of(4) {
                    stall += 1;
                    if stall > self.params.stall_nodes {
                        break;
                    }
                }
                continue;
            }
            top.entered[group] += 1;
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
            let Some(poses) = self.poses(&child) else {
                path.pop();
                continue;
            };
            let moves = self.moves(&child);
            stack.push(Frame {
                entered: vec![0; moves.caps.len()],
                moves,
                poses,
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
    /// of its range that agrees in height with the others and keeps clear of their legs, the
    /// body at a height every foot reaches; `None` if that does not hold the CG.
    pub fn initial_stance(&self) -> Option<Stance> {
        let robot = self.space.robot();
        let cg = self.route[0];
        let table = &robot.headings[usize::from(cg.it)];
        let mut feet: Vec<Option<FootCell>> = vec![None; robot.leg_count()];
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
                    && !feet.contains(&Some(f))
                    && self.heights(0, &feet, None, Some((leg, f))).is_some()
                {
                    let mut with = feet.clone();
                    with[leg] = Some(f);
                    if self.stance_at_some_height(0, &with).is_some() {
                        feet = with;
                        break;
                    }
                }
            }
        }
        self.stance_at_some_height(0, &feet)
            .filter(|s| self.holds(s, None))
    }

    /// The standing feet at route cell `k` with the body at the first of the preferred
    /// heights at which every leg can stand clear of the others.
    fn stance_at_some_height(&self, k: usize, feet: &[Option<FootCell>]) -> Option<Stance> {
        let (lo, hi) = self.heights(k, feet, None, None)?;
        self.preferred_heights(lo, hi).into_iter().find_map(|z| {
            let s = Stance::new(k, feet.to_vec(), millimetres(z));
            self.poses(&s).filter(|p| self.legs_clear(&s, p)).map(|_| s)
        })
    }

    /// The body-height interval at route cell `k` for the standing feet (`skip`: a foot
    /// to leave out, `extra`: a foot to add) from the range maps; `None` if a foot is out of
    /// range or the interval is empty.
    pub(crate) fn heights(
        &self,
        k: usize,
        feet: &[Option<FootCell>],
        skip: Option<usize>,
        extra: Option<(usize, FootCell)>,
    ) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (self.min_h[k], f64::INFINITY);
        let standing = feet
            .iter()
            .enumerate()
            .filter(|(l, _)| Some(*l) != skip && extra.is_none_or(|(e, _)| e != *l))
            .filter_map(|(l, f)| f.map(|f| (l, f)))
            .chain(extra);
        for (l, f) in standing {
            let (a, b) = self.foot_heights(l, k, f)?;
            lo = lo.max(a);
            hi = hi.min(b);
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// The body heights (world Z of the origin) at route cell `k` at which leg `leg`'s
    /// foot on cell `f` stays within its range map's heights.
    pub(crate) fn foot_heights(&self, leg: usize, k: usize, f: FootCell) -> Option<(f64, f64)> {
        let (z_lo, z_hi, _) = self.range(leg, k, f)?;
        let g = self.space.foot().height(f.0, f.1)?;
        Some(crate::validity::foot_interval(
            g,
            self.space.robot().foot_radius[leg],
            z_lo,
            z_hi,
        ))
    }

    /// The body heights tried within `lo..hi`, best first: high in the interval (the feet
    /// then have room to rise over the ground between footholds), then lower.
    pub(crate) fn preferred_heights(&self, lo: f64, hi: f64) -> Vec<f64> {
        if !hi.is_finite() {
            return vec![lo];
        }
        let mut out: Vec<f64> = [0.7, 0.45, 0.9, 0.2]
            .iter()
            .map(|b| lo + b * (hi - lo))
            .collect();
        out.dedup_by(|a, b| (*a - *b).abs() < 0.005);
        out
    }
}
