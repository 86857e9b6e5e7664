//! The acceptance campaign: (leg, target) pairs drawn at random from the green cells of the
//! rover's maps on the built-in rock field, and for each:
//!
//! - the dense reference planner ([`crate::reference`]) decides whether the step is
//!   feasible at all (with the field heuristics);
//! - SBL with smoothing plans it, and the plan is checked from outside
//!   ([`crate::verify`]): margins, the 20 cm way-points, at most five swing way-points;
//! - task-space A* alone plans it, and A* with SBL as its fall-back;
//! - the SBL plan is carried out on the simulator with the limbs sagging under load, and so
//!   is a plan made without the heuristics (the terrain as it is, low way-points), counting
//!   the collisions of each; the plan without the heuristics is also carried out on a rigid
//!   robot, where it must not collide.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tca_legged_model::RobotModel;
use tca_legged_sim::{LeggedSim, SagParams, SimParams, StartPose};

use crate::collision::CheckerParams;
use crate::error::FootfallError;
use crate::maps::{Colour, leg_maps};
use crate::plan::{FootfallPlan, PlanOptions, PlannerKind, StepPlanner};
use crate::reference::{ReferenceParams, reference_path};
use crate::scene::Scene;
use crate::verify::check_plan;

/// What the campaign does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignParams {
    /// How many pairs.
    pub pairs: usize,
    /// Seed of the draw (and of SBL, plus the pair's number).
    pub seed: u64,
    /// Seed of the rock field.
    pub course_seed: u64,
    /// The reference planner's budget.
    pub reference: ReferenceParams,
    /// The simulated robot's sag.
    pub sag: SagParams,
    /// How steps are planned (with the heuristics; the campaign also plans without).
    pub options: PlanOptions,
}

impl Default for CampaignParams {
    fn default() -> Self {
        Self {
            pairs: 100,
            seed: 1,
            course_seed: 1,
            reference: ReferenceParams::default(),
            sag: SagParams::athlete(),
            options: PlanOptions::default(),
        }
    }
}

/// One planner's attempt at one pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Attempt {
    /// A plan came out.
    pub ok: bool,
    /// Planning time, milliseconds (the terrain mesh made beforehand).
    pub ms: f64,
    /// Its swing's way-points.
    pub swing_waypoints: usize,
    /// The outside check passed (margins, way-points, at most five).
    pub checked: bool,
    /// Which planner made it.
    pub planner: String,
    /// Why not, or what the check found.
    pub note: Option<String>,
}

/// What carrying a plan out on the simulator did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Execution {
    /// Collisions the simulator counted.
    pub collisions: u32,
    /// The foot stands at the end.
    pub landed: bool,
    /// The move's error, if any.
    pub error: Option<String>,
}

/// One pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairOutcome {
    /// The leg.
    pub leg: String,
    /// The target, world XY.
    pub target: [f64; 2],
    /// Why the step's problem could not be posed (a way-point unreachable or not clear of
    /// the terrain), or `None` when it could.
    pub problem_error: Option<String>,
    /// The reference planner found a path.
    pub feasible: bool,
    /// Its time, milliseconds.
    pub reference_ms: f64,
    /// SBL with smoothing.
    pub sbl: Attempt,
    /// A* alone.
    pub astar: Attempt,
    /// A* with SBL as its fall-back (the default planner).
    pub astar_then_sbl: Attempt,
    /// The SBL plan carried out on the sagging robot.
    pub sag_with_heuristics: Option<Execution>,
    /// A plan without the heuristics carried out on the sagging robot.
    pub sag_without_heuristics: Option<Execution>,
    /// That plan carried out on the rigid robot.
    pub rigid_without_heuristics: Option<Execution>,
    /// A plan with the 20 cm way-points but the terrain as it is (half the heuristics)
    /// carried out on the sagging robot.
    pub sag_waypoints_only: Option<Execution>,
}

