//! The simulator's state: the body on its standing feet, the clock and the counters.

use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
use tca_legged_messages::{FootState, LegStateReply, SupportState};
use tca_legged_model::{IkOptions, RobotModel};
use tca_robot::HeightField;
use tca_stability::{Polygon, stability_margin, support_polygon};

use crate::collide::{BlockMax, foot_clearance, rest_height, shape_contact};
use crate::error::{MoveCommand, MoveError, SimError};
use crate::params::{SimParams, StartPose};
use crate::pose::{isometry_to_pose, world_point};
use crate::report::{Counters, MoveReport};

/// The quasi-static simulator of one robot on one terrain.
///
/// The body is where the last move left it; a standing foot stays where it touched down
/// (its sphere's centre is fixed in the world) and a swinging one rides with its leg. Every
/// move keeps these true or is refused; see `SIMULATOR.md`.
#[derive(Clone)]
pub struct LeggedSim {
    pub(crate) model: Arc<RobotModel>,
    pub(crate) terrain: Arc<HeightField>,
    pub(crate) blocks: BlockMax,
    pub(crate) params: SimParams,
    pub(crate) body: Isometry3<f64>,
    pub(crate) posture: Vec<Vec<f64>>,
    pub(crate) stance: Vec<bool>,
    /// World centres of the standing feet's spheres (where they touched down).
    pub(crate) anchors: Vec<Point3<f64>>,
    pub(crate) clock_s: f64,
    pub(crate) counters: Counters,
    pub(crate) fallen: bool,
    pub(crate) last: Option<MoveReport>,
    /// The leg each collision shape rides on, in `collision_shapes` order.
    pub(crate) shape_legs: Vec<Option<usize>>,
    /// The sag of the lifted leg, when the robot sags ([`SimParams::sag`]).
    pub(crate) sag: Option<crate::sag::Sag>,
}

impl std::fmt::Debug for LeggedSim {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LeggedSim")
            .field("robot", &self.model.name())
            .field("body", &isometry_to_pose(&self.body))
            .field("posture", &self.posture)
            .field("stance", &self.stance)
            .field("clock_s", &self.clock_s)
            .field("counters", &self.counters)
            .field("fallen", &self.fallen)
            .finish_non_exhaustive()
    }
}

