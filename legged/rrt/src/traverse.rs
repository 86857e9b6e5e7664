//! The move between two postures (the paper's CHECK_TRAVERSE): the body along a straight
//! line with its angles changed linearly, the legs swinging in the gait's groups along
//! their convex-hull trajectories, every posture along the way checked for reach, static
//! stability over the standing feet, self-collision and terrain collision.

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};

use crate::checks::{margin, self_collision, statically_stable, terrain_collision};
use crate::create::Refusal;
use crate::params::RrtParams;
use crate::pose::{BodyPose, Posture};
use crate::robot::Robot;
use crate::terrain::Terrain;
use crate::trajectory::{foot_trajectory, path_length, point_along};

/// One leg's swing: its way-points from the old foothold to the new (world).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Swing {
    /// The leg.
    pub leg: usize,
    /// Way-points of the foot's contact-sphere centre, world, first and last on the
    /// footholds.
    pub path: Vec<Point3<f64>>,
}

/// One phase of a move: some legs swing while the body moves from one pose to the next.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Phase {
    /// The body's pose as the phase begins.
    pub body_from: BodyPose,
    /// The body's pose as it ends.
    pub body_to: BodyPose,
    /// The legs in the air and their paths.
    pub swings: Vec<Swing>,
    /// The smallest distance of the centre of mass inside the standing feet's support
    /// polygon over the phase, metres.
    pub min_margin_m: f64,
}

/// A checked move between two postures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Transition {
    /// The phases in order.
    pub phases: Vec<Phase>,
    /// The smallest margin over every phase, metres.
    pub min_margin_m: f64,
    /// Postures checked along the move.
    pub postures_checked: usize,
}

/// Checks the move from posture `from` to posture `to` and returns it, or why it fails.
pub fn check_traverse(
    robot: &Robot,
    terrain: &Terrain,
    params: &RrtParams,
    from: &Posture,
    to: &Posture,
) -> Result<Transition, Refusal> {
    let groups = robot.swing_groups(params.gait);
    let n = groups.len() as f64;
    let mut feet = from.feet.clone();
    let mut joints = from.joints.clone();
    let mut phases = Vec::with_capacity(groups.len());
    let mut checked = 0;
    let spacing = params.check_spacing_m;
    for (k, group) in groups.iter().enumerate() {
        let body_from = from.body.lerp(&to.body, k as f64 / n);
        let body_to = from.body.lerp(&to.body, (k + 1) as f64 / n);
        let swings: Vec<Swing> = group
            .iter()
            .map(|&leg| Swing {
                leg,
                path: foot_trajectory(
                    terrain,
                    feet[leg],
                    to.feet[leg],
                    robot.foot_radius(leg),
                    params.foot_clearance_m,
                    terrain.resolution_m(),
                ),
            })
            .collect();
        let body_len = (Point3::new(body_to.x, body_to.y, body_to.z)
            - Point3::new(body_from.x, body_from.y, body_from.z))
        .norm()
            + 0.15 * crate::pose::wrap(body_to.yaw - body_from.yaw).abs();
        let swing_len = swings
            .iter()
            .map(|s| path_length(&s.path))
            .fold(0.0, f64::max);
        let steps = ((body_len.max(swing_len) / spacing).ceil() as usize).max(2);
        let stance: Vec<usize> = (0..robot.leg_count())
            .filter(|l| !group.contains(l))
            .collect();
        let stance_xy: Vec<Point2<f64>> = stance
            .iter()
            .map(|&l| Point2::new(feet[l].x, feet[l].y))
            .collect();
        let mut min_margin = f64::INFINITY;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            let pose = body_from.lerp(&body_to, t);
            let iso = pose.isometry();
            let inv = iso.inverse();
            for leg in 0..robot.leg_count() {
                let target = match swings.iter().find(|s| s.leg == leg) {
                    Some(s) => point_along(&s.path, t),
                    None => feet[leg],
                };
                match robot.leg_ik(leg, &(inv * target), &joints[leg]) {
                    Some(q) => joints[leg] = q,
                    None => {
                        return Err(Refusal::Move(format!(
                            "leg `{}` cannot reach its foot {:.0}% into phase {}",
                            robot.model().legs()[leg].name(),
                            100.0 * t,
                            k + 1
                        )));
                    }
                }
            }
            let com = iso
                * robot
                    .model()
                    .centre_of_mass(&joints)
                    .map_err(|e| Refusal::Move(e.to_string()))?
                    .centre;
            let com_xy = Point2::new(com.x, com.y);
            if !statically_stable(&stance_xy, com_xy, params.stability_margin_m) {
                return Err(Refusal::Move(format!(
                    "the centre of mass leaves the shrunk support polygon {:.0}% into phase {}",
                    100.0 * t,
                    k + 1
                )));
            }
            min_margin = min_margin.min(margin(&stance_xy, com_xy));
            let poses = robot
                .shape_poses(&iso, &joints)
                .ok_or_else(|| Refusal::Move("joint positions out of range".to_owned()))?;
            if let Some(why) = self_collision(robot, &joints) {
                return Err(Refusal::Move(why));
            }
            if let Some(why) = terrain_collision(robot, terrain, &poses, 0.0) {
                return Err(Refusal::Move(why));
            }
            checked += 1;
        }
        for &leg in group {
            feet[leg] = to.feet[leg];
        }
        phases.push(Phase {
            body_from,
            body_to,
            swings,
            min_margin_m: min_margin,
        });
    }
    let min_margin_m = phases
        .iter()
        .map(|p| p.min_margin_m)
        .fold(f64::INFINITY, f64::min);
    Ok(Transition {
        phases,
        min_margin_m,
        postures_checked: checked,
    })
}