/// The campaign's figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Pairs drawn.
    pub pairs: usize,
    /// Pairs whose problem could be posed.
    pub posed: usize,
    /// Pairs the reference planner proved feasible.
    pub feasible: usize,
    /// SBL successes among them.
    pub sbl_successes: usize,
    /// SBL's success rate on the feasible pairs.
    pub sbl_rate: f64,
    /// SBL plans that pass the outside check, of all SBL plans.
    pub sbl_checked: usize,
    /// SBL plans.
    pub sbl_plans: usize,
    /// Largest swing of an SBL plan, way-points.
    pub sbl_max_waypoints: usize,
    /// SBL's median and 90th-percentile planning time, milliseconds.
    pub sbl_ms: [f64; 2],
    /// A* alone: successes among the feasible pairs, rate, median and 90th-percentile time
    /// of its successes (milliseconds).
    pub astar_successes: usize,
    /// A*'s rate on the feasible pairs.
    pub astar_rate: f64,
    /// A*'s times, milliseconds.
    pub astar_ms: [f64; 2],
    /// A* then SBL: successes among the feasible pairs.
    pub combined_successes: usize,
    /// Its times (every attempt), milliseconds.
    pub combined_ms: [f64; 2],
    /// The reference planner's median time, milliseconds.
    pub reference_median_ms: f64,
    /// With sag: collisions of the plans made with the heuristics, over the pairs run.
    pub sag_collisions_with: u32,
    /// Plans with the heuristics carried out with sag.
    pub sag_runs_with: usize,
    /// With sag: collisions of the plans made without the heuristics.
    pub sag_collisions_without: u32,
    /// Pairs whose plan without the heuristics collided with sag.
    pub sag_pairs_colliding_without: usize,
    /// Plans without the heuristics carried out.
    pub sag_runs_without: usize,
    /// Those plans on the rigid robot: collisions.
    pub rigid_collisions_without: u32,
    /// With sag: collisions of the plans with the way-points but no raise.
    pub sag_collisions_waypoints_only: u32,
    /// Pairs whose plan with the way-points only collided with sag.
    pub sag_pairs_colliding_waypoints_only: usize,
    /// Plans with the way-points only carried out.
    pub sag_runs_waypoints_only: usize,
    /// Making the six legs' terrain meshes, milliseconds in all.
    pub mesh_setup_ms: f64,
}

/// The campaign's report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignReport {
    /// The parameters.
    pub params: CampaignParams,
    /// Every pair.
    pub pairs: Vec<PairOutcome>,
    /// The figures.
    pub summary: Summary,
}

fn percentile(values: &[f64], p: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let i = ((v.len() - 1) as f64 * p).round() as usize;
    v[i]
}

/// The rover standing at the rock field's start, on a simulator with `sag`.
pub fn rock_field_sim(
    course_seed: u64,
    sag: Option<SagParams>,
) -> Result<LeggedSim, FootfallError> {
    let course = tca_legged_courses::Course::builtin("rock-field", course_seed)
        .map_err(|e| FootfallError::Scene(e.to_string()))?;
    let model = Arc::new(
        RobotModel::builtin(course.robot_hint).map_err(|e| FootfallError::Scene(e.to_string()))?,
    );
    let mut params = SimParams::for_model(&model);
    params.sag = sag;
    let start = StartPose {
        x_m: course.start.x_m,
        y_m: course.start.y_m,
        yaw_rad: course.start.yaw_rad,
    };
    LeggedSim::new(model, Arc::new(course.terrain), start, params)
        .map_err(|e| FootfallError::Scene(format!("the rover cannot stand: {e}")))
}

/// Carries a plan out on a copy of `sim`.
pub fn execute(sim: &LeggedSim, plan: &FootfallPlan) -> Execution {
    let mut sim = sim.clone();
    let result = sim.leg_move(&plan.leg, &plan.leg_move_waypoints(), true);
    let leg = sim.model().leg_index(&plan.leg).unwrap_or(0);
    Execution {
        collisions: sim.counters().collisions,
        landed: sim.stance().get(leg).copied().unwrap_or(false),
        error: result.err().map(|e| e.to_string()),
    }
}