impl LeggedSim {
    /// Stands the robot at `start`: body level at `params.standing_height_m` over the mean
    /// ground under its feet, every foot where its neutral position puts it and resting on
    /// the terrain. Refused when a foot or the body is off the map, the ground under a foot
    /// is steeper than allowed, a leg cannot reach the ground, a link touches the terrain,
    /// or the centre of mass is not inside the feet.
    pub fn new(
        model: Arc<RobotModel>,
        terrain: Arc<HeightField>,
        start: StartPose,
        params: SimParams,
    ) -> Result<LeggedSim, SimError> {
        params.check().map_err(SimError::Params)?;
        if ![start.x_m, start.y_m, start.yaw_rad]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(SimError::Params(format!(
                "the start pose {start:?} has a number that is not finite"
            )));
        }
        let height = params.standing_height_m;
        let rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, start.yaw_rad);
        let (min, max) = terrain.extent();
        let off = |what: String, p: Point2<f64>| SimError::OffMap {
            x_m: start.x_m,
            y_m: start.y_m,
            what,
            px: p.x,
            py: p.y,
            min_x: min.x,
            min_y: min.y,
            max_x: max.x,
            max_y: max.y,
        };
        let inside = |p: Point2<f64>, r: f64| {
            p.x - r >= min.x && p.x + r <= max.x && p.y - r >= min.y && p.y + r <= max.y
        };
        let centre = Point2::new(start.x_m, start.y_m);
        if !inside(centre, 0.0) {
            return Err(off("the body".into(), centre));
        }
        let feet = model.standing_feet(height);
        let mut rests = Vec::with_capacity(feet.len());
        for (leg, foot) in model.legs().iter().zip(&feet) {
            let w = rotation * foot.coords;
            let xy = Point2::new(start.x_m + w.x, start.y_m + w.y);
            if !inside(xy, leg.foot_radius()) {
                return Err(off(format!("the foot of leg `{}`", leg.name()), xy));
            }
            let normal = terrain.normal_at(xy.x, xy.y);
            let slope = normal.z.clamp(-1.0, 1.0).acos();
            if slope > params.max_start_slope_rad {
                return Err(SimError::TooSteep {
                    leg: leg.name().to_owned(),
                    slope_deg: slope.to_degrees(),
                    max_deg: params.max_start_slope_rad.to_degrees(),
                });
            }
            rests.push((xy, rest_height(&terrain, xy, leg.foot_radius())));
        }
        // Body height: the standing height over the mean ground under the feet.
        let n = feet.len() as f64;
        let mean_ground: f64 = model
            .legs()
            .iter()
            .zip(&rests)
            .map(|(leg, (_, z))| z - leg.foot_radius())
            .sum::<f64>()
            / n;
        let body = Isometry3::from_parts(
            Translation3::new(start.x_m, start.y_m, mean_ground + height),
            rotation,
        );
        let inverse = body.inverse();
        let mut posture = Vec::with_capacity(feet.len());
        for (leg, (xy, z)) in model.legs().iter().zip(&rests) {
            let target = inverse * Point3::new(xy.x, xy.y, *z);
            let solution = leg
                .inverse_kinematics(&target, &IkOptions::starting_at(&leg.neutral()))
                .map_err(|e| SimError::CannotReach {
                    leg: leg.name().to_owned(),
                    reason: e.to_string(),
                })?;
            posture.push(solution.joints);
        }
        let shape_legs = model
            .links()
            .iter()
            .flat_map(|l| std::iter::repeat_n(l.leg(), l.collisions().len()))
            .collect();
        let mut sim = LeggedSim {
            blocks: BlockMax::new(&terrain),
            anchors: Vec::new(),
            stance: vec![true; feet.len()],
            model,
            terrain,
            params,
            body,
            posture,
            clock_s: 0.0,
            counters: Counters::default(),
            fallen: false,
            last: None,
            shape_legs,
            sag: None,
        };
        sim.anchors = sim.foot_centres();
        if let Some((link, at)) = sim.link_contact(&sim.body, &sim.posture, None) {
            return Err(SimError::Collision { link, at });
        }
        let margin = sim.margin();
        if margin.is_nan() || margin <= 0.0 {
            return Err(SimError::Unstable { margin_m: margin });
        }
        Ok(sim)
    }

    /// The robot model.
    pub fn model(&self) -> &Arc<RobotModel> {
        &self.model
    }

    /// The terrain.
    pub fn terrain(&self) -> &Arc<HeightField> {
        &self.terrain
    }

    /// The parameters.
    pub fn params(&self) -> &SimParams {
        &self.params
    }

    /// The body's pose, world frame.
    pub fn body(&self) -> Isometry3<f64> {
        self.body
    }

    /// Every leg's joint positions, in model order.
    pub fn posture(&self) -> &[Vec<f64>] {
        &self.posture
    }

    /// Which feet stand, in model order.
    pub fn stance(&self) -> Vec<bool> {
        self.stance.clone()
    }

    /// The centre of every foot's sphere, world frame, in model order.
    pub fn foot_centres(&self) -> Vec<Point3<f64>> {
        self.model
            .legs()
            .iter()
            .zip(&self.posture)
            .map(|(leg, q)| self.body * leg.foot_position(q).unwrap_or_else(|_| Point3::origin()))
            .collect()
    }

    /// A leg's contact point: the bottom of its foot sphere, world frame (`None` for an
    /// index beyond the legs).
    pub fn contact_point(&self, leg: usize) -> Option<Point3<f64>> {
        let l = self.model.legs().get(leg)?;
        let centre = self.body * l.foot_position(&self.posture[leg]).ok()?;
        Some(centre - Vector3::z() * l.foot_radius())
    }

    /// Every leg's contact point, in model order.
    pub fn contact_points(&self) -> Vec<Point3<f64>> {
        (0..self.model.legs().len())
            .filter_map(|i| self.contact_point(i))
            .collect()
    }

    /// Where a foot's centre really is, world frame: for a lifted leg of a sagging robot,
    /// lower than its joints say by the sag taken so far ([`SimParams::sag`]); otherwise as
    /// [`Self::foot_centres`].
    pub fn real_foot_centre(&self, leg: usize) -> Option<Point3<f64>> {
        let l = self.model.legs().get(leg)?;
        let s = self.sagged(leg, &self.posture[leg], false);
        Some(s.body * l.foot_position(&s.q).ok()?)
    }

    /// How far the lifted leg's foot sits below where its joints put it, metres (0 when the
    /// robot does not sag or no leg is lifted).
    pub fn sag_drop_m(&self, leg: usize) -> f64 {
        match (self.real_foot_centre(leg), self.foot_centres().get(leg)) {
            (Some(real), Some(commanded)) => commanded.z - real.z,
            _ => 0.0,
        }
    }

    /// The centre of mass, legs included, world frame.
    pub fn centre_of_mass(&self) -> Point3<f64> {
        self.com_at(&self.body, &self.posture)
    }

    /// The static stability margin of the centre of mass over the standing feet's support
    /// polygon, metres (negative outside; minus infinity with no foot standing).
    pub fn margin(&self) -> f64 {
        stability_margin(&self.support(&self.stance), self.centre_of_mass())
    }

    /// The simulated clock, seconds since the start; only ever increases.
    pub fn clock_s(&self) -> f64 {
        self.clock_s
    }

    /// Falls, collisions and moves so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Whether the robot lies tipped over (it then refuses every move).
    pub fn fallen(&self) -> bool {
        self.fallen
    }

    /// The report of the last move carried out, also when it stopped early (a collision,
    /// no contact, a tip-over): its foot events are what happened.
    pub fn last_move(&self) -> Option<&MoveReport> {
        self.last.as_ref()
    }

    /// Where a standing foot touches the terrain, world frame: the terrain point that holds
    /// its sphere up (the bottom of the sphere on level ground, the edge on a step); for a
    /// foot in the air, the bottom of its sphere ([`Self::contact_point`]).
    pub fn touch_point(&self, leg: usize) -> Option<Point3<f64>> {
        let bottom = self.contact_point(leg)?;
        if !self.stance.get(leg).copied().unwrap_or(false) {
            return Some(bottom);
        }
        let r = self.model.legs().get(leg)?.foot_radius();
        Some(crate::collide::touch_point(
            &self.terrain,
            nalgebra::Point2::new(bottom.x, bottom.y),
            r,
        ))
    }

    /// The robot's state as the `legged.supportState` inform reports it: every standing
    /// foot at the terrain point it touches ([`Self::touch_point`]).
    pub fn support_state(&self) -> SupportState {
        let feet = self
            .model
            .legs()
            .iter()
            .enumerate()
            .map(|(i, leg)| FootState {
                leg: leg.name().to_owned(),
                at: world_point(&self.touch_point(i).unwrap_or_else(Point3::origin)),
                stance: self.stance[i],
            })
            .collect();
        SupportState {
            t_s: self.clock_s,
            body: isometry_to_pose(&self.body),
            com: world_point(&self.centre_of_mass()),
            feet,
            margin_m: self.margin(),
        }
    }

    /// One leg's state as the `legged.legState` query answers it (force: the robot's weight
    /// shared equally by the standing feet).
    pub fn leg_state(&self, leg: &str) -> Result<LegStateReply, MoveError> {
        let i = self.leg_index(leg, MoveCommand::Leg)?;
        let standing = self.stance.iter().filter(|&&s| s).count().max(1);
        let force = if self.stance[i] {
            self.model.total_mass() * 9.80665 / standing as f64
        } else {
            0.0
        };
        Ok(LegStateReply {
            leg: leg.to_owned(),
            joints: self.posture[i].clone(),
            foot: world_point(&self.contact_point(i).unwrap_or_else(Point3::origin)),
            stance: self.stance[i],
            force_n: force,
        })
    }

    /// The names of the standing legs.
    pub fn standing_legs(&self) -> Vec<String> {
        self.model
            .legs()
            .iter()
            .zip(&self.stance)
            .filter(|(_, s)| **s)
            .map(|(l, _)| l.name().to_owned())
            .collect()
    }

    pub(crate) fn leg_index(&self, leg: &str, command: MoveCommand) -> Result<usize, MoveError> {
        self.model.leg_index(leg).ok_or_else(|| MoveError::Refused {
            command,
            leg: Some(leg.to_owned()),
            reason: format!(
                "the robot has no leg `{leg}`; its legs are {}",
                self.model
                    .legs()
                    .iter()
                    .map(|l| format!("`{}`", l.name()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
    }

    /// The support polygon of the feet marked standing, from their anchors.
    /// The support polygon of the feet marked in `stance`: the terrain points their
    /// spheres touch (the point under the centre on level ground).
    pub(crate) fn support(&self, stance: &[bool]) -> Polygon {
        let feet: Vec<Point2<f64>> = self
            .anchors
            .iter()
            .zip(self.model.legs())
            .zip(stance)
            .filter(|(_, s)| **s)
            .map(|((p, leg), _)| {
                let t = crate::collide::touch_point(
                    &self.terrain,
                    Point2::new(p.x, p.y),
                    leg.foot_radius(),
                );
                Point2::new(t.x, t.y)
            })
            .collect();
        support_polygon(&feet)
    }

    pub(crate) fn com_at(&self, body: &Isometry3<f64>, posture: &[Vec<f64>]) -> Point3<f64> {
        match self.model.centre_of_mass(posture) {
            Ok(m) => body * m.centre,
            Err(_) => Point3::new(f64::NAN, f64::NAN, f64::NAN),
        }
    }

    /// The first link shape in the terrain for this body pose and posture, only among the
    /// shapes of `leg` when given; (link, deepest point).
    pub(crate) fn link_contacts(
        &self,
        body: &Isometry3<f64>,
        posture: &[Vec<f64>],
        leg: Option<usize>,
    ) -> Vec<(String, Point3<f64>)> {
        let Ok(shapes) = self.model.collision_shapes(posture) else {
            return Vec::new();
        };
        let mut hits: Vec<(String, Point3<f64>)> = Vec::new();
        for (shape, on) in shapes.iter().zip(&self.shape_legs) {
            if leg.is_some() && *on != leg {
                continue;
            }
            let pose = body * shape.pose;
            if let Some((at, _)) = shape_contact(&self.terrain, &self.blocks, &shape.shape, &pose)
                && !hits.iter().any(|(l, _)| l == shape.link)
            {
                hits.push((shape.link.to_owned(), at));
            }
        }
        hits
    }

    pub(crate) fn link_contact(
        &self,
        body: &Isometry3<f64>,
        posture: &[Vec<f64>],
        leg: Option<usize>,
    ) -> Option<(String, Point3<f64>)> {
        self.link_contacts(body, posture, leg).into_iter().next()
    }

    /// The sag a leg lifting now starts, when the robot sags: the body's displacement as
    /// its load moves onto the other standing feet, and the limb's droop.
    pub(crate) fn begin_sag(&self, i: usize) -> Option<crate::sag::Sag> {
        let params = self.params.sag?;
        let inverse = self.body.inverse();
        let feet: Vec<Point3<f64>> = self.anchors.iter().map(|a| inverse * a).collect();
        let com = self.model.centre_of_mass(&self.posture).ok()?.centre;
        let weight = self.model.total_mass() * crate::sag::GRAVITY;
        let mut after = self.stance.clone();
        after[i] = false;
        let body = crate::sag::body_sag(
            &feet,
            &self.stance,
            &after,
            &com,
            weight,
            params.leg_stiffness_n_per_m,
        );
        let l = &self.model.legs()[i];
        let nominal = self.body * l.foot_position(&self.posture[i]).ok()?;
        Some(crate::sag::Sag {
            leg: i,
            body,
            from: nominal,
            taken: 0.0,
            lifted: false,
        })
    }

    /// How the lifted leg's joints give under gravity at commanded joints `q`.
    fn droop(&self, i: usize, q: &[f64]) -> Vec<f64> {
        let Some(params) = self.params.sag else {
            return vec![0.0; q.len()];
        };
        let gravity = self.body.rotation.inverse() * (-Vector3::z() * crate::sag::GRAVITY);
        crate::sag::limb_droop(
            &self.model,
            &self.posture,
            i,
            q,
            &gravity,
            params.joint_compliance_rad_per_nm,
        )
    }

    /// The body pose and the leg's joints as they really are when leg `i` is commanded to
    /// `q`, and the sag taken (see [`crate::sag`]); as commanded when the robot does not
    /// sag. With `update` the share of the load off a foot not yet lifted off follows `q`;
    /// without, the share last kept ([`Self::take_sag`]) is used.
    pub(crate) fn sagged(&self, i: usize, q: &[f64], update: bool) -> Sagged {
        let Some(sag) = self.sag.as_ref().filter(|s| s.leg == i) else {
            return Sagged {
                body: self.body,
                q: q.to_vec(),
                taken: 0.0,
                lifted: true,
                drag_m: 0.0,
            };
        };
        let l = &self.model.legs()[i];
        let droop = self.droop(i, q);
        let real = |t: f64| {
            let body = self.body * crate::sag::partial(&sag.body, t);
            let q: Vec<f64> = q.iter().zip(&droop).map(|(a, d)| a + t * d).collect();
            body * l.foot_position(&q).unwrap_or_else(|_| Point3::origin())
        };
        let (mut taken, mut lifted) = (sag.taken, sag.lifted);
        if update && !lifted {
            // The share of the load off the foot: the robot sags until the foot would go
            // below where it lifted off, so that it leaves the ground only once the
            // commanded rise exceeds the full sag (found by bisection: the foot sinks as
            // the sag grows).
            if real(1.0).z >= sag.from.z {
                (taken, lifted) = (1.0, true);
            } else if real(0.0).z <= sag.from.z {
                taken = 0.0;
            } else {
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..24 {
                    let mid = 0.5 * (lo + hi);
                    if real(mid).z >= sag.from.z {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                taken = lo;
            }
        }
        // Dragged: the foot commanded away sideways while it still bears load (the sag's
        // own sideways give is the structure bending over the pinned foot, not a drag).
        let commanded = self.body * l.foot_position(q).unwrap_or_else(|_| Point3::origin());
        let drag_m = if lifted {
            0.0
        } else {
            (commanded.x - sag.from.x).hypot(commanded.y - sag.from.y)
        };
        Sagged {
            body: self.body * crate::sag::partial(&sag.body, taken),
            q: q.iter().zip(&droop).map(|(a, d)| a + taken * d).collect(),
            taken,
            lifted,
            drag_m,
        }
    }

    /// Keeps the share of the sag the lifted leg has taken.
    pub(crate) fn take_sag(&mut self, s: &Sagged) {
        if let Some(sag) = self.sag.as_mut() {
            sag.taken = s.taken;
            sag.lifted = s.lifted;
        }
    }

    /// Joints of leg `i` that put its foot's centre at world `centre` with the body where it
    /// is, from `q`; `q` when none do.
    pub(crate) fn reach_to(&self, i: usize, centre: &Point3<f64>, q: &[f64]) -> Vec<f64> {
        let l = &self.model.legs()[i];
        let target = self.body.inverse() * centre;
        l.inverse_kinematics(&target, &IkOptions::starting_at(q))
            .map(|s| s.joints)
            .unwrap_or_else(|_| q.to_vec())
    }

    /// A foot's clearance over the ground for this body pose and leg joints.
    pub(crate) fn clearance(&self, body: &Isometry3<f64>, leg: usize, q: &[f64]) -> f64 {
        let l = &self.model.legs()[leg];
        match l.foot_position(q) {
            Ok(c) => {
                let c = body * c;
                let r = l.foot_radius();
                // Well above everything under it: the height over that is enough.
                let above = c.z - r - self.blocks.bound(&self.terrain, Point2::new(c.x, c.y), r);
                if above > self.params.contact_tolerance_m {
                    return above;
                }
                foot_clearance(&self.terrain, &c, r)
            }
            Err(_) => f64::NAN,
        }
    }

    /// Counts a move starting now and opens its report.
    pub(crate) fn begin_move(&mut self, min_margin_m: f64) -> MoveReport {
        self.counters.moves += 1;
        MoveReport {
            start_s: self.clock_s,
            duration_s: 0.0,
            samples: 0,
            min_margin_m,
            events: Vec::new(),
            contact: None,
        }
    }

    /// Marks a tip-over: the robot lies on the ground from now on.
    pub(crate) fn tip_over(&mut self, command: MoveCommand, margin_m: f64) -> MoveError {
        self.fallen = true;
        self.counters.falls += 1;
        tracing::warn!(margin_m, "the robot tipped over");
        MoveError::TipOver {
            command,
            com: self.centre_of_mass(),
            margin_m,
            standing: self.standing_legs(),
        }
    }
}

/// Where a leg really is (see [`LeggedSim::sagged`]).
pub(crate) struct Sagged {
    /// The body's pose.
    pub(crate) body: Isometry3<f64>,
    /// The leg's joints.
    pub(crate) q: Vec<f64>,
    /// The share of the sag taken.
    pub(crate) taken: f64,
    /// Whether the foot has left the ground.
    pub(crate) lifted: bool,
    /// How far a foot still bearing load is commanded sideways from where it stood, metres.
    pub(crate) drag_m: f64,
}

/// Whether a margin falls short of a minimum (a NaN margin always does).
pub(crate) fn short_of(margin: f64, min: f64) -> bool {
    margin.is_nan() || margin < min
}
