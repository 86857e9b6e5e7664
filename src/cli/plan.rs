//! `tca plan rrt`: the integrated RRT-Connect motion planner for a multi-legged robot,
//! planning without walking.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use serde_json::json;
use tca_legged_courses::Course;
use tca_legged_courses::walls::WallsChecks;
use tca_legged_model::RobotModel;
use tca_rrt::nalgebra::Point2;
use tca_rrt::tca_robot::HeightField;
use tca_rrt::tca_robot::terrain::asc::{NoData, read_height_field};
use tca_rrt::{Gait, Plan, Planner, RrtParams, write_plan_png};

use super::legged_walk::parse_place;

/// `tca plan ...`.
#[derive(Debug, Subcommand)]
pub(crate) enum PlanCommand {
    /// Plan a statically stable walk with RRT-Connect over body positions (postures,
    /// footholds, stability and collision checks, convex-hull foot paths) and report it.
    #[command(after_help = "Examples:
  tca plan rrt --robot hexapod --terrain hexapod-walls --png out/
  tca plan rrt --robot hexapod --terrain walls.asc --from 0.5,0 --to 4.5,0 --json
  tca plan rrt --robot hexapod --terrain hexapod-walls --seeds 1..10")]
    Rrt(RrtArgs),
}

#[derive(Debug, Args)]
pub(crate) struct RrtArgs {
    /// The robot: a shipped one (`tca robot list`) or a URDF file.
    #[arg(long, default_value = "hexapod")]
    robot: String,
    /// The terrain: a built-in course's name (`tca course list`) or an .asc file.
    #[arg(long)]
    terrain: String,
    /// Where the body starts, X,Y or X,Y,YAW (world metres, radians); a course's start by
    /// default.
    #[arg(long)]
    from: Option<String>,
    /// Where the body should end, X,Y; a course's goal by default.
    #[arg(long)]
    to: Option<String>,
    /// Seed of the planner's samples (and of a built-in course).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Plan once for each seed of FIRST..LAST and print a line each and the median time.
    #[arg(long)]
    seeds: Option<String>,
    /// The gait: tripod or wave.
    #[arg(long, default_value = "tripod")]
    gait: String,
    /// Iterations before "no path".
    #[arg(long)]
    iterations: Option<usize>,
    /// Write the trees and the path over the elevation map as DIR/rrt-SEED.png.
    #[arg(long, value_name = "DIR")]
    png: Option<PathBuf>,
    /// Print the plan as one JSON line.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(command: PlanCommand) -> anyhow::Result<ExitCode> {
    match command {
        PlanCommand::Rrt(args) => run_rrt(args),
    }
}

/// A built-in course's start pose (x, y, yaw) and goal (x, y).
type CourseEnds = ([f64; 3], [f64; 2]);

/// The terrain and, for a built-in course, its start and goal.
fn terrain_of(name: &str, seed: u64) -> anyhow::Result<(HeightField, Option<CourseEnds>)> {
    if let Ok(course) = Course::builtin(name, seed) {
        let s = course.start;
        return Ok((
            course.terrain,
            Some(([s.x_m, s.y_m, s.yaw_rad], [course.goal.x, course.goal.y])),
        ));
    }
    let path = PathBuf::from(name);
    if !path.exists() {
        anyhow::bail!(
            "--terrain {name:?} is neither a built-in course ({}) nor an existing .asc file",
            tca_legged_courses::NAMES.join(", ")
        );
    }
    let field = read_height_field(&path, NoData::Refuse)
        .with_context(|| format!("cannot read the terrain {}", path.display()))?;
    Ok((field, None))
}

