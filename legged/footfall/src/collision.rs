//! Collision checking for one moving leg: its parts against the terrain mesh, against the
//! body and the other legs (which stand still), and against each other, each pair kept
//! apart by its margin from a [`MarginTable`]; and segments between configurations checked
//! by bisection down to a resolution in joint space.
//!
//! A configuration is checked with `parry3d` distance queries: a pair of parts collides
//! when they are closer than their margin. Cheap bounds come first (bounding balls for
//! parts, a pyramid of terrain maxima), so that most pairs cost no query. A part whose
//! centre has gone below the terrain surface collides too (a mesh is a surface, not a
//! solid).
//!
//! The wheel itself stands on the ground at the start and the end of a step. On the
//! vertical lift and drop segments ([`Phase::LiftOrDrop`]) it may touch the ground but not
//! sink into it; everywhere else it keeps the terrain margin like every other part.

use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::query;
use parry3d_f64::shape::{Ball, SharedShape};
use tca_legged_model::Shape;
use tca_legged_sim::collide::foot_clearance;

use crate::error::FootfallError;
use crate::margins::{MarginTable, part_class};
use crate::scene::Scene;
use crate::terrain::TerrainPatch;

/// Which rules a configuration is checked by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// In the air: every part keeps every margin.
    Free,
    /// Lifting off or putting down: the wheel may touch the ground, not sink into it.
    LiftOrDrop,
}

/// A collision found: which parts, how close, and the margin they had to keep.
#[derive(Debug, Clone, PartialEq)]
pub struct Hit {
    /// The moving leg's link.
    pub part: String,
    /// What it came too close to: `terrain`, a body link or another link.
    pub other: String,
    /// Their distance, metres (0 when touching or overlapping).
    pub distance_m: f64,
    /// The margin they had to keep, metres.
    pub margin_m: f64,
}

impl std::fmt::Display for Hit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} within {:.3} m of {} (margin {:.3} m)",
            self.part, self.distance_m, self.other, self.margin_m
        )
    }
}

/// A solid of the robot in the parry form.
#[derive(Clone)]
struct Solid {
    shape: SharedShape,
    /// From the model shape's frame to parry's (parry's cylinders run along Y).
    correction: Isometry3<f64>,
    /// Radius of a ball about the shape's origin that holds it.
    bound_m: f64,
}

impl Solid {
    fn of(shape: &Shape) -> Solid {
        let (solid, correction) = match *shape {
            Shape::Sphere { radius } => (SharedShape::ball(radius), Isometry3::identity()),
            Shape::Box { size } => (
                SharedShape::cuboid(size.x / 2.0, size.y / 2.0, size.z / 2.0),
                Isometry3::identity(),
            ),
            Shape::Cylinder { radius, length } => (
                SharedShape::cylinder(length / 2.0, radius),
                Isometry3::from_parts(
                    Translation3::identity(),
                    UnitQuaternion::from_euler_angles(std::f64::consts::FRAC_PI_2, 0.0, 0.0),
                ),
            ),
            Shape::Capsule { radius, length } => (
                SharedShape::capsule_z(length / 2.0, radius),
                Isometry3::identity(),
            ),
        };
        Solid {
            shape: solid,
            correction,
            bound_m: shape.bounding_radius(),
        }
    }
}

/// A part of the moving leg: one collision shape of one of its links, or its wheel.
#[derive(Clone)]
struct MovingPart {
    link: String,
    class: String,
    /// The leg's joints between the body and the link.
    stage: usize,
    solid: Solid,
    /// Whether this is the foot's sphere.
    wheel: bool,
}

/// A part that does not move while the leg does: the body's, and the other legs'.
#[derive(Clone)]
struct StillPart {
    link: String,
    pose: Pose,
    centre: Point3<f64>,
    solid: Solid,
}

