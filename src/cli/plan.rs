//! `tca plan rrt`: the integrated RRT-Connect motion planner for a multi-legged robot,
//! planning without walking; `tca plan cgspace`: the CG-space route and footfall planner.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use serde_json::json;
use tca_cg_space::{
    CgError, CgParams, CgRobot, CgSpace, FootStep, Layout, PictureOptions, PlanParams,
    write_cg_space_png,
};
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
    /// Plan a route for the centre of gravity through CG-space and the footfalls along it
    /// (after Eldershaw and Yim): report the route, the foot moves and the work done, and
    /// optionally draw the footmap, the invalid CG cells, the route and the footfalls.
    #[command(after_help = "Examples:
  tca plan cgspace --robot ambler --terrain cliff --png out/
  tca plan cgspace --robot ambler --terrain cliff --theta 0 --json
  tca plan cgspace --robot spider --terrain flat --from 4,0 --to 12,0
  tca plan cgspace --robot ambler --terrain walled-goal        # no route: exit status 2
  tca plan cgspace --robot robot.urdf --terrain field.asc --from 2,2 --to 20,5,1.57 --seeds 1..5
  tca plan cgspace --robot ambler --terrain cliff --workers 3      # the route's joins on 3 worker processes
  tca plan cgspace --robot ambler --terrain cliff --workers 3 --route-only   # the route alone

The picture (DIR/cgspace-SEED.png) shows the elevation in grey, foot cells without traction
as red circles, invalid CG cells in black (--theta all: black where every heading is
invalid, dark grey where some are), the route in blue, footfalls as yellow crosses and the
start and goal in green. Exit status 2 when some seed found no plan.")]
    Cgspace(CgSpaceArgs),
}

