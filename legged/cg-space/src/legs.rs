//! The robot's legs as the foot-level search checks its moves: for a foot at a point in the
//! body frame, the leg's joints (the robot's own inverse kinematics) and its parts (link
//! capsules and mass moment), each worked out once and kept.
//!
//! The range maps of [`CgRobot`](crate::CgRobot) say where a foot may be; these say whether
//! the whole leg can be there: the joints exist with the body at the height the search
//! holds it, no link of one leg comes within the leg clearance of another's, and the
//! centre of mass (from every link) stays over the standing feet.

use rustc_hash::FxHashMap;
use std::cell::RefCell;
use std::rc::Rc;

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
use tca_legged_model::{IkOptions, LegParts, RobotModel};

/// Body-frame targets are rounded to this before their leg is worked out, metres.
const QUANTUM_M: f64 = 0.005;

/// Leg poses worked out so far, by leg and quantised body-frame target.
type PoseCache = FxHashMap<(usize, [i64; 3]), Option<Rc<LegPose>>>;

/// One leg with its foot at a point: joints and parts.
#[derive(Debug, Clone)]
pub struct LegPose {
    /// Joint positions, from the body outwards.
    pub joints: Vec<f64>,
    /// The links' capsules and mass moment, body frame.
    pub parts: LegParts,
}

/// The body's pose over the ground: its origin's world position and height, its heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPose {
    /// World X, Y of the body origin, metres.
    pub at: Point2<f64>,
    /// World Z of the body origin, metres.
    pub z: f64,
    /// Heading, radians counter-clockwise from world +X.
    pub theta: f64,
}

impl BodyPose {
    /// The body frame in the world.
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.at.x, self.at.y, self.z),
            UnitQuaternion::from_euler_angles(0.0, 0.0, self.theta),
        )
    }

    /// A world point in the body frame.
    pub fn to_body(&self, p: Point3<f64>) -> Point3<f64> {
        let (s, c) = self.theta.sin_cos();
        let (dx, dy) = (p.x - self.at.x, p.y - self.at.y);
        Point3::new(c * dx + s * dy, -s * dx + c * dy, p.z - self.z)
    }

    /// A body-frame point's world X, Y.
    pub fn to_world_xy(&self, p: Point3<f64>) -> Point2<f64> {
        let (s, c) = self.theta.sin_cos();
        Point2::new(self.at.x + c * p.x - s * p.y, self.at.y + s * p.x + c * p.y)
    }

    /// Part of the way to `other` (`t` 0 here, 1 there; the heading the short way round).
    pub fn lerp(&self, other: &BodyPose, t: f64) -> BodyPose {
        let turn = (other.theta - self.theta + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        BodyPose {
            at: self.at + (other.at - self.at) * t,
            z: self.z + (other.z - self.z) * t,
            theta: self.theta + turn * t,
        }
    }
}

/// The legs of one robot, their poses worked out on demand and kept.
pub struct Legs<'a> {
    model: &'a RobotModel,
    /// Per leg, the pose at its neutral joints: stands in for a foot held up.
    neutral: Vec<Rc<LegPose>>,
    body_mass: f64,
    body_moment: Vector3<f64>,
    cache: RefCell<PoseCache>,
    solved: RefCell<u64>,
}

