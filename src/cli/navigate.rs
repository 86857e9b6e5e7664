//! `tca navigate`: stereo-camera navigation on rough terrain toward a goal given relative
//! to the start, in simulation (depth camera, drifting odometry, the true terrain). By
//! default the Controller, ISM, LTM Manager and navigator run as modules on a central in
//! this process; `--direct` runs the same loop as one function (faster, for campaigns).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context as _, bail};
use clap::Args;
use serde_json::json;
use tca_nav_bus::{LeggedBase, NavBase, NavSetup, run_on_bus_with, run_with};
use tca_nav_hexapod::{HexapodBase, StepperParams, hexapod_params, legged_params};
use tca_nav_navigator::{
    Base, Course, DangerParams, NavParams, Pose2, RunOptions, RunReport, WheeledBase,
    WheeledParams, course_by_name, run, wheeled_params, write_picture,
};
use tca_robot::terrain::asc::{NoData, read_height_field};

#[derive(Debug, Args)]
pub(crate) struct NavigateArgs {
    /// The robot: `wheeled` (differential drive), `hexapod` (the shipped walking hexapod),
    /// or a walking robot's URDF file (a shipped robot's name works too). A walking robot
    /// walks the navigator's speeds with the free gait on the legged simulator, its camera
    /// on its body.
    #[arg(
        long,
        default_value = "wheeled",
        value_name = "wheeled|hexapod|FILE.urdf"
    )]
    robot: String,
    /// The terrain: an .asc file, or a built-in course (`ramps`, `hill`).
    #[arg(long)]
    terrain: String,
    /// Start pose X,Y[,YAW] in metres and radians (the built-in course's by default).
    #[arg(long, value_name = "X,Y[,YAW]", allow_hyphen_values = true)]
    start: Option<String>,
    /// Goal DX,DY: metres east and north of the start, negative for west or south (the
    /// built-in course's by default).
    #[arg(long, value_name = "DX,DY", allow_hyphen_values = true)]
    goal: Option<String>,
    /// Odometry drift, percent of the distance travelled.
    #[arg(long, default_value_t = 1.25)]
    drift: f64,
    /// Seed of the camera's and the odometry's noise.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Run this many seeds (seed, seed + 1, ...) and print a summary too.
    #[arg(long, default_value_t = 1)]
    seeds: u64,
    /// Weight of danger against length in D* Lite's edge cost, per cell (the robot's
    /// default is 2; the paper asks for more than 1). Lower follows the shortest way more
    /// closely, higher keeps further from dangerous and unknown ground.
    #[arg(long, value_name = "BETA", conflicts_with = "connect")]
    beta: Option<f64>,
    /// How far along the planned path the follower steers to, m (default 0.12). Longer
    /// cuts the grid path's corners more, and passes closer to what the path goes round.
    #[arg(long, value_name = "M", conflicts_with = "connect")]
    lookahead: Option<f64>,
    /// Line of sight, m: steer to the farthest path cell within this distance that a
    /// straight line reaches over ground no worse and no less known than the path's own
    /// (default 0.6; 0: off, follow the grid path).
    #[arg(long, value_name = "M", conflicts_with = "connect")]
    sight: Option<f64>,
    /// Clearance kept from untraversable cells when planning, m (default 0.06): a cell this
    /// close to one is planned as barely traversable, a margin for drift and tracking error.
    #[arg(long, value_name = "M", conflicts_with = "connect")]
    clearance: Option<f64>,
    /// Farthest depth-image point put into the terrain map, m (default 2.2): farther
    /// points see more of the way ahead but carry stereo's range noise, which grows with
    /// the square of the distance.
    #[arg(long, value_name = "M", conflicts_with = "connect")]
    map_range: Option<f64>,
    /// The depth camera's horizontal field of view, degrees (default 60).
    #[arg(long, value_name = "DEG", conflicts_with = "connect")]
    camera_fov: Option<f64>,
    /// The depth camera's image size in pixels, WIDTHxHEIGHT (default 160x120).
    #[arg(long, value_name = "WxH", conflicts_with = "connect")]
    camera_pixels: Option<String>,
    /// The depth camera's range noise factor k, 1/m: the depth's standard deviation is
    /// k z² (default 0.004).
    #[arg(long, value_name = "K", conflicts_with = "connect")]
    camera_noise: Option<f64>,
    /// Danger parameters file (TOML) instead of the robot's own.
    #[arg(long, conflicts_with = "connect")]
    danger: Option<PathBuf>,
    /// Frames before giving up.
    #[arg(long, default_value_t = 3000)]
    max_frames: usize,
    /// Write a picture of the perceived danger map with the planned, estimated and true
    /// paths to this PNG (with several seeds: one file per seed, `-SEED` before `.png`).
    #[arg(long)]
    picture: Option<PathBuf>,
    /// Write central's traffic log (MCAP) here: every depth image, map update, plan and
    /// drive command (with several seeds: one file per seed, `-SEED` before `.mcap`).
    /// `tca log export FILE --foxglove OUT.mcap` turns it into Foxglove's messages.
    #[arg(long, value_name = "FILE.mcap", conflicts_with = "direct")]
    log: Option<PathBuf>,
    /// Watch the run live in Foxglove: serve the Foxglove WebSocket protocol on
    /// `[HOST:]PORT` (loopback unless a host is given) from this process while it runs.
    #[arg(long, value_name = "[HOST:]PORT", conflicts_with = "direct")]
    foxglove: Option<String>,
    /// The LTM Matcher: register each frame against the map so far and correct the pose the
    /// frames are placed with and the navigator steers by (reported as `registrations`).
    #[arg(long)]
    matcher: bool,
    /// Navigate with the modules already running behind central at this endpoint (each its
    /// own process, `tca module nav-controller|nav-ism|nav-ltm|nav-navigator`, started with
    /// the same terrain, start, drift, seed and matcher; `tca up nav.toml` starts them all).
    #[arg(long, value_name = "ENDPOINT", conflicts_with_all = ["direct", "log", "foxglove"])]
    connect: Option<String>,
    /// Run the loop as one function instead of as modules on the bus (the same steps and
    /// report; no traffic, so no log).
    #[arg(long)]
    direct: bool,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// `path` with `-SEED` before its extension when several seeds run.
