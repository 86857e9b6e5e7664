//! Foothold selection: for one leg at a given body pose, the cell near the neutral foot
//! position with the best footfall quality over its 3 x 3 neighbourhood, within the leg's
//! workspace, preferring footholds away from the workspace's border.
//!
//! The paper's foothold quality is a slip predictor learned on the robot (described in a
//! separate paper); this planner uses the terrain's footfall evaluation instead: how far
//! the ground under the foot strays from its tangent plane plus the slope's tangent,
//! summed over the 3 x 3 cells around the candidate (see [`Terrain::foothold_quality`]).
//! The border term is one minus the joints' slack from their limits
//! ([`Robot::joint_slack`]).

use nalgebra::{Isometry3, Point2, Point3};

use crate::params::RrtParams;
use crate::robot::Robot;
use crate::terrain::Terrain;

/// Candidates whose inverse kinematics is tried, best terrain quality first.
const MAX_IK_TRIES: usize = 24;
/// Reachable candidates compared before the best is taken.
const ENOUGH_REACHABLE: usize = 6;

/// A chosen foothold.
#[derive(Debug, Clone, PartialEq)]
pub struct Foothold {
    /// The foot's contact-sphere centre resting on the ground there, world.
    pub foot: Point3<f64>,
    /// The joint positions that put the foot there.
    pub joints: Vec<f64>,
    /// The score it won with (lower is better).
    pub score: f64,
}

/// The best foothold for `leg` with the body at `body` (body frame to world), or `None`
/// when no cell within the search radius is both acceptable and reachable. `initial` is
/// where the joint search starts.
pub fn select_foothold(
    robot: &Robot,
    terrain: &Terrain,
    params: &RrtParams,
    body: &Isometry3<f64>,
    leg: usize,
    initial: &[f64],
) -> Option<Foothold> {
    let r = robot.foot_radius(leg);
    let nominal = body * robot.neutral_feet[leg];
    let centre = Point2::new(nominal.x, nominal.y);
    let search = params.foothold_search_m;
    let mut candidates: Vec<(f64, Point2<f64>)> = terrain
        .cells_near(centre, search)
        .into_iter()
        .filter_map(|p| {
            let q = terrain.foothold_quality(p);
            q.is_finite()
                .then(|| (q + 0.1 * (p - centre).norm() / search, p))
        })
        .collect();
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let inverse = body.inverse();
    let mut best: Option<Foothold> = None;
    let mut reachable = 0;
    for (quality, p) in candidates.into_iter().take(MAX_IK_TRIES) {
        let foot = Point3::new(p.x, p.y, terrain.max_in_disc(p, r) + r);
        let local = inverse * foot;
        let Some(joints) = robot.leg_ik(leg, &local, initial) else {
            continue;
        };
        reachable += 1;
        let score = quality + params.border_weight * (1.0 - robot.joint_slack(leg, &joints));
        if best.as_ref().is_none_or(|b| score < b.score) {
            best = Some(Foothold {
                foot,
                joints,
                score,
            });
        }
        if reachable >= ENOUGH_REACHABLE {
            break;
        }
    }
    best
}
