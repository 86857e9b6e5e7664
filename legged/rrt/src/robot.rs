//! What the planner needs of the robot model: its legs grouped by side, the neutral
//! footprint, and each collision shape reduced to a capsule (a segment and a radius) and
//! to points on its surface.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};
use tca_legged_model::{IkOptions, RobotModel};

use crate::error::PlanError;

/// A collision shape as the checks see it, in its own frame.
#[derive(Debug, Clone)]
pub(crate) struct ShapeProbe {
    /// The shape's link.
    pub link: String,
    /// Points over the shape and the radius each stands for (shape frame).
    pub points: Vec<(Point3<f64>, f64)>,
    /// The radius of the ball about the shape's centre that holds it.
    pub bounding_radius: f64,
}

/// The robot model prepared for planning.
#[derive(Debug, Clone)]
pub struct Robot {
    model: Arc<RobotModel>,
    /// Leg indices of the left side, front to rear.
    pub(crate) left: Vec<usize>,
    /// Leg indices of the right side, front to rear.
    pub(crate) right: Vec<usize>,
    /// Each leg's foot (contact-sphere centre) in the neutral posture, body frame.
    pub(crate) neutral_feet: Vec<Point3<f64>>,
    /// Body height over level ground in the neutral posture, metres.
    pub(crate) neutral_height: f64,
    /// Half extents of the body's box (the bounding box of the body's collision shapes).
    pub(crate) body_half: Vector3<f64>,
    /// Centre of that box, body frame.
    pub(crate) body_centre: Point3<f64>,
    pub(crate) probes: Vec<ShapeProbe>,
}

impl Robot {
    /// Prepares a model: it must have legs on both sides, as many on each, with a body
    /// collision shape.
    pub fn new(model: Arc<RobotModel>) -> Result<Robot, PlanError> {
        let neutral = model.neutral_posture();
        let neutral_feet = model
            .foot_positions(&neutral)
            .map_err(|e| PlanError::Model(e.to_string()))?;
        let mut left = Vec::new();
        let mut right = Vec::new();
        for (i, leg) in model.legs().iter().enumerate() {
            if leg.base_position().y >= 0.0 {
                left.push(i);
            } else {
                right.push(i);
            }
        }
        let front_first = |v: &mut Vec<usize>| {
            v.sort_by(|&a, &b| {
                let (pa, pb) = (
                    model.legs()[a].base_position(),
                    model.legs()[b].base_position(),
                );
                pb.x.total_cmp(&pa.x)
            })
        };
        front_first(&mut left);
        front_first(&mut right);
        if left.len() != right.len() || left.len() < 2 {
            return Err(PlanError::Model(format!(
                "`{}` has {} legs on the left and {} on the right; the tripod and wave gaits \
                 need at least two on each side and as many on both",
                model.name(),
                left.len(),
                right.len()
            )));
        }
        let shapes = model
            .collision_shapes(&neutral)
            .map_err(|e| PlanError::Model(e.to_string()))?;
        let mut probes = Vec::new();
        let (mut lo, mut hi) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for s in &shapes {
            let leg = model.link(s.link).and_then(|l| l.leg());
            if leg.is_none() {
                for p in s.shape.surface_points(0.5) {
                    let w = s.pose * p.0;
                    lo = lo.inf(&w.coords);
                    hi = hi.sup(&w.coords);
                }
            }
            probes.push(ShapeProbe {
                link: s.link.to_owned(),
                points: s.shape.surface_points(0.01),
                bounding_radius: s.shape.bounding_radius(),
            });
        }
        if !lo.x.is_finite() {
            return Err(PlanError::Model(format!(
                "`{}` has no collision shape on its body; give the body link a <collision>",
                model.name()
            )));
        }
        Ok(Robot {
            neutral_height: model.neutral_height(),
            body_half: (hi - lo) / 2.0,
            body_centre: Point3::from((hi + lo) / 2.0),
            model,
            left,
            right,
            neutral_feet,
            probes,
        })
    }

    /// The model.
    pub fn model(&self) -> &RobotModel {
        &self.model
    }

    /// The model, shared.
    pub fn model_arc(&self) -> Arc<RobotModel> {
        self.model.clone()
    }

    /// Number of legs.
    pub fn leg_count(&self) -> usize {
        self.neutral_feet.len()
    }

    /// The foot's contact radius of a leg, metres.
    pub fn foot_radius(&self, leg: usize) -> f64 {
        self.model.legs()[leg].foot_radius()
    }

    /// The body's height over level ground in the neutral posture, metres.
    pub fn neutral_height(&self) -> f64 {
        self.neutral_height
    }