#[derive(Debug, Args)]
pub(crate) struct CgSpaceArgs {
    /// The robot: a shipped one (ambler, hexapod, athlete, spider, polybot6, polybot8; see
    /// `tca robot list`) or a URDF file.
    #[arg(long)]
    robot: String,
    /// The terrain: a built-in course's name (`tca course list`) or an .asc file.
    #[arg(long)]
    terrain: String,
    /// Where the centre of gravity starts, X,Y or X,Y,HEADING (world metres, radians); a
    /// course's start by default.
    #[arg(long)]
    from: Option<String>,
    /// Where it should end, X,Y or X,Y,HEADING; a course's goal by default (the heading
    /// defaults to the start's).
    #[arg(long)]
    to: Option<String>,
    /// Seed of the roadmap's random points (and of a built-in course).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Plan once for each seed of FIRST..LAST and print a line each and the median time.
    #[arg(long)]
    seeds: Option<String>,
    /// Draw the CG-space and the plan as DIR/cgspace-SEED.png.
    #[arg(long, value_name = "DIR")]
    png: Option<PathBuf>,
    /// The heading bin whose invalid CG cells the picture shows, or `all`.
    #[arg(long, default_value = "all", value_name = "all|BIN")]
    theta: String,
    /// Print each plan as one JSON line.
    #[arg(long)]
    json: bool,
    /// The route's roadmap joins on N worker processes (`tca module cgspace-worker`, started
    /// and stopped by this command), each owning a strip of CG-space under a region cap; the
    /// footfalls are searched here, and every route replanned after the search marked a
    /// cell is planned on the workers again, the marked cells sent with each batch.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=256), conflicts_with = "seeds")]
    workers: Option<u32>,
    /// With --workers: plan the route alone, without the footfalls (what the distributed
    /// benchmark times).
    #[arg(long, requires = "workers")]
    route_only: bool,
    /// With --workers: the central the planner and the workers join (default: one started
    /// in this process on a free loopback port).
    #[arg(long, value_name = "ENDPOINT", requires = "workers")]
    connect: Option<String>,
    /// With --workers: most CG-space regions each worker holds (default: as many as its
    /// strip's searches can touch).
    #[arg(long, value_name = "N", requires = "workers")]
    region_cap: Option<usize>,
    /// With --workers and --connect: use the workers already connected to that central
    /// (`tca module cgspace-worker --index K ...`, one per index, with this robot, terrain
    /// and seed; on any machine) instead of starting them; one that dies must be started
    /// again from outside within 30 s.
    #[arg(long, requires = "connect")]
    external_workers: bool,
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
        PlanCommand::Cgspace(args) => match args.workers {
            Some(n) => run_cgspace_workers(args, n as usize).await,
            None => run_cgspace(args),
        },
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

/// Parses `--theta`: `all` (every heading) or a heading bin.
fn parse_theta(text: &str) -> anyhow::Result<Option<u16>> {
    if text.trim().eq_ignore_ascii_case("all") {
        return Ok(None);
    }
    text.trim().parse::<u16>().map(Some).map_err(|_| {
        anyhow::anyhow!(
            "--theta {text:?} is neither `all` nor a heading bin number; give e.g. --theta 0"
        )
    })
}

/// Refuses a place outside the CG-space's map, naming the option.
fn check_inside(
    option: &str,
    what: &'static str,
    grid: &tca_cg_space::CgGrid,
    p: Point2<f64>,
) -> anyhow::Result<()> {
    if grid.cell_of(p, 0.0).is_some() {
        return Ok(());
    }
    let e = CgError::OutsideMap {
        what,
        x: p.x,
        y: p.y,
        x_min: grid.origin.x,
        x_max: grid.origin.x + f64::from(grid.nx) * grid.cell_m,
        y_min: grid.origin.y,
        y_max: grid.origin.y + f64::from(grid.ny) * grid.cell_m,
    };
    anyhow::bail!("--{option} {},{}: {e}", p.x, p.y)
}

fn run_cgspace(args: CgSpaceArgs) -> anyhow::Result<ExitCode> {
    let model = RobotModel::load(&args.robot)
        .map_err(|e| anyhow::anyhow!("--robot {}: {e}", args.robot))?;
    let theta = parse_theta(&args.theta)?;
    let seeds = match &args.seeds {
        Some(text) => parse_seeds(text)?,
        None => args.seed..=args.seed,
    };
    let from = args
        .from
        .as_deref()
        .map(|t| parse_place("from", t, true))
        .transpose()?;
    let to = args
        .to
        .as_deref()
        .map(|t| parse_place("to", t, true))
        .transpose()?;
    if let Some(dir) = &args.png {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the directory {}", dir.display()))?;
    }
    let campaign = args.seeds.is_some();
    // The robot's tables depend on the terrain's resolution only: built once per resolution.
    let mut robot: Option<(f64, Arc<CgRobot>)> = None;
    let mut times = Vec::new();
    let (mut planned, mut total) = (0, 0);
    for seed in seeds {
        total += 1;
        let (field, course) = terrain_of(&args.terrain, seed)?;
        let start = match (&from, course) {
            (Some(v), _) => [v[0], v[1], v.get(2).copied().unwrap_or(0.0)],
            (None, Some((s, _))) => s,
            (None, None) => anyhow::bail!("--from X,Y is needed with a terrain file"),
        };
        let goal = match (&to, course) {
            (Some(v), _) => [v[0], v[1], v.get(2).copied().unwrap_or(start[2])],
            (None, Some((_, g))) => [g[0], g[1], start[2]],
            (None, None) => anyhow::bail!("--to X,Y is needed with a terrain file"),
        };
        let built = Instant::now();
        let res = field.grid().resolution_m();
        let tables = match &robot {
            Some((r, t)) if *r == res => t.clone(),
            _ => {
                let t = Arc::new(
                    CgRobot::new(&model, res, CgParams::default())
                        .map_err(|e| anyhow::anyhow!("--robot {}: {e}", args.robot))?,
                );
                robot = Some((res, t.clone()));
                t
            }
        };
        let mut space = CgSpace::new(tables.clone(), &field)
            .map_err(|e| anyhow::anyhow!("--terrain {}: {e}", args.terrain))?;
        let space_s = built.elapsed().as_secs_f64();
        let grid = *space.grid();
        check_inside("from", "the start", &grid, Point2::new(start[0], start[1]))?;
        check_inside("to", "the goal", &grid, Point2::new(goal[0], goal[1]))?;
        let picture = PictureOptions {
            theta,
            start: Some(Point2::new(start[0], start[1])),
            goal: Some(Point2::new(goal[0], goal[1])),
            label: Some(format!("{} {} seed {seed}", args.robot, args.terrain)),
            ..PictureOptions::default()
        };
        Layout::new(&grid, &picture).map_err(|e| anyhow::anyhow!("--theta {}: {e}", args.theta))?;
        let mut params = PlanParams::default();
        params.route.seed = seed;
        let began = Instant::now();
        let result = tca_cg_space::plan(
            &mut space,
            (Point2::new(start[0], start[1]), start[2]),
            (Point2::new(goal[0], goal[1]), goal[2]),
            None,
            &params,
        );
        let time_s = began.elapsed().as_secs_f64();
        let work = CgWork {
            evaluated: space.evaluations(),
            regions: space.regions_materialised(),
            time_s,
            space_s,
        };
        match &result {
            Ok(plan) => {
                planned += 1;
                times.push(time_s);
                if args.json {
                    println!("{}", cg_plan_json(seed, &space, plan, &work));
                } else {
                    println!(
                        "seed {seed}: {}; {} CG cells evaluated in {} regions; planned in {:.3} s (CG-space built in {:.3} s)",
                        plan_summary(&grid, plan),
                        work.evaluated,
                        work.regions,
                        work.time_s,
                        work.space_s,
                    );
                }
            }
            Err(e) => {
                let unreachable = matches!(e, CgError::Unreachable { .. });
                if args.json {
                    println!(
                        "{}",
                        json!({
                            "seed": seed,
                            "planned": false,
                            "unreachable": unreachable,
                            "reason": e.to_string(),
                            "cg_cells_evaluated": work.evaluated,
                            "regions_materialised": work.regions,
                            "time_s": work.time_s,
                        })
                    );
                } else {
                    let what = if e.to_string().starts_with("no route") {
                        String::new()
                    } else {
                        "no plan: ".to_owned()
                    };
                    println!(
                        "seed {seed}: {what}{e} ({} CG cells evaluated in {} regions, {:.3} s)",
                        work.evaluated, work.regions, work.time_s
                    );
                }
            }
        }
        if let Some(dir) = &args.png {
            let path = dir.join(format!("cgspace-{seed}.png"));
            write_cg_space_png(&path, &mut space, &picture, result.as_ref().ok())
                .with_context(|| format!("cannot write {}", path.display()))?;
            if !args.json {
                println!("seed {seed}: picture {}", path.display());
            }
        }
    }
    if campaign && !args.json {
        times.sort_by(f64::total_cmp);
        match times.get(times.len() / 2) {
            Some(median) => println!(
                "planned {planned} of {total}; median planning time of the plans {median:.3} s"
            ),
            None => println!("planned 0 of {total}"),
        }
    }
    Ok(if planned == total {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}

/// `tca plan cgspace --workers N`: the route alone, its joins on N worker processes of this
/// same binary.
async fn run_cgspace_workers(args: CgSpaceArgs, workers: usize) -> anyhow::Result<ExitCode> {
    use tca_cg_space_bus::{DistributedJoiner, ExternalWorkers, JoinerOptions, ProcessWorkers};
    let model = RobotModel::load(&args.robot)
        .map_err(|e| anyhow::anyhow!("--robot {}: {e}", args.robot))?;
    let seed = args.seed;
    let (field, course) = terrain_of(&args.terrain, seed)?;
    let place = |option: &str, text: &Option<String>| {
        text.as_deref()
            .map(|t| parse_place(option, t, true))
            .transpose()
    };
    let start = match (place("from", &args.from)?, course) {
        (Some(v), _) => [v[0], v[1], v.get(2).copied().unwrap_or(0.0)],
        (None, Some((s, _))) => s,
        (None, None) => anyhow::bail!("--from X,Y is needed with a terrain file"),
    };
    let goal = match (place("to", &args.to)?, course) {
        (Some(v), _) => [v[0], v[1], v.get(2).copied().unwrap_or(start[2])],
        (None, Some((_, g))) => [g[0], g[1], start[2]],
        (None, None) => anyhow::bail!("--to X,Y is needed with a terrain file"),
    };
    let built = Instant::now();
    let space = CgSpace::for_model(&model, &field, CgParams::default()).map_err(|e| {
        anyhow::anyhow!("--robot {} on --terrain {}: {e}", args.robot, args.terrain)
    })?;
    let space_s = built.elapsed().as_secs_f64();
    let grid = *space.grid();
    check_inside("from", "the start", &grid, Point2::new(start[0], start[1]))?;
    check_inside("to", "the goal", &grid, Point2::new(goal[0], goal[1]))?;
    let cell = |p: [f64; 3]| grid.cell_of(Point2::new(p[0], p[1]), p[2]);
    let (Some(s), Some(g)) = (cell(start), cell(goal)) else {
        anyhow::bail!("the start or the goal is outside the map");
    };
    let route_params = tca_cg_space::RouteParams {
        seed,
        ..tca_cg_space::RouteParams::default()
    };
    let partition = tca_cg_space::Partition::new(&grid, workers)
        .map_err(|e| anyhow::anyhow!("--workers {workers}: {e}"))?;
    let cap = args.region_cap.unwrap_or_else(|| {
        (0..workers)
            .map(|k| partition.regions_in_reach(k, &route_params))
            .max()
            .unwrap_or(1)
    });
    // Central: the one given, or one in this process the worker processes can reach.
    let (central, endpoint, connector) = match &args.connect {
        Some(e) => (None, e.clone(), tca_module::Connector::endpoint(e.clone())),
        None => {
            let e = tca_link::net::free_loopback_endpoint()
                .context("no free loopback port for the workers' central")?;
            let c = tca_central::start(tca_central::StartOptions {
                listen: vec![e.clone()],
                ..tca_central::StartOptions::default()
            })
            .await
            .with_context(|| format!("cannot start central on {e}"))?;
            let connector = tca_module::Connector::from(c.in_process());
            (Some(c), e, connector)
        }
    };
    let planner = tca_module::Module::builder(format!("cgspace-planner-{}", std::process::id()))
        .connect(&connector)
        .await
        .with_context(|| format!("the planner cannot join central at {endpoint}"))?;
    let exe = std::env::current_exe().context("cannot find this program to start the workers")?;
    let worker_args: Vec<String> = [
        "module",
        "cgspace-worker",
        "--connect",
        &endpoint,
        "--robot",
        &args.robot,
        "--terrain",
        &args.terrain,
        "--seed",
        &seed.to_string(),
        "--region-cap",
        &cap.to_string(),
    ]
    .iter()
    .map(|a| (*a).to_owned())
    .collect();
    let options = JoinerOptions::default();
    let joiner = if args.external_workers {
        DistributedJoiner::start(planner, workers, ExternalWorkers, options).await
    } else {
        let factory = ProcessWorkers::new(exe, worker_args);
        DistributedJoiner::start(planner, workers, factory, options).await
    };
    let mut joiner = joiner.map_err(|e| anyhow::anyhow!("--workers {workers}: {e}"))?;
    let began = Instant::now();
    let route_only = args.route_only;
    let (result, joiner, space) = tokio::task::spawn_blocking(move || {
        let mut space = space;
        let batch = tca_cg_space::BatchParams::default();
        let result = if route_only {
            tca_cg_space::plan_route_batched(&mut space, &mut joiner, s, g, &route_params, &batch)
                .map(Planned::Route)
                .map_err(|e| e.to_string())
        } else {
            let params = PlanParams {
                route: route_params,
                ..PlanParams::default()
            };
            let mut routes = tca_cg_space::JoinedRoutes { joiner, batch };
            let r = tca_cg_space::plan_with(
                &mut space,
                (Point2::new(start[0], start[1]), start[2]),
                (Point2::new(goal[0], goal[1]), goal[2]),
                None,
                &params,
                None,
                &mut routes,
            );
            joiner = routes.joiner;
            r.map(|p| Planned::Footfalls(Box::new(p)))
                .map_err(|e| e.to_string())
        };
        (result, joiner, space)
    })
    .await
    .context("the planning thread stopped")?;
    let time_s = began.elapsed().as_secs_f64();
    let stats = joiner.shutdown().await;
    if let Some(c) = central {
        let _ = c.shutdown().await;
    }
    // The caps the workers report (external workers have their own).
    let mut caps: Vec<u64> = stats.workers.iter().map(|w| w.region_cap).collect();
    caps.dedup();
    let caps = caps
        .iter()
        .map(|c| {
            if *c == 0 {
                "none".to_owned()
            } else {
                c.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("/");
    let per_worker = stats
        .queries_per_worker
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join("/");
    let workers_json = json!({
        "workers": workers, "region_cap": caps, "batches": stats.batches,
        "joins_per_worker": stats.queries_per_worker,
        "replacements": stats.replacements,
        "worker_cells_evaluated": stats.cells_evaluated(),
        "worker_regions_materialised": stats.regions_materialised(),
        "planner_cells_evaluated": space.evaluations(),
    });
    let on_workers = format!(
        "{} batches of joins on {workers} workers ({per_worker} joins), {} workers replaced; the workers evaluated {} CG cells in {} regions (cap {caps} each), the planner {}",
        stats.batches,
        stats.replacements,
        stats.cells_evaluated(),
        stats.regions_materialised(),
        space.evaluations(),
    );
    let planned = match &result {
        Ok(Planned::Route(route)) => {
            let length = route_length_m(&grid, &route.cells);
            if args.json {
                let cells: Vec<[f64; 3]> = route
                    .cells
                    .iter()
                    .map(|c| {
                        let p = grid.centre(c.ix, c.iy);
                        [p.x, p.y, grid.theta(c.it)]
                    })
                    .collect();
                let mut v = json!({
                    "seed": seed, "planned": true, "route_only": true,
                    "route_cells": route.cells.len(), "route_length_m": length,
                    "draws": route.draws, "joins": route.searches,
                    "time_s": time_s, "route": cells,
                });
                merge(&mut v, &workers_json);
                println!("{v}");
            } else {
                println!(
                    "seed {seed}: route of {} cells, {length:.2} m; {} draws, {} joins; {on_workers}; planned in {time_s:.3} s",
                    route.cells.len(),
                    route.draws,
                    route.searches,
                );
            }
            true
        }
        Ok(Planned::Footfalls(plan)) => {
            let work = CgWork {
                evaluated: space.evaluations(),
                regions: space.regions_materialised(),
                time_s,
                space_s,
            };
            if args.json {
                let mut v = cg_plan_json(seed, &space, plan, &work);
                merge(&mut v, &workers_json);
                v["joins"] = json!(stats.queries);
                println!("{v}");
            } else {
                println!(
                    "seed {seed}: {}; {on_workers}; planned in {time_s:.3} s",
                    plan_summary(&grid, plan),
                );
            }
            true
        }
        Err(e) => {
            if args.json {
                println!(
                    "{}",
                    json!({ "seed": seed, "planned": false, "workers": workers, "reason": e, "replacements": stats.replacements, "time_s": time_s })
                );
            } else {
                let what = if e.starts_with("no route") {
                    ""
                } else {
                    "no plan: "
                };
                println!("seed {seed}: {what}{e}");
            }
            false
        }
    };
    if let Some(dir) = &args.png {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the directory {}", dir.display()))?;
        let path = dir.join(format!("cgspace-{seed}.png"));
        let picture = PictureOptions {
            theta: parse_theta(&args.theta)?,
            start: Some(Point2::new(start[0], start[1])),
            goal: Some(Point2::new(goal[0], goal[1])),
            label: Some(format!(
                "{} {} seed {seed}, {workers} workers",
                args.robot, args.terrain
            )),
            ..PictureOptions::default()
        };
        let mut space = space;
        let plan = match &result {
            Ok(Planned::Footfalls(p)) => Some(p.as_ref()),
            _ => None,
        };
        write_cg_space_png(&path, &mut space, &picture, plan)
            .with_context(|| format!("cannot write {}", path.display()))?;
        if !args.json {
            println!("seed {seed}: picture {}", path.display());
        }
    }
    Ok(if planned {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}

/// What `tca plan cgspace --workers` planned.
enum Planned {
    /// The route alone (`--route-only`).
    Route(tca_cg_space::Route),
    /// The route and its footfalls.
    Footfalls(Box<tca_cg_space::Plan>),
}

/// Copies `extra`'s fields into the JSON object `into`.
fn merge(into: &mut serde_json::Value, extra: &serde_json::Value) {
    if let (Some(into), Some(extra)) = (into.as_object_mut(), extra.as_object()) {
        for (k, v) in extra {
            into.insert(k.clone(), v.clone());
        }
    }
}

/// The CG-space's work for one plan.
struct CgWork {
    evaluated: u64,
    regions: u64,
    time_s: f64,
    space_s: f64,
}

/// The route's length over the ground: its cells' centres joined, metres.
fn route_length_m(grid: &tca_cg_space::CgGrid, route: &[tca_cg_space::CgCell]) -> f64 {
    route
        .windows(2)
        .map(|w| (grid.centre(w[1].ix, w[1].iy) - grid.centre(w[0].ix, w[0].iy)).norm())
        .sum()
}

/// A plan in a line: its route, foot moves, search nodes, routes planned and cells marked.
fn plan_summary(grid: &tca_cg_space::CgGrid, plan: &tca_cg_space::Plan) -> String {
    format!(
        "route of {} cells, {:.2} m; {} foot moves, {} search nodes, {} routes planned, {} cells marked",
        plan.feet.route.len(),
        route_length_m(grid, &plan.feet.route),
        plan.feet.foot_moves(),
        plan.feet.nodes,
        plan.routes,
        plan.marked.len(),
    )
}

fn cg_plan_json(
    seed: u64,
    space: &CgSpace,
    plan: &tca_cg_space::Plan,
    work: &CgWork,
) -> serde_json::Value {
    let grid = space.grid();
    let legs = &space.robot().leg_names;
    let at = |f: (i32, i32)| {
        let p = grid.centre(f.0, f.1);
        [p.x, p.y]
    };
    let route: Vec<[f64; 3]> = plan
        .feet
        .route
        .iter()
        .map(|c| {
            let p = grid.centre(c.ix, c.iy);
            [p.x, p.y, grid.theta(c.it)]
        })
        .collect();
    let footfalls: Vec<serde_json::Value> = plan
        .feet
        .steps
        .iter()
        .filter_map(|s| match *s {
            FootStep::Place { leg, to, .. } => {
                let [x, y] = at(to);
                Some(json!({ "leg": legs.get(leg), "x": x, "y": y }))
            }
            _ => None,
        })
        .collect();
    let stances: Vec<Vec<Option<[f64; 2]>>> = tca_cg_space::stances(plan)
        .iter()
        .map(|s| s.feet.iter().map(|f| f.map(at)).collect())
        .collect();
    json!({
        "seed": seed,
        "planned": true,
        "route_cells": plan.feet.route.len(),
        "route_length_m": route_length_m(grid, &plan.feet.route),
        "foot_moves": plan.feet.foot_moves(),
        "search_nodes": plan.feet.nodes,
        "routes_planned": plan.routes,
        "cells_marked": plan.marked.len(),
        "cg_cells_evaluated": work.evaluated,
        "regions_materialised": work.regions,
        "time_s": work.time_s,
        "space_s": work.space_s,
        "cell_m": grid.cell_m,
        "theta_bins": grid.theta_bins,
        "legs": legs,
        "route": route,
        "footfalls": footfalls,
        "stances": stances,
    })
}