/// The collision checker of one leg in one scene.
pub struct LegChecker {
    scene: Arc<Scene>,
    leg: usize,
    body_world: Isometry3<f64>,
    parts: Vec<MovingPart>,
    still: Vec<StillPart>,
    /// Margin per (moving part, still part).
    still_margins: Vec<Vec<f64>>,
    /// Pairs of moving parts checked against each other, with their margin.
    own_pairs: Vec<(usize, usize, f64)>,
    /// The terrain, or `None` for a checker of the robot's own parts only.
    terrain: Option<Arc<TerrainPatch>>,
    environment_m: f64,
    /// How far the wheel may dip into the ground on lift and drop, metres.
    touch_tolerance_m: f64,
    /// Joint-space resolution of segment checks, radians (L-infinity).
    resolution_rad: f64,
    checks: std::sync::atomic::AtomicU64,
}

impl std::fmt::Debug for LegChecker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LegChecker")
            .field("leg", &self.leg)
            .field("parts", &self.parts.len())
            .field("still", &self.still.len())
            .field("own_pairs", &self.own_pairs.len())
            .field("terrain", &self.terrain)
            .finish()
    }
}

/// How a checker is set up.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckerParams {
    /// The margins.
    pub margins: MarginTable,
    /// Joint-space resolution of segment checks, radians (L-infinity distance between
    /// checked configurations).
    pub resolution_rad: f64,
    /// The terrain is raised this much for planning, metres (0: as it is).
    pub raise_m: f64,
    /// Whether the terrain is checked at all (false: only the robot's parts against each
    /// other, for a foot standing on the ground).
    pub terrain: bool,
}

impl Default for CheckerParams {
    fn default() -> Self {
        Self {
            margins: MarginTable::default(),
            resolution_rad: 0.01,
            raise_m: 0.0,
            terrain: true,
        }
    }
}

/// Converts a pose to parry's form.
fn to_pose(iso: &Isometry3<f64>) -> Pose {
    let t = iso.translation.vector;
    let q = iso.rotation.quaternion();
    Pose::from_parts(
        Vector::new(t.x, t.y, t.z),
        Rotation::from_xyzw(q.i, q.j, q.k, q.w),
    )
}