    /// The leg groups that swing together: for the tripod gait two groups (alternate legs
    /// of the left side with the others of the right), for the wave gait one leg each, rear
    /// to front on the right and then on the left.
    pub fn swing_groups(&self, gait: crate::Gait) -> Vec<Vec<usize>> {
        match gait {
            crate::Gait::Tripod => {
                let mut a = Vec::new();
                let mut b = Vec::new();
                for (k, (&l, &r)) in self.left.iter().zip(&self.right).enumerate() {
                    if k % 2 == 0 {
                        a.push(l);
                        b.push(r);
                    } else {
                        a.push(r);
                        b.push(l);
                    }
                }
                vec![a, b]
            }
            crate::Gait::Wave => self
                .right
                .iter()
                .rev()
                .chain(self.left.iter().rev())
                .map(|&l| vec![l])
                .collect(),
        }
    }

    /// Joint positions of one leg that put its foot at `foot` (body frame), starting the
    /// search from `initial`; `None` when out of reach or beyond the joint limits (the
    /// workspace check).
    pub fn leg_ik(&self, leg: usize, foot: &Point3<f64>, initial: &[f64]) -> Option<Vec<f64>> {
        let options = IkOptions {
            tolerance_m: 2e-4,
            max_iterations: 60,
            random_starts: 0,
            initial: Some(initial.to_vec()),
            seed: 7,
        };
        self.model.legs()[leg]
            .inverse_kinematics(foot, &options)
            .ok()
            .map(|s| s.joints)
    }

    /// How far a leg's joints are from their limits: the smallest over its joints of the
    /// distance to the nearer limit over half the range, in 0..=1 (1 at the middle of every
    /// range, 0 on a limit).
    pub fn joint_slack(&self, leg: usize, q: &[f64]) -> f64 {
        self.model.legs()[leg]
            .joints()
            .iter()
            .zip(q)
            .map(|(j, &v)| {
                let l = j.limits();
                let half = l.span() / 2.0;
                if half <= 0.0 {
                    1.0
                } else {
                    ((v - l.lower).min(l.upper - v) / half).clamp(0.0, 1.0)
                }
            })
            .fold(1.0, f64::min)
    }

    /// Every collision shape's pose in the world for a body pose and posture, in the order
    /// of the probes.
    pub(crate) fn shape_poses(
        &self,
        body: &Isometry3<f64>,
        joints: &[Vec<f64>],
    ) -> Option<Vec<Isometry3<f64>>> {
        let shapes = self.model.collision_shapes(joints).ok()?;
        Some(shapes.iter().map(|s| body * s.pose).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Gait;

    fn hexapod() -> Robot {
        Robot::new(Arc::new(RobotModel::builtin("hexapod").unwrap())).unwrap()
    }

    #[test]
    fn hexapod_legs_are_grouped_by_side_and_gait() {
        let r = hexapod();
        assert_eq!((r.left.len(), r.right.len()), (3, 3));
        let m = r.model();
        assert!(m.legs()[r.left[0]].base_position().x > m.legs()[r.left[2]].base_position().x);
        let tripod = r.swing_groups(Gait::Tripod);
        assert_eq!(tripod.len(), 2);
        for g in &tripod {
            assert_eq!(g.len(), 3);
            // Each group has one middle leg and the two corner legs of the other side.
            let left = g.iter().filter(|l| r.left.contains(l)).count();
            assert!(left == 1 || left == 2);
        }
        let mut all: Vec<usize> = tripod.concat();
        all.sort_unstable();
        assert_eq!(all, (0..6).collect::<Vec<_>>());
        let wave = r.swing_groups(Gait::Wave);
        assert_eq!(wave.len(), 6);
        assert_eq!(wave[0], vec![r.right[2]]);
        assert_eq!(wave[5], vec![r.left[0]]);
        assert!(r.body_half.x > 0.1 && r.body_half.y > 0.05);
    }

    #[test]
    fn ik_reaches_the_neutral_foot_and_refuses_a_far_one() {
        let r = hexapod();
        let leg = r.left[0];
        let q0 = r.model().legs()[leg].neutral();
        let q = r.leg_ik(leg, &r.neutral_feet[leg], &q0).unwrap();
        let p = r.model().legs()[leg].foot_position(&q).unwrap();
        assert!((p - r.neutral_feet[leg]).norm() < 1e-3);
        let far = r.neutral_feet[leg] + Vector3::new(1.0, 1.0, 0.0);
        assert!(r.leg_ik(leg, &far, &q0).is_none());
        assert!(r.joint_slack(leg, &q0) > 0.0);
    }
}