/// `n` (leg, target) pairs: a leg at random, then one of its green cells at random.
pub fn draw_pairs(
    scene: &Scene,
    map: &crate::maps::MapParams,
    n: usize,
    seed: u64,
) -> Result<Vec<(usize, Point2<f64>)>, FootfallError> {
    let legs = scene.model.legs().len();
    let mut greens = Vec::with_capacity(legs);
    for leg in 0..legs {
        let maps = leg_maps(scene, leg, map)?;
        greens.push(
            maps.cells_of(Colour::Green)
                .into_iter()
                .map(|(ix, iy)| maps.centre(ix, iy))
                .collect::<Vec<Point2<f64>>>(),
        );
    }
    if greens.iter().all(|g| g.is_empty()) {
        return Err(FootfallError::Scene(
            "no leg has a green cell: there is nowhere to step".into(),
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    Ok((0..n)
        .map(|_| {
            let leg = loop {
                let l = rng.random_range(0..legs);
                if !greens[l].is_empty() {
                    break l;
                }
            };
            (leg, greens[leg][rng.random_range(0..greens[leg].len())])
        })
        .collect())
}

/// Runs the campaign, calling `progress` after each pair.
pub fn run_campaign(
    params: &CampaignParams,
    mut progress: impl FnMut(usize, &PairOutcome),
) -> Result<CampaignReport, FootfallError> {
    let rigid = rock_field_sim(params.course_seed, None)?;
    let sagging = rock_field_sim(params.course_seed, Some(params.sag))?;
    let scene = Arc::new(Scene::from_sim(&rigid));
    let planner = StepPlanner::new(scene.clone(), params.options.clone())?;
    let legs = scene.model.legs().len();
    let draw = draw_pairs(&scene, &params.options.map, params.pairs, params.seed)?;
    // The meshes, made once (a terrain arrives before the operator plans on it).
    let mut mesh_setup_ms = 0.0;
    for leg in 0..legs {
        for raise in [params.options.raise_m(), 0.0] {
            // The campaign plans on the terrain raised (the heuristics) and as it is.
            mesh_setup_ms += planner.checker(leg, raise)?.1;
        }
    }
    let mut pairs = Vec::with_capacity(params.pairs);
    let checker_params = CheckerParams {
        margins: params.options.map.margins.clone(),
        resolution_rad: params.options.resolution_rad,
        raise_m: 0.0,
        terrain: true,
    };
    for (n, &(leg, target)) in draw.iter().enumerate() {
        let mut options = params.options.clone();
        options.sbl.seed = params.seed.wrapping_mul(1000).wrapping_add(n as u64);
        let attempt = |kind: PlannerKind, fallback: bool, options: &PlanOptions| {
            let mut o = options.clone();
            o.planner = kind;
            o.astar_fallback = fallback;
            let t = Instant::now();
            let result = planner.plan_with(leg, target, &o);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            match result {
                Ok(plan) => {
                    let check = check_plan(&scene, &plan, &checker_params);
                    let (checked, note) = match check {
                        Ok(c) if c.ok() => (true, None),
                        Ok(c) => (false, Some(format!("{c:?}"))),
                        Err(e) => (false, Some(e.to_string())),
                    };
                    (
                        Attempt {
                            ok: true,
                            ms,
                            swing_waypoints: plan.swing_waypoints,
                            checked,
                            planner: plan.planner.clone(),
                            note,
                        },
                        Some(plan),
                    )
                }
                Err(e) => (
                    Attempt {
                        ok: false,
                        ms,
                        swing_waypoints: 0,
                        checked: false,
                        planner: kind.name().to_owned(),
                        note: Some(e.to_string()),
                    },
                    None,
                ),
            }
        };
        let problem = planner.problem(leg, target, &options);
        let (posed, feasible, reference_ms) = match &problem {
            Ok(p) => {
                let t = Instant::now();
                let path = reference_path(
                    &p.checker,
                    &p.q_lift,
                    &p.q_drop,
                    &p.active,
                    &params.reference,
                );
                (None, path.is_some(), t.elapsed().as_secs_f64() * 1e3)
            }
            Err(e) => (Some(e.to_string()), false, 0.0),
        };
        let (sbl, sbl_plan) = attempt(PlannerKind::Sbl, false, &options);
        let (astar, _) = attempt(PlannerKind::Astar, false, &options);
        let (astar_then_sbl, _) = attempt(PlannerKind::Astar, true, &options);
        let mut without = options.clone();
        without.heuristics = None;
        let (_, plain_plan) = attempt(PlannerKind::Sbl, false, &without);
        let mut half = options.clone();
        half.heuristics = half
            .heuristics
            .map(|h| crate::plan::Heuristics { raise_m: 0.0, ..h });
        let (_, half_plan) = attempt(PlannerKind::Sbl, false, &half);
        let outcome = PairOutcome {
            leg: scene.model.legs()[leg].name().to_owned(),
            target: [target.x, target.y],
            problem_error: posed,
            feasible,
            reference_ms,
            sbl,
            astar,
            astar_then_sbl,
            sag_with_heuristics: sbl_plan.as_ref().map(|p| execute(&sagging, p)),
            sag_without_heuristics: plain_plan.as_ref().map(|p| execute(&sagging, p)),
            rigid_without_heuristics: plain_plan.as_ref().map(|p| execute(&rigid, p)),
            sag_waypoints_only: half_plan.as_ref().map(|p| execute(&sagging, p)),
        };
        progress(n, &outcome);
        pairs.push(outcome);
    }
    let summary = summarise(&pairs, mesh_setup_ms);
    Ok(CampaignReport {
        params: params.clone(),
        pairs,
        summary,
    })
}

fn summarise(pairs: &[PairOutcome], mesh_setup_ms: f64) -> Summary {
    let feasible: Vec<&PairOutcome> = pairs.iter().filter(|p| p.feasible).collect();
    let rate = |k: usize| {
        if feasible.is_empty() {
            f64::NAN
        } else {
            k as f64 / feasible.len() as f64
        }
    };
    let sbl_successes = feasible.iter().filter(|p| p.sbl.ok).count();
    let astar_successes = feasible.iter().filter(|p| p.astar.ok).count();
    let combined_successes = feasible.iter().filter(|p| p.astar_then_sbl.ok).count();
    let sbl_plans: Vec<&PairOutcome> = pairs.iter().filter(|p| p.sbl.ok).collect();
    let times = |f: &dyn Fn(&PairOutcome) -> Option<f64>| -> [f64; 2] {
        let v: Vec<f64> = pairs.iter().filter_map(f).collect();
        [percentile(&v, 0.5), percentile(&v, 0.9)]
    };
    let with: Vec<&Execution> = pairs
        .iter()
        .filter_map(|p| p.sag_with_heuristics.as_ref())
        .collect();
    let without: Vec<&Execution> = pairs
        .iter()
        .filter_map(|p| p.sag_without_heuristics.as_ref())
        .collect();
    let half: Vec<&Execution> = pairs
        .iter()
        .filter_map(|p| p.sag_waypoints_only.as_ref())
        .collect();
    let reference: Vec<f64> = pairs
        .iter()
        .filter(|p| p.problem_error.is_none())
        .map(|p| p.reference_ms)
        .collect();
    Summary {
        pairs: pairs.len(),
        posed: pairs.iter().filter(|p| p.problem_error.is_none()).count(),
        feasible: feasible.len(),
        sbl_successes,
        sbl_rate: rate(sbl_successes),
        sbl_checked: sbl_plans.iter().filter(|p| p.sbl.checked).count(),
        sbl_plans: sbl_plans.len(),
        sbl_max_waypoints: sbl_plans
            .iter()
            .map(|p| p.sbl.swing_waypoints)
            .max()
            .unwrap_or(0),
        sbl_ms: times(&|p| p.sbl.ok.then_some(p.sbl.ms)),
        astar_successes,
        astar_rate: rate(astar_successes),
        astar_ms: times(&|p| p.astar.ok.then_some(p.astar.ms)),
        combined_successes,
        combined_ms: times(&|p| p.problem_error.is_none().then_some(p.astar_then_sbl.ms)),
        reference_median_ms: percentile(&reference, 0.5),
        sag_collisions_with: with.iter().map(|e| e.collisions).sum(),
        sag_runs_with: with.len(),
        sag_collisions_without: without.iter().map(|e| e.collisions).sum(),
        sag_pairs_colliding_without: without.iter().filter(|e| e.collisions > 0).count(),
        sag_runs_without: without.len(),
        rigid_collisions_without: pairs
            .iter()
            .filter_map(|p| p.rigid_without_heuristics.as_ref())
            .map(|e| e.collisions)
            .sum(),
        sag_collisions_waypoints_only: half.iter().map(|e| e.collisions).sum(),
        sag_pairs_colliding_waypoints_only: half.iter().filter(|e| e.collisions > 0).count(),
        sag_runs_waypoints_only: half.len(),
        mesh_setup_ms,
    }
}
