//! The Leg Recovery Planner as a plain struct: checks its inputs, builds the configuration
//! space, runs the ETFA, extracts and verifies the trajectory, and answers reachability.

use std::borrow::Cow;
use std::collections::VecDeque;

use nalgebra::{Point2, Point3};
use tca_robot::{CarriagePose, ElbowBranch, Grid, JointPosition, LegKinematics, LegParams};
use tca_single_leg_messages::{Joints, LegMove};

use crate::cost::MotionCost;
use crate::cspace::{CCell, CSpace};
use crate::error::{PlanError, Result};
use crate::etfa::{self, SearchGoal};
use crate::params::LrpParams;
use crate::terrain_grid::TerrainGrid;
use crate::trajectory::{self, TrajectoryPoint};

/// A planned leg trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct LegPlan {
    /// Joint-space way-points for `legMove` (the start excluded); the last segment is the
    /// transition move straight down onto the footfall, aiming below the expected ground.
    pub waypoints: Vec<JointPosition>,
    /// The trajectory as (shoulder rad, elbow rad, sole height m) from the start to the
    /// expected contact with the ground.
    pub points: Vec<TrajectoryPoint>,
    /// Estimated time and energy of the trajectory down to the contact (joints at full
    /// speed, without the controller's acceleration blends).
    pub motion: MotionCost,
    /// `motion` weighed by the cost model (no turn penalties).
    pub cost: f64,
    /// The search's cost, turn penalties included.
    pub search_cost: f64,
    /// Turns of the C-space path.
    pub turns: usize,
    /// The C-space path.
    pub cells: Vec<CCell>,
    /// Cells expanded by the search (for pictures), row-major like the space.
    pub expanded: Vec<bool>,
    /// Search states expanded.
    pub expansions: usize,
    /// The leg at the expected contact.
    pub goal_joints: JointPosition,
}

impl LegPlan {
    /// The `legMove` command: the way-points with a transition move at the end.
    pub fn to_leg_move(&self) -> LegMove {
        LegMove {
            waypoints: self
                .waypoints
                .iter()
                .map(|q| Joints {
                    shoulder_rad: q.shoulder_rad,
                    elbow_rad: q.elbow_rad,
                    vertical_m: q.vertical_m,
                })
                .collect(),
            transition: true,
        }
    }
}

/// Which footfalls the foot can reach from where it is (the Gait Planner's binary map).
#[derive(Debug, Clone)]
pub struct Reachability<'a> {
    cs: Cow<'a, CSpace>,
    reachable: Vec<bool>,
}

impl Reachability<'_> {
    /// Whether the foot can be brought above the world point `p` (on either elbow branch)
    /// along free cells from where it is.
    pub fn reaches(&self, p: Point2<f64>) -> bool {
        let kin = self.cs.kinematics();
        let (_, z_max) = self.cs.z_range_m();
        let c = self
            .cs
            .pose()
            .to_carriage(kin.carriage(), &Point3::new(p.x, p.y, z_max - 0.5));
        [ElbowBranch::Positive, ElbowBranch::Negative]
            .into_iter()
            .filter_map(|b| kin.inverse(&Point3::new(c.x, c.y, c.z), b).ok())
            .any(|q| {
                let cell = self.cs.cell_at(q.shoulder_rad, q.elbow_rad);
                self.reachable
                    .get(self.cs.index(cell))
                    .copied()
                    .unwrap_or(false)
            })
    }

    /// Reachable C-space cells, row-major like the space.
    pub fn cells(&self) -> &[bool] {
        &self.reachable
    }

    /// The binary map over a world grid: `true` where the foot can reach.
    pub fn to_grid(
        &self,
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
    ) -> Result<Grid<bool>> {
        Grid::from_fn(origin, resolution_m, nx, ny, |_, p| self.reaches(p)).map_err(|e| {
            PlanError::BadMap {
                what: "reachability",
                reason: e.to_string(),
            }
        })
    }
}

/// The Leg Recovery Planner.
#[derive(Debug, Clone)]
pub struct LegRecoveryPlanner {
    leg: LegParams,
    params: LrpParams,
    kin: LegKinematics,
}

impl LegRecoveryPlanner {
    /// A planner for a leg; both parameter sets are checked.
    pub fn new(leg: LegParams, params: LrpParams) -> Result<Self> {
        leg.validate()
            .map_err(|e| PlanError::BadLegParams(e.to_string()))?;
        params.validate()?;
        let kin = LegKinematics::new(&leg);
        Ok(Self { leg, params, kin })
    }

    /// The leg's parameters.
    pub fn leg_params(&self) -> &LegParams {
        &self.leg
    }

    /// The planner's parameters.
    pub fn params(&self) -> &LrpParams {
        &self.params
    }

    /// The configuration space over an elevation map with the (level) carriage at
    /// `body_y_m`.
    pub fn cspace(&self, elevation: &TerrainGrid, body_y_m: f64) -> Result<CSpace> {
        if !body_y_m.is_finite() {
            return Err(PlanError::NotFinite {
                what: "carriage position",
            });
        }
        CSpace::build(
            &self.leg,
            &self.params,
            &CarriagePose::level(body_y_m),
            elevation,
        )
    }

