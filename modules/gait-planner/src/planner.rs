//! The Gait Planner as a plain struct: builds the cost maps for one step, combines them and
//! chooses the footfall and the body move (§6.2.1).

use nalgebra::{Point2, Point3};
use tca_lrp::TerrainGrid;
use tca_robot::{CellIndex, ElbowBranch, Grid, LegKinematics, LegParams};
use tca_single_leg_messages::PlanePoint;

use crate::error::{GaitError, Result};
use crate::maps::CostMaps;
use crate::maps::advance::advance_map;
use crate::maps::elevation::{elevation_ok, ground_map};
use crate::maps::footfall::{Padded, clear_region, filtered_footfall, footfall_cost};
use crate::maps::visibility::visibility_map;
use crate::params::GaitParams;
use crate::region::{StepRegion, WalkDirection};

/// The carriage counts as at the goal within this distance, metres.
/// A carriage closer than this to the goal is at the goal, metres.
pub const AT_GOAL_M: f64 = 0.01;
/// A footfall must allow at least this much advance (or all that is left), metres.
const MIN_ADVANCE_M: f64 = 0.05;

/// The maps one step is planned from.
pub struct GaitMaps<'a> {
    /// The LTM Manager's footfall statistic (metres of deviation from a plane under the
    /// foot) over [`GaitPlanner::map_polygon`].
    pub footfall: &'a TerrainGrid,
    /// The LTM Manager's elevation map over the same polygon.
    pub elevation: &'a TerrainGrid,
    /// The Leg Recovery Planner's reachability: whether the foot can be brought above a
    /// world point from where it is.
    pub reachable: &'a dyn Fn(Point2<f64>) -> bool,
}

/// One planned step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepPlan {
    /// The footfall: the chosen cell's centre on the highest ground under the foot, world.
    pub footfall: Point3<f64>,
    /// Where the carriage goes after the leg is planted, world Y.
    pub body_target_y_m: f64,
    /// The body move, metres (negative walking backward).
    pub advance_m: f64,
    /// The elbow branch the advance was computed for: the foot must land with the elbow
    /// bent this way (a body move cannot change it).
    pub elbow: ElbowBranch,
    /// The composite cost of the chosen cell.
    pub cost: f64,
    /// The chosen cell of the region's grid.
    pub cell: CellIndex,
    /// The planning region.
    pub region: StepRegion,
    /// Every cost map.
    pub maps: CostMaps,
}

/// The Gait Planner.
#[derive(Debug, Clone)]
pub struct GaitPlanner {
    leg: LegParams,
    params: GaitParams,
    kin: LegKinematics,
    forward: Kinematic,
    backward: Kinematic,
}

/// The maps that depend only on the leg's kinematics and the cell's position relative to
/// the carriage, the same at every step: computed once per direction.
#[derive(Debug, Clone)]
struct Kinematic {
    advance: Grid<Option<(f64, ElbowBranch)>>,
    visibility: Grid<f64>,
}

impl Kinematic {
    fn new(
        leg: &LegParams,
        kin: &LegKinematics,
        params: &GaitParams,
        direction: WalkDirection,
    ) -> Result<Self> {
        let region = StepRegion::new(leg, params.grid.resolution_m, 0.0, direction)?;
        let advance = advance_map(&region, leg, kin);
        let threshold = params.body_advance.threshold_m;
        let visibility = visibility_map(
            &region,
            leg,
            kin,
            &params.scanner_visibility,
            &advance,
            |a| a.min(threshold),
        );
        Ok(Self {
            advance,
            visibility,
        })
    }
}

/// The same cells placed at another grid's origin (the region's, which has the same size).
fn relaid<T: Clone>(layout: &Grid<()>, cells: &Grid<T>) -> Grid<T> {
    Grid::from_vec(
        layout.origin(),
        layout.resolution_m(),
        cells.nx(),
        cells.ny(),
        cells.cells().to_vec(),
    )
    // Only a non-finite origin fails, which `StepRegion::new` refuses.
    .unwrap_or_else(|_| cells.clone())
}

