//! An operator's FootFall session from the ground: for each step, the chosen leg's maps as
//! the robot stands now (from the ground-side planner, which reads the robot's state across
//! the bridge), a target picked from their green cells, the step planned by that planner and
//! the plan sent up to the robot-side executor as `footfall.execute`, its outcome and the
//! telemetry it raised waited for.
//!
//! The legs take turns in the description's order. Each step aims the foot `stride_m` from
//! where it stands along the body's x axis (forward on a leg's odd turns, back on its even
//! ones, so the robot stays where it stands) and takes the green cell nearest that point,
//! at least half a stride from the foot. Where the feet stand is asked once, at the start;
//! afterwards each foot is where its last touch-down came down as telemetry.

use std::time::{Duration, Instant};

use nalgebra::{Point2, Vector2};
use serde::Serialize;
use tca_footfall::maps::Colour;
use tca_footfall::plan::PlannerKind;
use tca_footfall_bus::{FootfallMaps, FootfallPlanStep, Telemetry, send_plan};
use tca_legged_messages::{BodyPose, LegState, RobotModel as AskModel};
use tca_messages::control::TaskOutcome;
use tca_messages::now_ns;
use tca_module::Module;

use crate::error::GroundError;
use crate::session::{SessionReport, StepRecord};

/// How a FootFall session goes.
#[derive(Clone, Debug, PartialEq)]
pub struct FootfallSessionOptions {
    /// Steps to take.
    pub steps: usize,
    /// How far from where it stands each step aims a foot, metres.
    pub stride_m: f64,
    /// The planner asked for each step.
    pub planner: PlannerKind,
    /// Plan with the field heuristics (terrain raised, way-points above start and target).
    pub heuristics: bool,
    /// The maps' cell size, metres.
    pub resolution_m: f64,
    /// How long a query may take (across the bridge: twice the delay and more).
    pub query_timeout: Duration,
}

impl Default for FootfallSessionOptions {
    fn default() -> Self {
        FootfallSessionOptions {
            steps: 10,
            stride_m: 0.3,
            planner: PlannerKind::Astar,
            heuristics: true,
            resolution_m: 0.1,
            query_timeout: Duration::from_secs(30),
        }
    }
}

/// What one FootFall step did beyond its outcome.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FootfallStep {
    /// The target picked from the maps, world XY.
    pub target: [f64; 2],
    /// Green cells in the leg's maps.
    pub green_cells: usize,
    /// Which planner found the swing (`astar`, or `sbl`).
    pub planner: String,
    /// Joint way-points of the smoothed swing.
    pub swing_waypoints: usize,
    /// From asking the maps to having them, seconds.
    pub maps_s: f64,
    /// From asking the plan to having it, seconds.
    pub plan_s: f64,
    /// From sending the plan to its outcome, seconds.
    pub execute_s: f64,
    /// Where the foot touched down (telemetry), world frame; `None` if no touch-down came.
    pub landed: Option<[f64; 3]>,
    /// Horizontal distance from the target to the touch-down, metres.
    pub landed_error_m: Option<f64>,
}

/// The target for a foot at `foot` aiming at `aim`: the green cell of `maps` nearest `aim`,
/// at least `min_m` from the foot.
fn pick_target(
    maps: &tca_footfall::maps::LegMaps,
    foot: Point2<f64>,
    aim: Point2<f64>,
    min_m: f64,
) -> Option<Point2<f64>> {
    maps.cells_of(Colour::Green)
        .into_iter()
        .map(|(ix, iy)| maps.centre(ix, iy))
        .filter(|p| (p - foot).norm() >= min_m)
        .min_by(|a, b| (a - aim).norm().total_cmp(&(b - aim).norm()))
}