fn run_rrt(args: RrtArgs) -> anyhow::Result<ExitCode> {
    let model = Arc::new(
        RobotModel::load(&args.robot)
            .map_err(|e| anyhow::anyhow!("--robot {}: {e}", args.robot))?,
    );
    let gait = Gait::from_name(&args.gait).map_err(|e| anyhow::anyhow!("--gait: {e}"))?;
    let seeds = match &args.seeds {
        Some(text) => parse_seeds(text)?,
        None => args.seed..=args.seed,
    };
    if let Some(dir) = &args.png {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the directory {}", dir.display()))?;
    }
    let campaign = args.seeds.is_some();
    let mut times = Vec::new();
    let mut planned = 0;
    let mut total = 0;
    for seed in seeds {
        total += 1;
        let (field, course) = terrain_of(&args.terrain, seed)?;
        let start = match (&args.from, course) {
            (Some(text), _) => {
                let v = parse_place("from", text, true)?;
                [v[0], v[1], v.get(2).copied().unwrap_or(0.0)]
            }
            (None, Some((s, _))) => s,
            (None, None) => anyhow::bail!("--from X,Y is needed with a terrain file"),
        };
        let goal = match (&args.to, course) {
            (Some(text), _) => {
                let v = parse_place("to", text, false)?;
                [v[0], v[1]]
            }
            (None, Some((_, g))) => g,
            (None, None) => anyhow::bail!("--to X,Y is needed with a terrain file"),
        };
        let mut params = RrtParams {
            seed,
            gait,
            ..RrtParams::default()
        };
        if let Some(k) = args.iterations {
            params.max_iterations = k;
        }
        let planner = Planner::new(model.clone(), Arc::new(field), params)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let result = planner.plan(
            Point2::new(start[0], start[1]),
            start[2],
            Point2::new(goal[0], goal[1]),
        );
        if let Some(dir) = &args.png {
            let path = dir.join(format!("rrt-{seed}.png"));
            write_plan_png(&path, planner.terrain(), result.as_ref().ok(), 100.0)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        let walls_course =
            args.terrain == "hexapod-walls" && args.from.is_none() && args.to.is_none();
        match &result {
            Ok(plan) => {
                planned += 1;
                times.push(plan.stats.time_s);
                let checks = walls_course.then(|| walls_checks(plan));
                if args.json {
                    println!("{}", plan_json(seed, plan, checks.as_ref()));
                } else {
                    println!(
                        "seed {seed}: path of {} postures, {:.2} m, {} nodes, {} iterations, {:.3} s; least margin {:.3} m{}",
                        plan.postures.len(),
                        plan.length_m(),
                        plan.stats.nodes,
                        plan.stats.iterations,
                        plan.stats.time_s,
                        plan.transitions
                            .iter()
                            .map(|t| t.min_margin_m)
                            .fold(f64::INFINITY, f64::min),
                        checks
                            .map(|c| format!("; {}", c.describe()))
                            .unwrap_or_default()
                    );
                }
            }
            Err(e) => {
                if args.json {
                    println!(
                        "{}",
                        json!({ "seed": seed, "planned": false, "reason": e.to_string() })
                    );
                } else {
                    println!("seed {seed}: no plan: {e}");
                }
            }
        }
    }
    if campaign && !args.json {
        times.sort_by(f64::total_cmp);
        let median = if times.is_empty() {
            f64::NAN
        } else {
            times[times.len() / 2]
        };
        println!("planned {planned} of {total}; median planning time {median:.3} s");
    }
    Ok(if planned == total {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}

fn walls_checks(plan: &Plan) -> WallsChecks {
    let path: Vec<[f64; 2]> = plan.postures.iter().map(|q| [q.body.x, q.body.y]).collect();
    WallsChecks::of_path(&path)
}

fn plan_json(seed: u64, plan: &Plan, checks: Option<&WallsChecks>) -> serde_json::Value {
    let postures: Vec<serde_json::Value> = plan
        .postures
        .iter()
        .map(|q| {
            json!({
                "body": q.body,
                "feet": q.feet.iter().map(|f| [f.x, f.y, f.z]).collect::<Vec<_>>(),
                "margin_m": q.margin_m,
            })
        })
        .collect();
    let mut v = json!({
        "seed": seed,
        "planned": true,
        "length_m": plan.length_m(),
        "postures": postures,
        "least_move_margin_m": plan.transitions.iter().map(|t| t.min_margin_m).fold(f64::INFINITY, f64::min),
        "postures_checked": plan.transitions.iter().map(|t| t.postures_checked).sum::<usize>(),
        "stats": plan.stats,
    });
    if let Some(c) = checks {
        v["walls"] = json!({
            "over_low_wall": c.over_low_wall,
            "over_high_wall": c.over_high_wall,
            "nearest_to_hill_m": c.nearest_to_hill_m,
        });
    }
    v
}

/// Parses `FIRST..LAST` (or one seed).
fn parse_seeds(text: &str) -> anyhow::Result<std::ops::RangeInclusive<u64>> {
    let bad = || {
        anyhow::anyhow!(
            "--seeds {text:?} is not a range of seeds; give FIRST..LAST, e.g. --seeds 1..10"
        )
    };
    let (a, b) = text.split_once("..").unwrap_or((text, text));
    let (a, b) = (
        a.trim().parse::<u64>().map_err(|_| bad())?,
        b.trim().parse::<u64>().map_err(|_| bad())?,
    );
    if a > b {
        return Err(bad());
    }
    Ok(a..=b)
}