impl GaitPlanner {
    /// A planner for a leg; both parameter sets are checked.
    pub fn new(leg: LegParams, params: GaitParams) -> Result<Self> {
        leg.validate()
            .map_err(|e| GaitError::LegParams(e.to_string()))?;
        params.validate()?;
        let kin = LegKinematics::new(&leg);
        let forward = Kinematic::new(&leg, &kin, &params, WalkDirection::Forward)?;
        let backward = Kinematic::new(&leg, &kin, &params, WalkDirection::Backward)?;
        Ok(Self {
            leg,
            params,
            kin,
            forward,
            backward,
        })
    }

    /// The planner's parameters.
    pub fn params(&self) -> &GaitParams {
        &self.params
    }

    /// The leg's parameters.
    pub fn leg_params(&self) -> &LegParams {
        &self.leg
    }

    /// The direction of the walk, or [`GaitError::AtGoal`].
    pub fn direction(&self, body_y_m: f64, goal_y_m: f64) -> Result<WalkDirection> {
        if !body_y_m.is_finite() {
            return Err(GaitError::NotFinite {
                what: "carriage position",
            });
        }
        if !goal_y_m.is_finite() {
            return Err(GaitError::NotFinite { what: "goal" });
        }
        if (goal_y_m - body_y_m).abs() <= AT_GOAL_M {
            return Err(GaitError::AtGoal { body_y_m, goal_y_m });
        }
        Ok(if goal_y_m > body_y_m {
            WalkDirection::Forward
        } else {
            WalkDirection::Backward
        })
    }

    /// The planning region for a step.
    pub fn region(&self, body_y_m: f64, goal_y_m: f64) -> Result<StepRegion> {
        let direction = self.direction(body_y_m, goal_y_m)?;
        StepRegion::new(
            &self.leg,
            self.params.grid.resolution_m,
            body_y_m,
            direction,
        )
    }

    /// The polygon the footfall and elevation maps must cover (the region grown by the
    /// filter's and the clear region's radius), for `mapRegion` queries.
    pub fn map_polygon(&self, region: &StepRegion) -> Vec<PlanePoint> {
        region.polygon(self.padding_m() + self.params.grid.resolution_m)
    }

    fn padding_m(&self) -> f64 {
        self.params
            .filtered_footfall
            .radius_m
            .max(0.5 * self.params.footfall.clear_diameter_m)
    }