    /// Plans the leg from `start` to the footfall (world frame) over an elevation map.
    pub fn plan(
        &self,
        elevation: &TerrainGrid,
        body_y_m: f64,
        start: &JointPosition,
        footfall: &Point3<f64>,
    ) -> Result<LegPlan> {
        let cs = self.cspace(elevation, body_y_m)?;
        self.plan_in(&cs, start, footfall)
    }

    /// Plans in a configuration space already built, landing on either elbow branch.
    pub fn plan_in(
        &self,
        cs: &CSpace,
        start: &JointPosition,
        footfall: &Point3<f64>,
    ) -> Result<LegPlan> {
        self.plan_on_branch(cs, start, footfall, None)
    }

    /// Plans in a configuration space already built, landing on elbow branch `elbow` if
    /// given (the body move that follows keeps the branch, so the Gait Planner's advance
    /// depends on it).
    pub fn plan_on_branch(
        &self,
        cs: &CSpace,
        start: &JointPosition,
        footfall: &Point3<f64>,
        elbow: Option<ElbowBranch>,
    ) -> Result<LegPlan> {
        let spec = self.check_start(cs, start)?;
        let relaxed;
        let cs = match spec.relaxed_m {
            Some(r) => {
                relaxed = cs.with_relaxed_cell(spec.cell, r);
                &relaxed
            }
            None => cs,
        };
        let start_cell = spec.cell;
        // The initial straight lift (at least `start_lift_m`, within reach): the search and
        // the trajectory start from its top.
        let (_, z_max) = cs.z_range_m();
        let z_true = spec.z0;
        let z0 = (z_true + self.params.start_lift_m).min(z_max).max(z_true);
        let goal = self.check_goal(cs, footfall, elbow)?;
        let outcome = etfa::search(cs, &self.params.cost, start_cell, z0, &goal.search).ok_or(
            PlanError::Unreachable {
                x_m: footfall.x,
                y_m: footfall.y,
            },
        )?;
        let q_goal = goal
            .joints
            .get(outcome.goal)
            .copied()
            .ok_or_else(|| PlanError::Internal("the search reached an unknown goal".into()))?;
        let mut points = trajectory::extract(
            cs,
            &outcome.cells,
            [start.shoulder_rad, start.elbow_rad, z0],
            [q_goal.shoulder_rad, q_goal.elbow_rad, goal.ground_m],
        )?;
        if z0 > z_true {
            points.insert(0, [start.shoulder_rad, start.elbow_rad, z_true]);
            // One straight lift, not two.
            if points.len() >= 3
                && (points[2][0] - start.shoulder_rad).abs() < 1e-12
                && (points[2][1] - start.elbow_rad).abs() < 1e-12
            {
                points.remove(1);
            }
        }
        trajectory::check_clearance(cs, &points).map_err(PlanError::Internal)?;
        let motion = self.params.cost.path(cs.speeds(), &points);
        let mut waypoints: Vec<JointPosition> = points
            .iter()
            .skip(1)
            .map(|p| cs.joints(p[0], p[1], p[2]))
            .collect();
        if let Some(last) = waypoints.last_mut() {
            *last = cs.joints(q_goal.shoulder_rad, q_goal.elbow_rad, goal.target_m);
        }
        tracing::debug!(
            cells = outcome.cells.len(),
            turns = outcome.turns,
            expansions = outcome.expansions,
            time_s = motion.time_s,
            "leg trajectory planned"
        );
        Ok(LegPlan {
            waypoints,
            points,
            motion,
            cost: self.params.cost.cost(motion),
            search_cost: outcome.cost,
            turns: outcome.turns,
            cells: outcome.cells,
            expanded: outcome.expanded,
            expansions: outcome.expansions,
            goal_joints: cs.joints(q_goal.shoulder_rad, q_goal.elbow_rad, goal.ground_m),
        })
    }