fn per_seed(path: &std::path::Path, seed: u64, several: bool, ext: &str) -> PathBuf {
    if several {
        let stem = path.with_extension("");
        PathBuf::from(format!("{}-{seed}.{ext}", stem.display()))
    } else {
        path.to_path_buf()
    }
}

fn numbers(text: &str, what: &str, min: usize, max: usize) -> anyhow::Result<Vec<f64>> {
    let v: Result<Vec<f64>, _> = text.split(',').map(|s| s.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if (min..=max).contains(&v.len()) && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => {
            bail!("--{what} `{text}` is not valid; give {min} to {max} numbers separated by commas")
        }
    }
}

fn course(args: &NavigateArgs) -> anyhow::Result<Course> {
    nav_course(&args.terrain, args.start.as_deref(), args.goal.as_deref())
}

/// The course of a navigation: a built-in one (`ramps`, `hill`) or an .asc file (then with
/// `start` and `goal`), its start and goal overridden by those given.
pub(crate) fn nav_course(
    terrain: &str,
    start: Option<&str>,
    goal: Option<&str>,
) -> anyhow::Result<Course> {
    let mut course = match course_by_name(terrain) {
        Some(c) => c.context("build the course")?,
        None => {
            let field = read_height_field(terrain, NoData::FillLowest).with_context(|| {
                format!("read the terrain {terrain} (give an .asc file or `ramps`/`hill`)")
            })?;
            let (Some(_), Some(_)) = (start, goal) else {
                bail!("--start and --goal are needed with a terrain file");
            };
            Course {
                name: "file",
                terrain: field,
                start: Pose2::default(),
                goal_offset: [0.0, 0.0],
            }
        }
    };
    if let Some(s) = start {
        let v = numbers(s, "start", 2, 3)?;
        course.start = Pose2::new(v[0], v[1], v.get(2).copied().unwrap_or(0.0));
    }
    if let Some(g) = goal {
        let v = numbers(g, "goal", 2, 2)?;
        course.goal_offset = [v[0], v[1]];
    }
    Ok(course)
}

