//! The foot-level search's checks of a move on the robot's own legs, with the body at the
//! height the search holds it: every foot it stands on reached by its leg's inverse
//! kinematics, no link of one leg within the leg clearance of another's (where the feet
//! stand, and along a swing's travel and half-way through a body move), a swinging foot
//! able to rise over its two ends and the ground between, and the centre of mass (from
//! every link) over the feet that stand, by the stability margin.

use std::rc::Rc;

use nalgebra::{Point2, Point3};
use tca_legged_model::LegParts;
use tca_stability::support_polygon;

use crate::footplan::{FootCell, FootSearch, Stance, millimetres};
use crate::legs::{BodyPose, LegPose};

/// Samples per cell of foot travel along a swing (between its raised ends) and of body
/// travel along a body move, where the legs are checked against each other.
const SAMPLES_PER_CELL: f64 = 4.0;

impl FootSearch<'_> {
    /// The contact-sphere centre of leg `leg`'s foot resting on cell `f`, world frame: over
    /// the cell's centre, or where the foot stood at the start if that is on this cell.
    pub(crate) fn foot_centre(&self, leg: usize, f: FootCell) -> Option<Point3<f64>> {
        let g = self.space.foot().height(f.0, f.1)?;
        let c = self.foot_xy(leg, f);
        Some(Point3::new(
            c.x,
            c.y,
            g + self.space.robot().foot_radius[leg],
        ))
    }

    /// Where leg `leg`'s foot stands on cell `f`, world X, Y: the cell's centre, or where the
    /// foot stood at the start if that is on this cell.
    pub(crate) fn foot_xy(&self, leg: usize, f: FootCell) -> Point2<f64> {
        match self.start_feet.get(leg).copied().flatten() {
            Some((cell, at)) if cell == f => at,
            _ => self.space.grid().centre(f.0, f.1),
        }
    }

    /// Leg `leg` with its foot on cell `f` and the body at `body`.
    fn pose_on(&self, leg: usize, body: &BodyPose, f: FootCell) -> Option<Rc<LegPose>> {
        self.legs.at(leg, body.to_body(self.foot_centre(leg, f)?))
    }

    /// Every leg's pose in a stance: a standing leg's foot on its cell with the body at the
    /// stance's height, a lifted leg where its lift left it in the body frame (at its
    /// neutral joints where that is not known); `None` if a foot cannot be reached.
    pub(crate) fn poses(&self, s: &Stance) -> Option<Vec<Rc<LegPose>>> {
        self.poses_at(&self.body(s.k, s.body_z()), s)
    }

    /// The legs of stance `s` with the body at `body`.
    fn poses_at(&self, body: &BodyPose, s: &Stance) -> Option<Vec<Rc<LegPose>>> {
        s.feet
            .iter()
            .enumerate()
            .map(|(l, f)| match (f, s.held(l)) {
                (Some(f), _) => self.pose_on(l, body, *f),
                (None, Some(_)) => self.legs.at(l, self.held_point(s, l)?),
                (None, None) => Some(self.legs.neutral(l)),
            })
            .collect()
    }

    /// Where the foot of a leg held up is in the body frame (it rides with the body from
    /// where its lift left it), if that is known.
    fn held_point(&self, s: &Stance, leg: usize) -> Option<Point3<f64>> {
        let h = s.held(leg)?;
        let then = self.body(h.k, f64::from(h.z_mm) / 1000.0);
        let c = self.foot_centre(leg, h.from)?;
        Some(then.to_body(Point3::new(c.x, c.y, c.z + self.lift_m())))
    }

    /// How high a lift raises a foot, metres.
    fn lift_m(&self) -> f64 {
        1.5 * self.space.robot().swing_rise_m
    }

    /// Whether leg `l`'s joints are known in stance `s` (it stands, or its lift is known).
    fn known(s: &Stance, l: usize) -> bool {
        s.feet[l].is_some() || s.held(l).is_some()
    }

    /// Whether no two legs touch.
    pub(crate) fn legs_clear(&self, s: &Stance, poses: &[Rc<LegPose>]) -> bool {
        (0..s.feet.len()).all(|l| {
            !Self::known(s, l) || self.clear_of_others(l, &poses[l].parts, s, poses, l + 1)
        })
    }

    /// Whether `parts` of leg `leg` keep clear of every other leg from `from` on whose
    /// joints are known (a leg lifted before the plan began is not known here: the outside
    /// check sees it).
    fn clear_of_others(
        &self,
        leg: usize,
        parts: &LegParts,
        s: &Stance,
        poses: &[Rc<LegPose>],
        from: usize,
    ) -> bool {
        let margin = self.space.robot().leg_clearance_m;
        (from..s.feet.len())
            .filter(|&m| m != leg && Self::known(s, m))
            .all(|m| !parts.touches(&poses[m].parts, margin))
    }

    /// Whether the feet that stand (less `skip`) hold the centre of mass, worked out from
    /// every leg's parts (leg `swap.0`'s replaced by `swap.1`), with the margin, the body at
    /// `body`.
    fn held(
        &self,
        body: &BodyPose,
        feet: &[Option<FootCell>],
        skip: Option<usize>,
        poses: &[Rc<LegPose>],
        swap: Option<(usize, &LegParts)>,
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
        let com = self
            .legs
            .com(poses.iter().enumerate().map(|(l, p)| match swap {
                Some((s, parts)) if s == l => parts,
                _ => &p.parts,
            }));
        support_polygon(&pts).signed_distance(body.to_world_xy(com))
            >= self.space.robot().stability_margin_m
    }

    /// Whether a stance's standing feet (less `skip`) hold its centre of mass.
    pub(crate) fn holds(&self, s: &Stance, skip: Option<usize>) -> bool {
        self.poses(s)
            .is_some_and(|p| self.held(&self.body(s.k, s.body_z()), &s.feet, skip, &p, None))
    }

    /// The body-frame CG of a stance's legs, for the range maps' quicker tests.
    pub(crate) fn com_of(&self, poses: &[Rc<LegPose>]) -> Point3<f64> {
        self.legs.com(poses.iter().map(|p| &p.parts))
    }

    /// Whether the body can move from stance `s` to the next route cell at
    /// height `z`: every standing foot reached there and half-way, the legs clear of each
    /// other at both, the centre of mass held there.
    pub(crate) fn advance_ok(&self, s: &Stance, z: f64) -> bool {
        let from = self.body(s.k, s.body_z());
        let to = self.body(s.k + 1, f64::from(millimetres(z)) / 1000.0);
        let n = self.samples((to.at - from.at).norm() + (to.z - from.z).abs());
        let ok = (1..=n).all(|i| {
            let b = from.lerp(&to, i as f64 / n as f64);
            self.poses_at(&b, s)
                .is_some_and(|p| self.legs_clear(s, &p) && self.held_clear(s, &b, &p))
        }) && self
            .poses_at(&to, s)
            .is_some_and(|p| self.held(&to, &s.feet, None, &p, None));
        self.note(ok)
    }

    /// Whether the feet held up (riding with the body at `body`) and their legs' links keep
    /// clear of the ground.
    fn held_clear(&self, s: &Stance, body: &BodyPose, poses: &[Rc<LegPose>]) -> bool {
        let robot = self.space.robot();
        let clearance = robot.swing_rise_m / 4.0;
        let iso = body.isometry();
        (0..s.feet.len())
            .filter(|&l| s.feet[l].is_none() && s.held(l).is_some())
            .all(|l| {
                let r = robot.foot_radius[l];
                let foot = self.held_point(s, l).map(|p| iso * p);
                let foot_clear = foot.is_some_and(|c| {
                    self.ground_near(c.xy(), r)
                        .is_some_and(|g| c.z - r - clearance >= g)
                });
                foot_clear
                    && poses[l].parts.capsules().all(|(a, b, cr)| {
                        let (a, b) = (iso * a, iso * b);
                        let n = self.samples((b - a).norm());
                        (0..=n).all(|i| {
                            let p = a + (b - a) * (i as f64 / n as f64);
                            self.ground_near(p.xy(), cr)
                                .is_some_and(|g| p.z - cr - clearance >= g)
                        })
                    })
            })
    }

    /// The highest ground within `radius` of a world point (over whole foot cells); `None`
    /// off the map.
    fn ground_near(&self, p: Point2<f64>, radius: f64) -> Option<f64> {
        let grid = self.space.grid();
        let (x0, y0) = grid.xy_of(p - nalgebra::Vector2::new(radius, radius));
        let (x1, y1) = grid.xy_of(p + nalgebra::Vector2::new(radius, radius));
        let mut top = f64::NEG_INFINITY;
        for iy in y0..=y1 {
            for ix in x0..=x1 {
                top = top.max(self.space.foot().height(ix, iy)?);
            }
        }
        Some(top)
    }

    /// Whether leg `leg` can swing from where it is to cell `f`, the body still: its foot
    /// reached there, raised over both ends and the ground between, its links clear of the
    /// other standing legs there and along the way, the other feet holding the centre of
    /// mass throughout.
    pub(crate) fn place_ok(
        &self,
        s: &Stance,
        poses: &[Rc<LegPose>],
        leg: usize,
        f: FootCell,
    ) -> bool {
        let ok = self.swing_ok(s, poses, leg, f);
        self.note(ok)
    }

    fn swing_ok(&self, s: &Stance, poses: &[Rc<LegPose>], leg: usize, f: FootCell) -> bool {
        let robot = self.space.robot();
        let body = self.body(s.k, s.body_z());
        let Some(target) = self.foot_centre(leg, f) else {
            return false;
        };
        // Where the foot is: on its cell, or up where a lift left it.
        let start = match s.feet[leg] {
            Some(c) => self.foot_centre(leg, c),
            None => self.held_point(s, leg).map(|p| body.isometry() * p),
        };
        let rise = robot.swing_rise_m;
        let r = robot.foot_radius[leg];
        let mut top = start.map_or(target.z, |a| a.z.max(target.z)) + rise;
        if let Some(a) = start {
            let cell = self.space.grid().cell_m;
            let n = ((a.xy() - target.xy()).norm() / (cell / 2.0))
                .ceil()
                .max(1.0) as usize;
            for i in 0..=n {
                let p = a.xy() + (target.xy() - a.xy()) * (i as f64 / n as f64);
                let (ix, iy) = self.space.grid().xy_of(p);
                if let Some(h) = self.space.foot().height(ix, iy) {
                    top = top.max(h + r + 0.75 * rise);
                }
            }
        }
        let raised = |p: Point3<f64>| self.legs.at(leg, body.to_body(Point3::new(p.x, p.y, top)));
        let Some(down) = self.legs.at(leg, body.to_body(target)) else {
            return false;
        };
        let Some(high) = raised(target) else {
            return false;
        };
        let others = |parts: &LegParts| {
            self.over_map(&body, parts) && self.clear_of_others(leg, parts, s, poses, 0)
        };
        if !others(&down.parts) || !others(&high.parts) {
            return false;
        }
        let held =
            |parts: &LegParts| self.held(&body, &s.feet, Some(leg), poses, Some((leg, parts)));
        if !held(&high.parts) {
            return false;
        }
        let Some(a) = start else {
            return true;
        };
        let Some(low) = raised(a) else {
            return false;
        };
        if !others(&low.parts) || !held(&low.parts) {
            return false;
        }
        let n = self.samples((a.xy() - target.xy()).norm());
        (1..n).all(|i| {
            self.legs
                .between(leg, &low, &high, i as f64 / n as f64)
                .is_some_and(|p| others(&p) && held(&p))
        })
    }

    /// Whether a swinging leg's links (`parts`, the body at `body`) pass over mapped ground:
    /// each capsule, widened by its radius again and a cell (the box it fills and the
    /// ground around it that a check of its surface looks at), within the map. Ground off
    /// the map is unknown, and a leg never swings over unknown ground.
    fn over_map(&self, body: &BodyPose, parts: &LegParts) -> bool {
        let grid = self.space.grid();
        parts.capsules().all(|(a, b, r)| {
            let margin = 2.0 * r + grid.cell_m;
            [a, b]
                .into_iter()
                .all(|p| grid.holds_within(body.to_world_xy(p), margin))
        })
    }

    /// Whether the foot of a standing leg can be lifted and held up: raised within its
    /// reach, the others holding the centre of mass.
    pub(crate) fn lift_ok(&self, s: &Stance, poses: &[Rc<LegPose>], leg: usize) -> bool {
        let body = self.body(s.k, s.body_z());
        let lift = self.lift_m();
        let ok = s.feet[leg]
            .and_then(|f| self.foot_centre(leg, f))
            .and_then(|c| {
                self.legs
                    .at(leg, body.to_body(Point3::new(c.x, c.y, c.z + lift)))
            })
            .is_some_and(|up| {
                self.over_map(&body, &up.parts)
                    && self.held(&body, &s.feet, Some(leg), poses, Some((leg, &up.parts)))
                    && self.clear_of_others(leg, &up.parts, s, poses, 0)
            });
        self.note(ok)
    }

    /// Samples along a travel of `m` metres.
    fn samples(&self, m: f64) -> usize {
        ((m / self.space.grid().cell_m * SAMPLES_PER_CELL).ceil() as usize).max(2)
    }

    /// Counts a refusal.
    fn note(&self, ok: bool) -> bool {
        if !ok {
            self.refused_by_legs.set(self.refused_by_legs.get() + 1);
        }
        ok
    }
}