    /// Which C-space cells the foot can reach from `start` (8-connected through free cells,
    /// never cutting a blocked corner).
    pub fn reachability<'a>(
        &self,
        cs: &'a CSpace,
        start: &JointPosition,
    ) -> Result<Reachability<'a>> {
        let spec = self.check_start(cs, start)?;
        let cs: Cow<'a, CSpace> = match spec.relaxed_m {
            Some(r) => Cow::Owned(cs.with_relaxed_cell(spec.cell, r)),
            None => Cow::Borrowed(cs),
        };
        let start_cell = spec.cell;
        let (ns, ne) = cs.dims();
        let (_, z_max) = cs.z_range_m();
        let mut reachable = vec![false; ns * ne];
        let mut queue = VecDeque::from([start_cell]);
        reachable[cs.index(start_cell)] = true;
        while let Some(c) = queue.pop_front() {
            for (n, _) in cs.neighbours(c) {
                let i = cs.index(n);
                if !reachable[i] && cs.step_required_m(c, n) <= z_max {
                    reachable[i] = true;
                    queue.push_back(n);
                }
            }
        }
        Ok(Reachability { cs, reachable })
    }

    /// The start must be within limits, not inside mapped terrain, and free to move. The map
    /// near a planted foot is often a little above the sole (sand pressed down, the map's
    /// uncertainty): the trajectory lifts the foot straight up first, so only a map that is
    /// sure the ground is more than `start_tolerance_m` above the sole is a collision. A start
    /// cell blocked only by occluded or unknown terrain (the leg got there) is relaxed to its
    /// known terrain; the relaxed requirement is returned.
    fn check_start(&self, cs: &CSpace, start: &JointPosition) -> Result<StartSpec> {
        if !start.is_finite() {
            return Err(PlanError::NotFinite {
                what: "start joint position",
            });
        }
        self.kin
            .check_limits(start)
            .map_err(PlanError::StartOutOfLimits)?;
        let z0 = cs.foot_z_m(start);
        let xy = cs.foot_xy(start.shoulder_rad, start.elbow_rad);
        if let Some(top) = cs
            .obstacles()
            .max_known_lower_in_disc(xy, cs.foot_radius_m())
            && top > z0 + self.params.start_tolerance_m
        {
            return Err(PlanError::StartInCollision {
                x_m: xy.x,
                y_m: xy.y,
                depth_m: top - z0,
            });
        }
        let cell = cs.cell_at(start.shoulder_rad, start.elbow_rad);
        if cs.is_free(cell) {
            return Ok(StartSpec {
                cell,
                z0,
                relaxed_m: None,
            });
        }
        let relaxed = cs.start_requirement_m(cell);
        if relaxed > cs.z_range_m().1 {
            return Err(PlanError::StartBlocked {
                required_m: relaxed,
                max_m: cs.z_range_m().1,
            });
        }
        tracing::debug!(
            blocked_m = cs.required_m(cell),
            relaxed_m = relaxed,
            "start cell blocked by occluded or unknown terrain only: relaxed"
        );
        Ok(StartSpec {
            cell,
            z0,
            relaxed_m: Some(relaxed),
        })
    }

    /// The footfall must be on known ground within the foot's height range, within reach,
    /// and not inside grown obstacles.
    fn check_goal(
        &self,
        cs: &CSpace,
        footfall: &Point3<f64>,
        elbow: Option<ElbowBranch>,
    ) -> Result<GoalSpec> {
        if !(footfall.x.is_finite() && footfall.y.is_finite() && footfall.z.is_finite()) {
            return Err(PlanError::NotFinite { what: "footfall" });
        }
        let (x_m, y_m) = (footfall.x, footfall.y);
        let xy = Point2::new(x_m, y_m);
        let (mapped, known) = cs.obstacles().max_in_disc(xy, cs.foot_radius_m());
        if !known {
            return Err(PlanError::UnknownGoal { x_m, y_m });
        }
        let ground_m = mapped.max(footfall.z);
        let (z_min, z_max) = cs.z_range_m();
        let (lowest, highest) = (
            z_min + self.params.footfall_low_margin_m,
            z_max - self.params.clearance_m,
        );
        if !(ground_m >= lowest && ground_m <= highest) {
            return Err(PlanError::GoalHeightOutOfReach {
                x_m,
                y_m,
                ground_m,
                min_m: lowest,
                max_m: highest,
            });
        }
        let target_m = (mapped.min(footfall.z) - self.params.transition_overshoot_m).max(z_min);
        let p = cs
            .pose()
            .to_carriage(self.kin.carriage(), &Point3::new(x_m, y_m, ground_m));
        let mut joints = Vec::new();
        let mut first_error = None;
        let branches = match elbow {
            Some(b) => vec![b],
            None => vec![ElbowBranch::Positive, ElbowBranch::Negative],
        };
        for branch in branches {
            match self.kin.inverse(&p, branch) {
                Ok(q) => joints.push(q),
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        if joints.is_empty() {
            return Err(match first_error {
                Some(source) => PlanError::GoalOutOfReach {
                    x_m,
                    y_m,
                    body_y_m: cs.pose().y_m,
                    source,
                },
                None => PlanError::Internal("inverse kinematics gave no answer".into()),
            });
        }
        let mut search = Vec::new();
        let mut reachable_joints = Vec::new();
        let mut lowest_required = f64::INFINITY;
        for q in joints {
            let cell = cs.cell_at(q.shoulder_rad, q.elbow_rad);
            lowest_required = lowest_required.min(cs.required_m(cell));
            if cs.is_free(cell) {
                search.push(SearchGoal { cell, ground_m });
                reachable_joints.push(q);
            }
        }
        if search.is_empty() {
            return Err(PlanError::GoalBlocked {
                x_m,
                y_m,
                required_m: lowest_required,
                max_m: z_max,
            });
        }
        Ok(GoalSpec {
            search,
            joints: reachable_joints,
            ground_m,
            target_m,
        })
    }
}

/// A checked start.
struct StartSpec {
    cell: CCell,
    z0: f64,
    /// The start cell's requirement when relaxed.
    relaxed_m: Option<f64>,
}

/// A checked footfall.
struct GoalSpec {
    search: Vec<SearchGoal>,
    joints: Vec<JointPosition>,
    ground_m: f64,
    target_m: f64,
}