/// The base `robot` names (`wheeled`, `hexapod`, another shipped walking robot or a URDF
/// file) and its navigation parameters, with another danger file and the LTM Matcher if
/// asked.
pub(crate) fn nav_robot(
    robot: &str,
    danger: Option<&std::path::Path>,
    matcher: bool,
) -> anyhow::Result<(NavBase, NavParams)> {
    let danger = danger.map(DangerParams::read).transpose()?;
    let (base, mut params) = match robot {
        "wheeled" => {
            let mut params = wheeled_params();
            if let Some(d) = danger {
                params.danger = d;
            }
            (NavBase::Wheeled(WheeledParams::PIONEER), params)
        }
        name => {
            let (model, urdf) = tca_legged_walk::walk::load_robot(name).with_context(|| {
                format!("--robot {name}: give wheeled, hexapod or a walking robot's URDF file")
            })?;
            let params = match danger {
                None if name == "hexapod" => hexapod_params(&model)?,
                danger => legged_params(&model, danger),
            };
            let stepper = StepperParams::for_model(&model);
            let base = LeggedBase {
                model: std::sync::Arc::new(model),
                urdf,
                stepper,
            };
            (NavBase::Legged(base), params)
        }
    };
    if matcher {
        params.matcher = Some(tca_nav_navigator::MatchParams::default());
    }
    Ok((base, params))
}