impl<'a> Legs<'a> {
    /// The legs of `model`.
    pub fn new(model: &'a RobotModel) -> Self {
        let neutral = model
            .legs()
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let joints = l.neutral();
                let parts = model
                    .leg_parts(i, &joints)
                    .expect("a leg's neutral joints are within its limits");
                Rc::new(LegPose { joints, parts })
            })
            .collect();
        let (body_mass, body_moment) = model.body_mass_moment();
        Legs {
            model,
            neutral,
            body_mass,
            body_moment,
            cache: RefCell::new(FxHashMap::default()),
            solved: RefCell::new(0),
        }
    }

    /// The leg `leg` with its foot's contact-sphere centre at `p` (body frame); `None` where
    /// its inverse kinematics finds no joints within the limits.
    pub fn at(&self, leg: usize, p: Point3<f64>) -> Option<Rc<LegPose>> {
        let key = (
            leg,
            [
                (p.x / QUANTUM_M).round() as i64,
                (p.y / QUANTUM_M).round() as i64,
                (p.z / QUANTUM_M).round() as i64,
            ],
        );
        if let Some(hit) = self.cache.borrow().get(&key) {
            return hit.clone();
        }
        let target = Point3::new(
            key.1[0] as f64 * QUANTUM_M,
            key.1[1] as f64 * QUANTUM_M,
            key.1[2] as f64 * QUANTUM_M,
        );
        let l = &self.model.legs()[leg];
        let options = IkOptions {
            random_starts: 2,
            initial: Some(l.neutral()),
            ..IkOptions::default()
        };
        *self.solved.borrow_mut() += 1;
        let pose = l.inverse_kinematics(&target, &options).ok().and_then(|s| {
            let parts = self.model.leg_parts(leg, &s.joints).ok()?;
            Some(Rc::new(LegPose {
                joints: s.joints,
                parts,
            }))
        });
        self.cache.borrow_mut().insert(key, pose.clone());
        pose
    }

    /// The parts of `leg` with its joints part of the way (`t`) from `a`'s to `b`'s, as a
    /// swing's travel moves them.
    pub fn between(&self, leg: usize, a: &LegPose, b: &LegPose, t: f64) -> Option<LegParts> {
        let q: Vec<f64> = a
            .joints
            .iter()
            .zip(&b.joints)
            .map(|(x, y)| x + (y - x) * t)
            .collect();
        self.model.leg_parts(leg, &q).ok()
    }

    /// The pose standing in for a foot held up.
    pub fn neutral(&self, leg: usize) -> Rc<LegPose> {
        self.neutral[leg].clone()
    }

    /// The centre of mass in the body frame with each leg's parts as given.
    pub fn com<'p>(&self, parts: impl Iterator<Item = &'p LegParts>) -> Point3<f64> {
        let (mut m, mut s) = (self.body_mass, self.body_moment);
        for p in parts {
            m += p.mass();
            s += p.moment();
        }
        Point3::from(s / m.max(1e-12))
    }

    /// Inverse kinematics solved so far (cache misses).
    pub fn solved(&self) -> u64 {
        *self.solved.borrow()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_puts_the_foot_where_asked_and_an_unreachable_point_has_none() {
        let model = RobotModel::builtin("ambler").expect("the ambler");
        let legs = Legs::new(&model);
        let leg = &model.legs()[0];
        let foot = leg.foot_position(&leg.neutral()).expect("fk");
        let p = legs.at(0, foot).expect("the neutral foot is reachable");
        let back = leg.foot_position(&p.joints).expect("fk");
        assert!((back - foot).norm() < 0.005);
        assert!(legs.at(0, Point3::new(30.0, 0.0, 0.0)).is_none());
        // Asked again: kept, not solved again.
        let n = legs.solved();
        let _ = legs.at(0, foot);
        assert_eq!(legs.solved(), n);
        // The whole robot's centre of mass, from the neutral parts.
        let com = legs.com((0..model.legs().len()).map(|i| &legs.neutral[i].parts));
        let whole = model
            .centre_of_mass(&model.neutral_posture())
            .expect("com")
            .centre;
        assert!((com - whole).norm() < 1e-9);
    }

    #[test]
    fn body_poses_map_points_both_ways() {
        let b = BodyPose {
            at: Point2::new(3.0, -1.0),
            z: 2.0,
            theta: 0.7,
        };
        let w = Point3::new(4.5, 0.25, 0.3);
        let local = b.to_body(w);
        let again = b.isometry() * local;
        assert!((again - w).norm() < 1e-12);
        assert!((b.to_world_xy(local) - Point2::new(w.x, w.y)).norm() < 1e-12);
        let other = BodyPose { theta: -3.0, ..b };
        // Half-way from 0.7 to -3.0 rad the short way round passes through π.
        let mid = b.lerp(&other, 0.5);
        assert!((mid.theta - (0.7 + (std::f64::consts::TAU - 3.7) / 2.0)).abs() < 1e-12);
    }
}
