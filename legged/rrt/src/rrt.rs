//! RRT-Connect over the body's (x, y) (the paper's Algorithms 1 and 2): one tree rooted at
//! the start, one at the goal; each iteration extends one tree toward a random point and
//! then the other toward the new node until it is reached or blocked, and the trees swap.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::{Point2, Point3, Vector2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tca_legged_model::RobotModel;
use tca_robot::HeightField;

use crate::create::{Refusal, create_posture};
use crate::error::PlanError;
use crate::params::RrtParams;
use crate::pose::{BodyPose, Posture, wrap};
use crate::robot::Robot;
use crate::terrain::Terrain;
use crate::traverse::{Transition, check_traverse};

/// A node of a tree: a posture, its parent and the checked move between them (in the
/// direction the robot walks: parent to node in the start's tree, node to parent in the
/// goal's).
#[derive(Debug, Clone)]
pub struct Node {
    /// The robot's configuration.
    pub posture: Posture,
    /// Index of the parent in the same tree; `None` for the root.
    pub parent: Option<usize>,
    /// The move to or from the parent.
    pub transition: Option<Transition>,
}

/// One of the two trees.
#[derive(Debug, Clone)]
pub struct Tree {
    /// Its nodes; the root first.
    pub nodes: Vec<Node>,
    /// Whether the robot walks from the root outward (the start's tree) or toward it.
    pub forward: bool,
}

impl Tree {
    fn nearest(&self, q: Point2<f64>) -> usize {
        let mut best = (0, f64::INFINITY);
        for (i, n) in self.nodes.iter().enumerate() {
            let d = (n.posture.body.xy() - q).norm_squared();
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    }

    /// The tree's edges as (parent, child) positions, for pictures.
    pub fn edges(&self) -> Vec<(Point2<f64>, Point2<f64>)> {
        self.nodes
            .iter()
            .filter_map(|n| {
                n.parent
                    .map(|p| (self.nodes[p].posture.body.xy(), n.posture.body.xy()))
            })
            .collect()
    }
}

/// What one EXTEND did.
#[derive(Debug, Clone, PartialEq)]
pub enum Extension {
    /// The target itself became a node (its index).
    Reached(usize),
    /// A node part of the way to the target was added (its index).
    Advanced(usize),
    /// No node could be added; why the last try failed.
    Trapped(Refusal),
}

/// A planned walk.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Plan {
    /// The postures from the start to the goal.
    pub postures: Vec<Posture>,
    /// The moves between consecutive postures (one fewer than the postures).
    pub transitions: Vec<Transition>,
    /// The start's tree's edges (parent, child), world XY.
    pub start_tree: Vec<(Point2<f64>, Point2<f64>)>,
    /// The goal's tree's edges.
    pub goal_tree: Vec<(Point2<f64>, Point2<f64>)>,
    /// Figures of the search.
    pub stats: PlanStats,
}

impl Plan {
    /// The length of the body's path over the ground, metres.
    pub fn length_m(&self) -> f64 {
        self.postures
            .windows(2)
            .map(|w| (w[1].body.xy() - w[0].body.xy()).norm())
            .sum()
    }
}

/// Figures of a search.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct PlanStats {
    /// Iterations of the main loop run.
    pub iterations: usize,
    /// Nodes of both trees.
    pub nodes: usize,
    /// Extensions that failed, by reason.
    pub refusals: BTreeMap<String, usize>,
    /// Wall-clock time of the search, seconds.
    pub time_s: f64,
}

/// The planner: a robot on a terrain.
#[derive(Debug, Clone)]
pub struct Planner {
    robot: Robot,
    terrain: Terrain,
    params: RrtParams,
}