pub(crate) async fn run_navigate(args: NavigateArgs) -> anyhow::Result<ExitCode> {
    if !(args.drift.is_finite() && args.drift >= 0.0) {
        bail!(
            "--drift {} is not valid; give a percentage of at least 0",
            args.drift
        );
    }
    if args.seeds == 0 {
        bail!("--seeds must be at least 1");
    }
    let course = course(&args)?;
    let (base, mut params) = nav_robot(&args.robot, args.danger.as_deref(), args.matcher)?;
    if let Some(beta) = args.beta {
        if !(beta.is_finite() && beta >= 0.0) {
            bail!(
                "--beta {beta} is not valid; give a weight of at least 0 (more than 1 as the paper asks; the default is 2)"
            );
        }
        params.beta = beta;
    }
    if let Some(lookahead) = args.lookahead {
        if !(lookahead.is_finite() && lookahead > 0.0) {
            bail!(
                "--lookahead {lookahead} is not valid; give a distance in metres above 0 (the default is 0.12)"
            );
        }
        params.lookahead_m = lookahead;
    }
    if let Some(sight) = args.sight {
        if !(sight.is_finite() && sight >= 0.0) {
            bail!("--sight {sight} is not valid; give a distance in metres of at least 0 (0: off)");
        }
        params.sight_m = sight;
    }
    if let Some(range) = args.map_range {
        if !(range.is_finite() && range > 0.0) {
            bail!(
                "--map-range {range} is not valid; give a distance in metres above 0 (the default is 2.2)"
            );
        }
        params.map_range_m = range;
    }
    if let Some(fov) = args.camera_fov {
        params.camera.hfov_rad = fov.to_radians();
    }
    if let Some(pixels) = &args.camera_pixels {
        let parsed = pixels
            .split_once(['x', 'X'])
            .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)));
        let Some((width, height)) = parsed else {
            bail!("--camera-pixels {pixels} is not valid; give WIDTHxHEIGHT, e.g. 320x240");
        };
        params.camera.width = width;
        params.camera.height = height;
    }
    if let Some(k) = args.camera_noise {
        params.camera.noise_per_m = k;
    }
    if let Err(e) = params.camera.validate() {
        bail!(
            "the depth camera set by --camera-fov, --camera-pixels and --camera-noise is not valid: {e}"
        );
    }
    if let Some(clearance) = args.clearance {
        if !(clearance.is_finite() && clearance >= 0.0) {
            bail!(
                "--clearance {clearance} is not valid; give a distance in metres of at least 0 (the default is 0.06)"
            );
        }
        params.clearance_m = clearance;
    }
    let terrain = std::sync::Arc::new(course.terrain.clone());
    let attach = args
        .foxglove
        .as_deref()
        .map(super::foxglove::live_attachment)
        .transpose()?;
    let mut reports: Vec<RunReport> = Vec::new();
    for seed in args.seed..args.seed + args.seeds {
        let opts = RunOptions {
            start: course.start,
            goal_offset: course.goal_offset,
            drift: args.drift / 100.0,
            seed,
            max_frames: args.max_frames,
        };
        let several = args.seeds > 1;
        let (report, danger) = if args.direct {
            let mut driven: Box<dyn Base + '_> = match &base {
                NavBase::Wheeled(p) => {
                    Box::new(WheeledBase::new(*p, &course.terrain, course.start))
                }
                NavBase::Legged(l) => Box::new(
                    HexapodBase::new(
                        l.model.clone(),
                        terrain.clone(),
                        course.start,
                        l.stepper.clone(),
                    )
                    .map_err(|e| anyhow::anyhow!("--robot {}: {e}", args.robot))?,
                ),
            };
            let (report, nav) = run(&course.terrain, driven.as_mut(), params.clone(), &opts)?;
            (report, nav.danger().clone())
        } else {
            let setup = NavSetup {
                terrain: terrain.clone(),
                base: base.clone(),
                params: params.clone(),
                start: course.start,
                drift: opts.drift,
                seed,
            };
            let log = args
                .log
                .as_deref()
                .map(|l| per_seed(l, seed, several, "mcap"));
            if let Some(dir) = log.as_deref().and_then(std::path::Path::parent)
                && !dir.as_os_str().is_empty()
            {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("create the log's folder {}", dir.display()))?;
            }
            let run = match &args.connect {
                Some(endpoint) => {
                    let connector = tca_module::Connector::endpoint(endpoint.clone());
                    run_with(&connector, &setup, &opts, None).await?
                }
                None => run_on_bus_with(&setup, &opts, log, attach.as_ref()).await?,
            };
            (run.report, run.danger)
        };
        if let Some(pic) = &args.picture {
            let path = per_seed(pic, seed, several, "png");
            write_picture(&danger, &report, &path)
                .with_context(|| format!("write the picture {}", path.display()))?;
        }
        if !args.json {
            println!(
                "seed {seed}: {} ({}); travelled {:.2} m (true-map path {}), final error {:.3} m ({:.1} %), estimate error {:.3} m, {} replans, {} exploration turns, {} frames at {:.1} Hz, {} collisions, {} falls, {} frames in untraversable cells",
                if report.reached {
                    "reached"
                } else {
                    "NOT reached"
                },
                report.reason,
                report.distance_m,
                report
                    .true_map_path_m
                    .map_or("none".into(), |m| format!("{m:.2} m")),
                report.final_error_m,
                100.0 * report.final_error_m / report.distance_m.max(1e-9),
                report.estimate_error_m,
                report.replans,
                report.exploration_turns,
                report.frames,
                report.loop_hz,
                report.collisions,
                report.falls,
                report.untraversable_frames,
            );
        }
        reports.push(report);
    }
    let ok = reports.iter().filter(|r| r.meets_acceptance()).count();
    if args.json {
        let value = if reports.len() == 1 {
            serde_json::to_value(&reports[0])?
        } else {
            json!({ "runs": reports, "accepted": ok, "of": reports.len() })
        };
        println!("{}", serde_json::to_string(&value)?);
    } else if reports.len() > 1 {
        println!(
            "{}: {ok} of {} runs reached with final error <= 3 % of the distance, path <= 1.25 x the true-map path, no collision, fall or untraversable cell",
            course.name,
            reports.len()
        );
    }
    Ok(if reports.iter().all(|r| r.reached) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