    /// Plans one step from the carriage at `body_y_m` toward `goal_y_m`.
    pub fn plan(&self, body_y_m: f64, goal_y_m: f64, maps: &GaitMaps<'_>) -> Result<StepPlan> {
        let region = self.region(body_y_m, goal_y_m)?;
        let p = &self.params;
        let res = p.grid.resolution_m;
        let foot_radius = self.leg.leg.foot_radius_m;
        let remaining = (goal_y_m - body_y_m).abs();
        let rails = match region.direction {
            WalkDirection::Forward => self.leg.rails.y_max_m - body_y_m,
            WalkDirection::Backward => body_y_m - self.leg.rails.y_min_m,
        };
        let step_limit = p
            .body_advance
            .threshold_m
            .min(remaining)
            .min(rails.max(0.0));
        if step_limit <= AT_GOAL_M {
            return Err(GaitError::AtGoal { body_y_m, goal_y_m });
        }

        let pad = (self.padding_m() / res).ceil() as usize + 1;
        let statistic = Padded::sample(&region, maps.footfall, pad, |v| v.known());
        let elevation_known = Padded::sample(&region, maps.elevation, pad, |v| v.known().is_some());
        let footfall = footfall_cost(&region, &statistic, &p.footfall);
        let filtered = filtered_footfall(
            &region,
            &statistic,
            p.footfall.worst_m,
            p.filtered_footfall.radius_m,
            p.filtered_footfall.distance_scale_m,
        );
        let clear = clear_region(
            &region,
            &statistic,
            &elevation_known,
            &p.footfall,
            foot_radius,
        );
        let cached = match region.direction {
            WalkDirection::Forward => &self.forward,
            WalkDirection::Backward => &self.backward,
        };
        let advance = relaid(&region.layout, &cached.advance);
        let body_advance_m = advance.map(|a| a.map(|(m, _)| m));
        let body_advance = body_advance_m.map(|a| match a {
            Some(m) => 1.0 - m.min(step_limit) / step_limit,
            None => 1.0,
        });
        let scanner_visibility = if step_limit < p.body_advance.threshold_m {
            visibility_map(
                &region,
                &self.leg,
                &self.kin,
                &p.scanner_visibility,
                &advance,
                |a| a.min(step_limit),
            )
        } else {
            relaid(&region.layout, &cached.visibility)
        };
        let mut reachable = region.grid_of(false);
        for (c, v) in reachable.iter_mut() {
            let kinematic = body_advance_m.get(c).is_some_and(|a| a.is_some());
            *v = kinematic && (maps.reachable)(region.layout.cell_center(c));
        }
        let ground_m = ground_map(&region, maps.elevation, foot_radius);
        let link_plane = self.leg.carriage.link_plane_height_m;
        let (z_min, z_max) = (
            link_plane - self.leg.leg.vertical.max_m,
            link_plane - self.leg.leg.vertical.min_m,
        );
        let elevation = elevation_ok(
            &ground_m,
            z_min + p.elevation.low_margin_m,
            z_max - p.elevation.high_margin_m,
        );

        let mut counts = Eliminated::default();
        let mut total = region.grid_of(None);
        let min_advance = MIN_ADVANCE_M.min(step_limit);
        let mut best: Option<(f64, f64, CellIndex)> = None;
        for (c, t) in total.iter_mut() {
            let ff = footfall.get(c).copied().flatten();
            let ground = ground_m.get(c).copied().flatten();
            let a = body_advance_m.get(c).copied().flatten();
            let reason = if ff.is_none() || ground.is_none() {
                Some(&mut counts.unknown)
            } else if !reachable.get(c).copied().unwrap_or(false) {
                Some(&mut counts.out_of_reach)
            } else if !elevation.get(c).copied().unwrap_or(false) {
                Some(&mut counts.elevation)
            } else if !clear.get(c).copied().unwrap_or(false) {
                Some(&mut counts.not_clear)
            } else if a.is_none_or(|a| a < min_advance) {
                Some(&mut counts.no_advance)
            } else {
                None
            };
            if let Some(n) = reason {
                *n += 1;
                continue;
            }
            let cost = p.weights.footfall * ff.unwrap_or(1.0)
                + p.weights.filtered_footfall * filtered.get(c).copied().unwrap_or(1.0)
                + p.weights.body_advance * body_advance.get(c).copied().unwrap_or(1.0)
                + p.weights.scanner_visibility * scanner_visibility.get(c).copied().unwrap_or(1.0);
            *t = Some(cost);
            let adv = a.unwrap_or(0.0);
            let better = match best {
                None => true,
                Some((bc, ba, _)) => cost < bc - 1e-12 || (cost <= bc + 1e-12 && adv > ba),
            };
            if better {
                best = Some((cost, adv, c));
            }
        }
        let Some((cost, a_max, cell)) = best else {
            return Err(GaitError::NoFootfall {
                cells: region.layout.len(),
                unknown: counts.unknown,
                out_of_reach: counts.out_of_reach,
                elevation: counts.elevation,
                not_clear: counts.not_clear,
                no_advance: counts.no_advance,
            });
        };
        let centre = region.layout.cell_center(cell);
        let ground = ground_m.get(cell).copied().flatten().unwrap_or(0.0);
        let advance_m = region.direction.sign() * a_max.min(step_limit);
        let elbow = advance
            .get(cell)
            .copied()
            .flatten()
            .map_or(ElbowBranch::Positive, |(_, b)| b);
        tracing::debug!(
            x_m = centre.x,
            y_m = centre.y,
            cost,
            advance_m,
            "footfall chosen"
        );
        Ok(StepPlan {
            footfall: Point3::new(centre.x, centre.y, ground),
            body_target_y_m: body_y_m + advance_m,
            advance_m,
            elbow,
            cost,
            cell,
            maps: CostMaps {
                footfall,
                filtered_footfall: filtered,
                body_advance_m,
                body_advance,
                scanner_visibility,
                reachable,
                ground_m,
                elevation_ok: elevation,
                clear,
                total,
            },
            region,
        })
    }
}

/// Cells eliminated, by the first reason found.
#[derive(Debug, Default)]
struct Eliminated {
    unknown: usize,
    out_of_reach: usize,
    elevation: usize,
    not_clear: usize,
    no_advance: usize,
}