impl Planner {
    /// A planner for `model` on `terrain`; computes the foothold qualities of the whole
    /// map once.
    pub fn new(
        model: Arc<RobotModel>,
        terrain: Arc<HeightField>,
        params: RrtParams,
    ) -> Result<Planner, PlanError> {
        params.validate()?;
        let robot = Robot::new(model)?;
        let foot = (0..robot.leg_count())
            .map(|l| robot.foot_radius(l))
            .fold(0.0, f64::max);
        Ok(Planner {
            terrain: Terrain::new(terrain, foot),
            robot,
            params,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The terrain.
    pub fn terrain(&self) -> &Terrain {
        &self.terrain
    }

    /// The parameters.
    pub fn params(&self) -> &RrtParams {
        &self.params
    }

    /// Sets the seed of the random samples.
    pub fn set_seed(&mut self, seed: u64) {
        self.params.seed = seed;
    }

    /// A posture over `xy` facing `yaw`, starting from the neutral joints.
    pub fn posture_at(&self, xy: Point2<f64>, yaw: f64) -> Result<Posture, Refusal> {
        let neutral = self.robot.model().neutral_posture();
        create_posture(&self.robot, &self.terrain, &self.params, xy, yaw, &neutral)
    }

    /// Plans from the body over `start` facing `start_yaw` to the body over `goal` (facing
    /// the way from the start to the goal).
    pub fn plan(
        &self,
        start: Point2<f64>,
        start_yaw: f64,
        goal: Point2<f64>,
    ) -> Result<Plan, PlanError> {
        let posture = self
            .posture_at(start, start_yaw)
            .map_err(|r| PlanError::BadEndpoint {
                which: "start",
                x: start.x,
                y: start.y,
                reason: r.describe(),
            })?;
        self.plan_from(posture, goal)
    }

    /// The posture the robot stands in: its body pose, every foot's contact-sphere centre
    /// and every leg's joints (as a simulator or a robot reports them), with its centre of
    /// mass and margin computed; `None` when the joints do not fit the model.
    pub fn posture_from(
        &self,
        body: BodyPose,
        feet: Vec<Point3<f64>>,
        joints: Vec<Vec<f64>>,
    ) -> Option<Posture> {
        if feet.len() != self.robot.leg_count() || joints.len() != self.robot.leg_count() {
            return None;
        }
        let com = body.isometry() * self.robot.model().centre_of_mass(&joints).ok()?.centre;
        let feet_xy: Vec<Point2<f64>> = feet.iter().map(|f| Point2::new(f.x, f.y)).collect();
        let com_xy = Point2::new(com.x, com.y);
        Some(Posture {
            body,
            margin_m: crate::checks::margin(&feet_xy, com_xy),
            feet,
            joints,
            com: Point3::from(com.coords),
        })
    }

    /// Why the robot in posture `joints` with its body at `body` is not clear: two of its
    /// parts touching, or a link nearer the ground than `clearance_m`; `Ok` when clear.
    /// The checks the planner makes of every posture along a move.
    pub fn check_clear(
        &self,
        body: &nalgebra::Isometry3<f64>,
        joints: &[Vec<f64>],
        clearance_m: f64,
    ) -> Result<(), String> {
        let poses = self
            .robot
            .shape_poses(body, joints)
            .ok_or_else(|| "joint positions out of range".to_owned())?;
        if let Some(why) = crate::checks::self_collision(&self.robot, joints) {
            return Err(why);
        }
        if let Some(why) =
            crate::checks::terrain_collision(&self.robot, &self.terrain, &poses, clearance_m)
        {
            return Err(why);
        }
        Ok(())
    }

    /// Plans from the posture `start` (where the robot stands) to the body over `goal`
    /// (facing the way from the start to the goal).
    pub fn plan_from(&self, start_posture: Posture, goal: Point2<f64>) -> Result<Plan, PlanError> {
        let began = Instant::now();
        let start = start_posture.body.xy();
        let start_yaw = start_posture.body.yaw;
        let endpoint = |which: &'static str, p: Point2<f64>, yaw: f64| {
            self.posture_at(p, yaw).map_err(|r| PlanError::BadEndpoint {
                which,
                x: p.x,
                y: p.y,
                reason: r.describe(),
            })
        };
        let goal_yaw = {
            let d = goal - start;
            if d.norm() > 1e-9 {
                d.y.atan2(d.x)
            } else {
                start_yaw
            }
        };
        let root = |p: Posture| Node {
            posture: p,
            parent: None,
            transition: None,
        };
        let mut a = Tree {
            nodes: vec![root(start_posture)],
            forward: true,
        };
        let mut b = Tree {
            nodes: vec![root(endpoint("goal", goal, goal_yaw)?)],
            forward: false,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(self.params.seed);
        let (lo, hi) = self.terrain.extent();
        let mut stats = PlanStats::default();
        if (goal - start).norm() < self.params.min_step_m {
            let p = a.nodes[0].posture.clone();
            return Ok(Plan {
                postures: vec![p],
                transitions: Vec::new(),
                start_tree: Vec::new(),
                goal_tree: Vec::new(),
                stats,
            });
        }
        for k in 0..self.params.max_iterations {
            stats.iterations = k + 1;
            let q = Point2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
            match self.extend(&mut a, q, None) {
                Extension::Trapped(r) => *stats.refusals.entry(r.describe()).or_default() += 1,
                Extension::Advanced(i) | Extension::Reached(i) => {
                    let target = a.nodes[i].posture.clone();
                    loop {
                        match self.extend(&mut b, target.body.xy(), Some(&target)) {
                            Extension::Reached(j) => {
                                stats.nodes = a.nodes.len() + b.nodes.len();
                                stats.time_s = began.elapsed().as_secs_f64();
                                let (s, si, g, gi) = if a.forward {
                                    (&a, i, &b, j)
                                } else {
                                    (&b, j, &a, i)
                                };
                                return Ok(join(s, si, g, gi, stats));
                            }
                            Extension::Advanced(_) => {}
                            Extension::Trapped(r) => {
                                *stats.refusals.entry(r.describe()).or_default() += 1;
                                break;
                            }
                        }
                    }
                }
            }
            std::mem::swap(&mut a, &mut b);
        }
        let (s, g) = if a.forward { (&a, &b) } else { (&b, &a) };
        let mut gap = f64::INFINITY;
        for n in &s.nodes {
            let m = g.nearest(n.posture.body.xy());
            gap = gap.min((g.nodes[m].posture.body.xy() - n.posture.body.xy()).norm());
        }
        let reason = stats
            .refusals
            .iter()
            .max_by_key(|(_, c)| **c)
            .map(|(r, c)| format!("{r} ({c} times)"))
            .unwrap_or_else(|| "no extension was tried".to_owned());
        Err(PlanError::NoPath {
            iterations: stats.iterations,
            start_nodes: s.nodes.len(),
            goal_nodes: g.nodes.len(),
            gap_m: gap,
            reason,
        })
    }

    /// The paper's EXTEND: from the nearest node toward `q` by at most the longest step;
    /// when `given` is the target's posture (a node of the other tree) and it lies within a
    /// step, it is used as it is, so that the trees meet in one posture.
    pub fn extend(&self, tree: &mut Tree, q: Point2<f64>, given: Option<&Posture>) -> Extension {
        let near = tree.nearest(q);
        let near_posture = tree.nodes[near].posture.clone();
        let from = near_posture.body.xy();
        let d = q - from;
        let dist = d.norm();
        if dist < 1e-9 {
            return Extension::Trapped(Refusal::Move("the target is already a node".to_owned()));
        }
        let clipped = dist > self.params.max_step_m;
        let mut step: Vector2<f64> = d * (dist.min(self.params.max_step_m) / dist);
        let mut last = Refusal::Move("no try".to_owned());
        for k in 0..self.params.extend_attempts {
            if step.norm() < self.params.min_step_m {
                break;
            }
            let exact = k == 0 && !clipped;
            let posture = match given {
                Some(p) if exact => p.clone(),
                _ => {
                    let heading = if tree.forward {
                        step.y.atan2(step.x)
                    } else {
                        (-step.y).atan2(-step.x)
                    };
                    let turn = wrap(heading - near_posture.body.yaw)
                        .clamp(-self.params.max_turn_rad, self.params.max_turn_rad);
                    let yaw = wrap(near_posture.body.yaw + turn);
                    match create_posture(
                        &self.robot,
                        &self.terrain,
                        &self.params,
                        from + step,
                        yaw,
                        &near_posture.joints,
                    ) {
                        Ok(p) => p,
                        Err(r) => {
                            last = r;
                            step *= 0.5;
                            continue;
                        }
                    }
                }
            };
            let checked = if tree.forward {
                check_traverse(
                    &self.robot,
                    &self.terrain,
                    &self.params,
                    &near_posture,
                    &posture,
                )
            } else {
                check_traverse(
                    &self.robot,
                    &self.terrain,
                    &self.params,
                    &posture,
                    &near_posture,
                )
            };
            match checked {
                Ok(t) => {
                    tree.nodes.push(Node {
                        posture,
                        parent: Some(near),
                        transition: Some(t),
                    });
                    let i = tree.nodes.len() - 1;
                    return if exact {
                        Extension::Reached(i)
                    } else {
                        Extension::Advanced(i)
                    };
                }
                Err(r) => {
                    last = r;
                    step *= 0.5;
                }
            }
        }
        Extension::Trapped(last)
    }
}

/// The path through the start's tree to node `si` and on through the goal's tree from
/// node `gi` (the same posture) to its root.
fn join(start: &Tree, si: usize, goal: &Tree, gi: usize, stats: PlanStats) -> Plan {
    let mut chain = Vec::new();
    let mut i = Some(si);
    while let Some(k) = i {
        chain.push(k);
        i = start.nodes[k].parent;
    }
    chain.reverse();
    let mut postures: Vec<Posture> = chain
        .iter()
        .map(|&k| start.nodes[k].posture.clone())
        .collect();
    let mut transitions: Vec<Transition> = chain
        .iter()
        .filter_map(|&k| start.nodes[k].transition.clone())
        .collect();
    let mut j = gi;
    while let Some(p) = goal.nodes[j].parent {
        if let Some(t) = &goal.nodes[j].transition {
            transitions.push(t.clone());
        }
        postures.push(goal.nodes[p].posture.clone());
        j = p;
    }
    Plan {
        postures,
        transitions,
        start_tree: start.edges(),
        goal_tree: goal.edges(),
        stats,
    }
}