impl LegChecker {
    /// The checker of leg `leg` of `scene`: its links' shapes and its wheel; the body's and
    /// every other leg's shapes where they stand now; the terrain within the leg's reach as
    /// a mesh, raised by `params.raise_m`.
    pub fn new(
        scene: Arc<Scene>,
        leg: usize,
        params: &CheckerParams,
    ) -> Result<LegChecker, FootfallError> {
        scene.check()?;
        params.margins.check()?;
        if !(params.resolution_rad.is_finite() && params.resolution_rad > 0.0) {
            return Err(FootfallError::Params(format!(
                "the segment resolution is {} rad; give a positive number",
                params.resolution_rad
            )));
        }
        let model = scene.model.clone();
        let l = model
            .leg_at(leg)
            .map_err(|e| FootfallError::Scene(e.to_string()))?;
        let leg_name = l.name().to_owned();
        let body_world = scene.body;
        // The moving parts, in the order leg_collision_shapes gives them, then the wheel.
        let q = &scene.posture[leg];
        let shapes = model
            .leg_collision_shapes(leg, q)
            .map_err(|e| FootfallError::Scene(e.to_string()))?;
        let mut parts = Vec::new();
        for s in &shapes {
            let stage = model.link(s.link).map(|k| k.stage()).unwrap_or(0);
            let solid = Solid::of(&s.shape);
            parts.push(MovingPart {
                link: s.link.to_owned(),
                class: part_class(s.link, Some(&leg_name)),
                stage,
                solid,
                wheel: false,
            });
        }
        if l.foot_radius() > 0.0 {
            let r = l.foot_radius();
            parts.push(MovingPart {
                link: l.foot_link().to_owned(),
                class: "foot".to_owned(),
                stage: l.dof(),
                solid: Solid {
                    shape: SharedShape::new(Ball::new(r)),
                    correction: Isometry3::identity(),
                    bound_m: r,
                },
                wheel: true,
            });
        }
        // Everything else, where it stands now.
        let all = model
            .collision_shapes(&scene.posture)
            .map_err(|e| FootfallError::Scene(e.to_string()))?;
        let mut still = Vec::new();
        let mut still_meta = Vec::new();
        for s in &all {
            let owner = model.link(s.link).and_then(|k| k.leg());
            if owner == Some(leg) {
                continue;
            }
            let solid = Solid::of(&s.shape);
            let world = body_world * s.pose;
            still.push(StillPart {
                link: s.link.to_owned(),
                pose: to_pose(&(world * solid.correction)),
                centre: Point3::from(world.translation.vector),
                solid,
            });
            let class = part_class(s.link, owner.map(|o| model.legs()[o].name()));
            still_meta.push((class, owner.is_none()));
        }
        // The other legs' wheels.
        for (i, other) in model.legs().iter().enumerate() {
            if i == leg || other.foot_radius() <= 0.0 {
                continue;
            }
            let c = scene.foot_centre(i, &scene.posture[i]);
            let r = other.foot_radius();
            still.push(StillPart {
                link: other.foot_link().to_owned(),
                pose: to_pose(&Isometry3::translation(c.x, c.y, c.z)),
                centre: c,
                solid: Solid {
                    shape: SharedShape::new(Ball::new(r)),
                    correction: Isometry3::identity(),
                    bound_m: r,
                },
            });
            still_meta.push(("foot".to_owned(), false));
        }
        let margins = &params.margins;
        let still_margins = parts
            .iter()
            .map(|p| {
                still_meta
                    .iter()
                    .map(|(class, on_body)| {
                        // The link mounted on the body (the hip) touches it by construction.
                        if *on_body && p.stage <= 1 {
                            f64::NAN
                        } else {
                            margins.margin(&p.class, class, *on_body, !*on_body)
                        }
                    })
                    .collect()
            })
            .collect();
        let mut own_pairs = Vec::new();
        for i in 0..parts.len() {
            for j in i + 1..parts.len() {
                // Links joined by one joint (or the same link) touch by construction.
                if parts[i].stage.abs_diff(parts[j].stage) <= 1 {
                    continue;
                }
                let m = margins.margin(&parts[i].class, &parts[j].class, false, false);
                own_pairs.push((i, j, m));
            }
        }
        let base = body_world * l.base_position();
        let half = l.reach_bound() + l.foot_radius() + margins.environment_m + 0.2;
        let terrain = if params.terrain {
            Some(Arc::new(TerrainPatch::around(
                &scene.terrain,
                Point2::new(base.x, base.y),
                half,
                params.raise_m,
            )?))
        } else {
            None
        };
        Ok(LegChecker {
            scene,
            leg,
            body_world,
            parts,
            still,
            still_margins,
            own_pairs,
            terrain,
            environment_m: margins.environment_m,
            touch_tolerance_m: 0.01,
            resolution_rad: params.resolution_rad,
            checks: std::sync::atomic::AtomicU64::new(0),
        })
    }

    /// The scene checked in.
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// The moving leg's index.
    pub fn leg(&self) -> usize {
        self.leg
    }

    /// The terrain patch (raised as planned), if the terrain is checked.
    pub fn terrain(&self) -> Option<&TerrainPatch> {
        self.terrain.as_deref()
    }

    /// The joint-space resolution of segment checks, radians.
    pub fn resolution_rad(&self) -> f64 {
        self.resolution_rad
    }