/// Runs a FootFall session from `operator`, a module on the ground side beside the FootFall
/// planner; `progress` hears of each step as it ends. A step that fails ends the session
/// there. The records' `footfall` details come in the same order as the steps.
pub async fn run_footfall_session(
    operator: &Module,
    options: &FootfallSessionOptions,
    progress: impl Fn(&StepRecord, &FootfallStep),
) -> Result<(SessionReport, Vec<FootfallStep>), GroundError> {
    if !(options.stride_m.is_finite() && options.stride_m > 0.0) {
        return Err(GroundError::Setup(format!(
            "a stride of {} m: give a positive distance",
            options.stride_m
        )));
    }
    let timeout = options.query_timeout;
    // One round trip: the description, the body's pose and every foot.
    let (description, pose) = futures::future::try_join(
        operator.query_with_timeout(&AskModel, timeout),
        operator.query_with_timeout(&BodyPose, timeout),
    )
    .await?;
    let legs = description.legs.clone();
    if legs.is_empty() {
        return Err(GroundError::Setup("the robot has no legs".into()));
    }
    let queries: Vec<LegState> = legs.iter().map(|l| LegState { leg: l.clone() }).collect();
    let states = futures::future::try_join_all(
        queries
            .iter()
            .map(|q| operator.query_with_timeout(q, timeout)),
    )
    .await?;
    let mut feet: Vec<Point2<f64>> = states
        .iter()
        .map(|s| Point2::new(s.foot.x_m, s.foot.y_m))
        .collect();
    let heading = Vector2::new(pose.yaw_rad.cos(), pose.yaw_rad.sin());

    let mut steps = Vec::with_capacity(options.steps);
    let mut details = Vec::with_capacity(options.steps);
    for k in 0..options.steps {
        let i = k % legs.len();
        let leg = legs[i].clone();
        let forward = (k / legs.len()).is_multiple_of(2);
        let aim = feet[i]
            + heading
                * if forward {
                    options.stride_m
                } else {
                    -options.stride_m
                };

        let asked = Instant::now();
        let maps = operator
            .query_with_timeout(
                &FootfallMaps {
                    leg: leg.clone(),
                    polygon: None,
                    resolution_m: Some(options.resolution_m),
                },
                timeout,
            )
            .await?;
        let maps_s = asked.elapsed().as_secs_f64();
        let target = pick_target(&maps, feet[i], aim, options.stride_m / 2.0).ok_or_else(|| {
            GroundError::Setup(format!(
                "step {}: leg {leg} has no green cell {:.2} m or more from where it stands \
                 ({} green cells)",
                k + 1,
                options.stride_m / 2.0,
                maps.counts.green
            ))
        })?;

        let asked = Instant::now();
        let plan = operator
            .query_with_timeout(
                &FootfallPlanStep {
                    leg: leg.clone(),
                    target: [target.x, target.y],
                    planner: options.planner,
                    heuristics: options.heuristics,
                },
                timeout,
            )
            .await?;
        let plan_s = asked.elapsed().as_secs_f64();

        let sent_ns = now_ns();
        let sent = Instant::now();
        let mut landed = None;
        let outcome = send_plan(operator, &plan, Duration::from_millis(300), |t| {
            if let Telemetry::Contact(c) = t
                && c.leg == leg
                && c.stance
            {
                landed = Some([c.at.x_m, c.at.y_m, c.at.z_m]);
            }
        })
        .await?;
        let execute_s = sent.elapsed().as_secs_f64();
        let (achieved, outcome) = match outcome {
            TaskOutcome::Achieved => (true, "achieved".to_owned()),
            TaskOutcome::Failed(reason) => (false, reason),
            TaskOutcome::Killed => (false, "killed".to_owned()),
        };
        if let Some(at) = landed {
            feet[i] = Point2::new(at[0], at[1]);
        }
        let record = StepRecord {
            step: k + 1,
            leg: leg.clone(),
            sent_ns,
            ended_ns: now_ns(),
            achieved,
            outcome,
        };
        let detail = FootfallStep {
            target: [target.x, target.y],
            green_cells: maps.counts.green,
            planner: plan.planner.clone(),
            swing_waypoints: plan.swing_waypoints,
            maps_s,
            plan_s,
            execute_s,
            landed,
            landed_error_m: landed.map(|at| (Point2::new(at[0], at[1]) - target).norm()),
        };
        progress(&record, &detail);
        steps.push(record);
        details.push(detail);
        if !achieved {
            break;
        }
    }
    Ok((
        SessionReport {
            robot: description.name,
            achieved: steps.iter().filter(|s| s.achieved).count(),
            steps,
        },
        details,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_footfall::maps::LegMaps;

    fn maps(rows: &[&str]) -> LegMaps {
        let mut m: LegMaps = serde_json::from_value(serde_json::json!({
            "leg": "l", "origin": [0.0, 0.0], "resolution_m": 0.1,
            "nx": rows[0].len(), "ny": rows.len(),
            "rows": rows,
            "counts": {"green": 0, "red": 0, "orange": 0, "blue": 0},
            "now": {"com": [0.0, 0.0, 0.0], "support": [], "conservative": [],
                    "support_margin_m": 0.0, "conservative_margin_m": 0.0,
                    "lifted_support": [], "lifted_margin_m": 0.0},
            "params": tca_footfall::maps::MapParams::default(),
        }))
        .unwrap();
        m.counts.green = rows.iter().map(|r| r.matches('G').count()).sum();
        m
    }

    #[test]
    fn the_target_is_the_green_cell_nearest_the_aim_away_from_the_foot() {
        // Row 0 from x = 0: the foot at (0, 0); green at x = 0.0, 0.1, 0.3 and 0.5.
        let m = maps(&["GGRGRG"]);
        let foot = Point2::new(0.0, 0.0);
        let t = pick_target(&m, foot, Point2::new(0.35, 0.0), 0.15).unwrap();
        assert!((t.x - 0.3).abs() < 1e-9, "{t}");
        // The green cells near the foot are never picked, even when nearest the aim.
        let t = pick_target(&m, foot, Point2::new(0.0, 0.0), 0.15).unwrap();
        assert!((t.x - 0.3).abs() < 1e-9, "{t}");
        assert!(pick_target(&m, foot, Point2::new(0.0, 0.0), 0.6).is_none());
    }
}