    /// Configurations checked so far.
    pub fn checks(&self) -> u64 {
        self.checks.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The world poses of the moving parts for the leg's joints `q`.
    fn part_poses(&self, q: &[f64]) -> Option<Vec<Isometry3<f64>>> {
        let model = &self.scene.model;
        let shapes = model.leg_collision_shapes(self.leg, q).ok()?;
        let mut poses: Vec<Isometry3<f64>> =
            shapes.iter().map(|s| self.body_world * s.pose).collect();
        if self.parts.last().is_some_and(|p| p.wheel) {
            let c = self.scene.foot_centre(self.leg, q);
            poses.push(Isometry3::translation(c.x, c.y, c.z));
        }
        Some(poses)
    }

    /// The first collision of the leg at joints `q`, or `None` when every margin is kept.
    /// Joints outside the limits are a collision with `joint limits`.
    pub fn check(&self, q: &[f64], phase: Phase) -> Option<Hit> {
        self.checks
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let l = &self.scene.model.legs()[self.leg];
        if !l.within_limits(q) {
            return Some(Hit {
                part: l.name().to_owned(),
                other: "joint limits".into(),
                distance_m: 0.0,
                margin_m: 0.0,
            });
        }
        let Some(poses) = self.part_poses(q) else {
            return Some(Hit {
                part: l.name().to_owned(),
                other: "kinematics".into(),
                distance_m: 0.0,
                margin_m: 0.0,
            });
        };
        for (k, (part, pose)) in self.parts.iter().zip(&poses).enumerate() {
            if let Some(hit) = self.against_terrain(part, pose, phase) {
                return Some(hit);
            }
            let centre = Point3::from(pose.translation.vector);
            let parry_pose = to_pose(&(pose * part.solid.correction));
            for (s, other) in self.still.iter().enumerate() {
                let margin = self.still_margins[k][s];
                if margin.is_nan() {
                    continue;
                }
                let reach = part.solid.bound_m + other.solid.bound_m + margin;
                if (centre - other.centre).norm_squared() > reach * reach {
                    continue;
                }
                if let Some(d) = distance(&parry_pose, &part.solid, &other.pose, &other.solid)
                    && too_close(d, margin)
                {
                    return Some(Hit {
                        part: part.link.clone(),
                        other: other.link.clone(),
                        distance_m: d,
                        margin_m: margin,
                    });
                }
            }
        }
        for &(i, j, margin) in &self.own_pairs {
            let (a, b) = (&self.parts[i], &self.parts[j]);
            let (pa, pb) = (&poses[i], &poses[j]);
            let reach = a.solid.bound_m + b.solid.bound_m + margin;
            if (pa.translation.vector - pb.translation.vector).norm_squared() > reach * reach {
                continue;
            }
            let (ppa, ppb) = (
                to_pose(&(pa * a.solid.correction)),
                to_pose(&(pb * b.solid.correction)),
            );
            if let Some(d) = distance(&ppa, &a.solid, &ppb, &b.solid)
                && too_close(d, margin)
            {
                return Some(Hit {
                    part: a.link.clone(),
                    other: b.link.clone(),
                    distance_m: d,
                    margin_m: margin,
                });
            }
        }
        None
    }

    fn against_terrain(
        &self,
        part: &MovingPart,
        pose: &Isometry3<f64>,
        phase: Phase,
    ) -> Option<Hit> {
        let terrain = self.terrain.as_deref()?;
        let c = Point3::from(pose.translation.vector);
        let r = part.solid.bound_m;
        if part.wheel && phase == Phase::LiftOrDrop {
            // The wheel may rest on the ground here; it may not sink into it.
            // Against the real ground, raised or not: the wheel stands on it.
            let clearance = foot_clearance(&self.scene.terrain, &c, r);
            return (clearance < -self.touch_tolerance_m).then(|| Hit {
                part: part.link.clone(),
                other: "terrain".into(),
                distance_m: 0.0,
                margin_m: 0.0,
            });
        }
        let margin = self.environment_m;
        let top = terrain.max_over(Point2::new(c.x, c.y), r + margin);
        if c.z - r - margin > top {
            return None;
        }
        let below = c.z < terrain.height_at(c.x, c.y);
        let d = if below {
            Some(0.0)
        } else {
            let parry_pose = to_pose(&(pose * part.solid.correction));
            query::distance(
                &parry_pose,
                part.solid.shape.as_ref(),
                &Pose::identity(),
                &terrain.mesh,
            )
            .ok()
            .map(|d| d.distance)
        };
        match d {
            Some(d) if too_close(d, margin) => Some(Hit {
                part: part.link.clone(),
                other: "terrain".into(),
                distance_m: d,
                margin_m: margin,
            }),
            _ => None,
        }
    }

    /// The first collision along the straight joint-space segment from `a` to `b` (both
    /// ends excluded: the caller checked them), found by bisection: the midpoint first,
    /// then the quarter points, and so on until the checked points are closer than the
    /// resolution. Returns the fraction of the way where it was found.
    pub fn segment(&self, a: &[f64], b: &[f64], phase: Phase) -> Result<(), (f64, Hit)> {
        let levels = bisection_levels(a, b, self.resolution_rad);
        for level in 1..=levels {
            let steps = 1usize << level;
            for k in (1..steps).step_by(2) {
                let f = k as f64 / steps as f64;
                let q = lerp(a, b, f);
                if let Some(hit) = self.check(&q, phase) {
                    return Err((f, hit));
                }
            }
        }
        Ok(())
    }

    /// Checks the bisection level `level` of a segment (its points at odd multiples of
    /// 2^-level), for planners that check lazily a level at a time.
    pub fn segment_level(&self, a: &[f64], b: &[f64], level: u32, phase: Phase) -> Option<Hit> {
        let steps = 1usize << level;
        (1..steps).step_by(2).find_map(|k| {
            let q = lerp(a, b, k as f64 / steps as f64);
            self.check(&q, phase)
        })
    }

    /// Every configuration of a path of way-points checked densely: each point at most the
    /// resolution from the next, ends included; the first collision.
    pub fn path_dense(&self, path: &[Vec<f64>], phase: Phase) -> Option<(usize, Hit)> {
        for (i, w) in path.windows(2).enumerate() {
            let n = (linf(&w[0], &w[1]) / self.resolution_rad).ceil().max(1.0) as usize;
            for k in 0..=n {
                if k == 0 && i > 0 {
                    continue;
                }
                let q = lerp(&w[0], &w[1], k as f64 / n as f64);
                if let Some(hit) = self.check(&q, phase) {
                    return Some((i, hit));
                }
            }
        }
        if path.len() == 1 {
            return self.check(&path[0], phase).map(|h| (0, h));
        }
        None
    }

    /// The body's pose in the world.
    pub fn body(&self) -> &Isometry3<f64> {
        &self.body_world
    }

    /// The world's vertical seen in the body frame.
    pub fn world_down_in_body(&self) -> nalgebra::Unit<Vector3<f64>> {
        nalgebra::Unit::new_normalize(self.body_world.rotation.inverse() * -Vector3::z())
    }
}

/// Whether parts `d` apart break a margin: closer than it, or touching.
fn too_close(d: f64, margin: f64) -> bool {
    d < margin || d <= 0.0
}

fn distance(pa: &Pose, a: &Solid, pb: &Pose, b: &Solid) -> Option<f64> {
    query::distance(pa, a.shape.as_ref(), pb, b.shape.as_ref())
        .ok()
        .map(|d| d.distance)
}

/// The bisection levels a segment needs so that its checked points lie closer than
/// `resolution` (L-infinity).
pub fn bisection_levels(a: &[f64], b: &[f64], resolution: f64) -> u32 {
    let d = linf(a, b);
    if d <= resolution {
        return 0;
    }
    (d / resolution).log2().ceil().clamp(0.0, 30.0) as u32
}

/// The L-infinity distance of two configurations.
pub fn linf(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The Euclidean distance of two configurations.
pub fn euclid(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The configuration a fraction `f` of the way from `a` to `b`.
pub fn lerp(a: &[f64], b: &[f64], f: f64) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + (y - x) * f).collect()
}
