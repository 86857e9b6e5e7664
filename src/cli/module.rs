//! `tca module NAME`: one built-in module as its own process.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_module::Connector;

use super::ConnectArgs;

/// Names of the built-in modules: the echo of `tca ping`, the six walking modules of the
/// single leg, the four of a multi-legged robot and the CG-space route planner's worker.
pub(crate) const BUILTIN_MODULES: &[&str] = &[
    "echo",
    "controller",
    "ism",
    "ltm",
    "pdm",
    "lrp",
    "gait",
    "legged-controller",
    "legged-ism",
    "legged-ltm",
    "legged-gait",
    "legged-telemetry",
    "cgspace-worker",
    "nav-controller",
    "nav-legged-controller",
    "nav-ism",
    "nav-ltm",
    "nav-navigator",
    "footfall-planner",
    "footfall-exec",
];

#[derive(Debug, Args)]
pub(crate) struct ModuleArgs {
    /// The built-in module to run: echo; the single leg's controller, ism, ltm, pdm, lrp or
    /// gait; a multi-legged robot's legged-controller, legged-ism, legged-ltm or
    /// legged-gait (with --robot); legged-telemetry, the ground side's telemetry monitor
    /// (with --record FILE.jsonl to keep it); cgspace-worker (with --index, --robot and --terrain or
    /// --course), one worker of the distributed CG-space route planner; the navigation
    /// modules nav-controller, nav-ism, nav-ltm or nav-navigator, and for a walking base
    /// nav-legged-controller (with --course ramps|hill or --terrain FILE.asc, and --robot,
    /// --start, --drift, --seed, --matcher as `tca navigate`); FootFall's footfall-planner
    /// (ground side, with the terrain: --course, default rock-field, or --terrain FILE.asc)
    /// and footfall-exec (robot side).
    name: String,
    #[command(flatten)]
    connect: ConnectArgs,
    /// The terrain of the walking modules: for the single leg course 1, 2, 3 (the default),
    /// 4 or random (from --seed); for the legged modules one of `tca course list` (default:
    /// the robot's own scale's rough ground).
    #[arg(long, conflicts_with = "terrain")]
    course: Option<String>,
    /// The robot of the legged modules: a shipped one (ambler, hexapod, athlete) or a URDF
    /// file. Give every legged module, and `tca walk --robot ... --connect`, the same robot,
    /// course or terrain, start and seed.
    #[arg(long, value_name = "NAME|FILE.urdf")]
    robot: Option<String>,
    /// Where the legged robot's body starts, X,Y[,YAW] in world metres and radians (default:
    /// the course's start, or near a terrain file's west edge).
    #[arg(long, value_name = "X,Y[,YAW]", allow_negative_numbers = true)]
    start: Option<String>,
    /// legged-gait plans on the true terrain instead of the LTM Manager's maps.
    #[arg(long)]
    ground_truth: bool,
    /// legged-controller: the simulated robot sags under load when a leg lifts (the
    /// compliance of the shipped athlete: 12 kN/m per leg, 2e-5 rad per N m at the joints).
    #[arg(long)]
    sag: bool,
    /// legged-controller injects a hardware fault: from simulated time SECONDS on, leg
    /// LEG's drives stop responding (repeat for several legs).
    #[arg(long, value_name = "LEG@SECONDS")]
    fault: Vec<String>,
    /// What legged-gait plans with: `free` (the free gait) or `rrt` (RRT-Connect over the
    /// whole terrain).
    #[arg(long, value_name = "free|rrt", default_value = "free")]
    planner: String,
    /// With --planner rrt: `tripod` (default) or `wave`.
    #[arg(long, value_name = "tripod|wave")]
    gait: Option<String>,
    /// The terrain from an ESRI ASCII grid (.asc) file instead (cgspace-worker: a built-in
    /// course's name or an .asc file).
    #[arg(long, value_name = "FILE.asc")]
    terrain: Option<std::path::PathBuf>,
    /// cgspace-worker: which worker this is, 0 to N-1 for a planner with N workers (it
    /// answers the joins of strip K of CG-space, as module cgspace-worker-K).
    #[arg(long, value_name = "K")]
    index: Option<usize>,
    /// cgspace-worker: most CG-space regions (16 x 16 cells, every heading) held at once;
    /// beyond it the least recently used is dropped and recomputed when needed again.
    #[arg(long, value_name = "N")]
    region_cap: Option<usize>,
    /// cgspace-worker: the planner's CG-space layout as JSON (the fields of
    /// `tca_cg_space::CgParams`; default: the paper's). A walk's planner (`tca walk --planner
    /// cgspace --workers N`) gives its own, which differs in heading bins and margins.
    #[arg(long, value_name = "JSON")]
    cg_params: Option<String>,
    /// Navigation modules: odometry drift, percent of the distance travelled.
    #[arg(long, default_value_t = 1.25)]
    drift: f64,
    /// Navigation modules: the LTM Matcher is on (give nav-ltm and nav-navigator the same).
    #[arg(long)]
    matcher: bool,
    /// legged-controller publishes legged.telemetry (joint angles, body pose, foot forces)
    /// this many times a second, on a central on wall-clock time.
    #[arg(long, value_name = "HZ")]
    telemetry: Option<f64>,
    /// legged-telemetry writes everything it receives to this file, a JSON object a line.
    #[arg(long, value_name = "FILE.jsonl")]
    record: Option<std::path::PathBuf>,
    /// Seed of the random course and of the scanner noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Directory for pictures (the PDM's output; the planners' step pictures).
    #[arg(long, value_name = "DIR")]
    out: Option<std::path::PathBuf>,
    /// Write the planners' per-step pictures.
    #[arg(long)]
    pictures: bool,
    /// What the planners' computing costs in simulated time: "paper" (the 1990 system's
    /// times) or "measured".
    #[arg(long, value_enum, default_value_t = super::Compute::Paper)]
    compute: super::Compute,
    /// The Controller simulator's speed: simulated time runs FACTOR times faster than the
    /// wall clock (1 = real time, as the 1990 testbed). Default: as fast as it computes.
    /// legged-controller then carries out moves on the wall clock, FACTOR times faster than
    /// the robot (on a central on wall-clock time).
    #[arg(long, value_name = "FACTOR")]
    speed: Option<f64>,
    /// Keep what must survive a restart of this module in DIR: the Controller's leg and
    /// carriage state (and the outcomes of its latest commands, so a redelivered command is
    /// not carried out twice), the LTM Manager's map tiles. Start the module again with the
    /// same DIR after a crash and it goes on where it was.
    #[arg(long, value_name = "DIR")]
    state: Option<std::path::PathBuf>,
    /// A rigid leg: the Controller simulates no deflection and the planners compensate none.
    /// Give every walking module of a system the same choice.
    #[arg(long)]
    rigid: bool,
    /// How the Controller propels the carriage: `servo` (default) or `open-loop` (the
    /// report's first, inaccurate procedure; see `tca walk --help`).
    #[arg(long, value_name = "LAW", default_value = "servo")]
    body_move: tca_controller_sim::sim::BodyMoveLaw,
}

pub(crate) async fn run(args: ModuleArgs) -> anyhow::Result<ExitCode> {
    let endpoint = args
        .connect
        .connect
        .clone()
        .or_else(|| std::env::var("TCA_CONNECT").ok())
        .unwrap_or_else(|| args.connect.endpoint_or_default());
    let connector = Connector::endpoint(endpoint.clone());
    if args.name == "cgspace-worker" {
        return run_cgspace_worker(&args, &connector, &endpoint).await;
    }
    if let Some(inner) = args.name.strip_prefix("nav-") {
        return run_nav_module(&args, inner, &connector, &endpoint).await;
    }
    if args.name.starts_with("footfall-") {
        return run_footfall_module(&args, &connector, &endpoint).await;
    }
    if args.index.is_some() || args.region_cap.is_some() || args.cg_params.is_some() {
        anyhow::bail!(
            "--index, --region-cap and --cg-params are for the CG-space worker (tca module cgspace-worker), not {}",
            args.name
        );
    }
    if args.name == "legged-telemetry" {
        let (module, _feed) = tca_legged_ground::connect_monitor(
            &connector,
            tca_legged_ground::MonitorOptions {
                record: args.record.clone(),
                ..Default::default()
            },
        )
        .await
        .with_context(|| format!("module {} cannot join central at {endpoint}", args.name))?;
        return serve(module, &args.name, &endpoint).await;
    }
    if args.record.is_some() {
        anyhow::bail!("--record is for legged-telemetry, not {}", args.name);
    }
    if args.telemetry.is_some() && args.name != "legged-controller" {
        anyhow::bail!("--telemetry is for legged-controller, not {}", args.name);
    }
    if args.name == "legged-controller" && (args.telemetry.is_some() || args.speed.is_some()) {
        return run_live_controller(&args, &connector, &endpoint).await;
    }
    if let Some(inner) = args.name.strip_prefix("legged-") {
        let Some(robot) = &args.robot else {
            anyhow::bail!(
                "module {} is a multi-legged robot's: give its robot with --robot NAME|FILE.urdf",
                args.name
            );
        };
        let options = legged_options(&args, robot)?;
        let module = tca_legged_walk::walk::connect_module_for(inner, &connector, &options)
            .await
            .with_context(|| format!("module {} cannot join central at {endpoint}", args.name))?;
        return serve(module, &args.name, &endpoint).await;
    }
    if args.robot.is_some() || args.start.is_some() || args.ground_truth || !args.fault.is_empty() {
        anyhow::bail!(
            "--robot, --start, --ground-truth and --fault are for the legged modules (legged-controller, legged-ism, legged-ltm, legged-gait), not {}",
            args.name
        );
    }
    let course = args.course.as_deref().unwrap_or("3");
    let terrain = tca_walk::TerrainChoice::from_args(course, args.terrain.as_deref(), args.seed)?;
    let options = tca_walk::ModuleOptions {
        terrain,
        seed: args.seed,
        out: args.out.clone(),
        pictures: args.pictures,
        compute: args.compute.into(),
        speed: match args.speed {
            Some(f) => tca_controller_sim::SpeedFactor::Times(f),
            None => tca_controller_sim::SpeedFactor::AsFastAsPossible,
        },
        state_dir: args.state.clone(),
        rigid: args.rigid,
        body_move_law: args.body_move,
    };
    let module = if args.name == "echo" {
        tca_ping::echo::connect(&connector, "echo").await
    } else if tca_walk::WALKING_MODULES.contains(&args.name.as_str()) {
        tca_walk::connect_standalone(&args.name, &connector, &options).await
    } else {
        anyhow::bail!(
            "no built-in module named {:?}; built-in modules: {}",
            args.name,
            BUILTIN_MODULES.join(", ")
        );
    }
    .with_context(|| format!("module {} cannot join central at {endpoint}", args.name))?;
    serve(module, &args.name, &endpoint).await
}

/// The legged walk a legged module is set up for, from its arguments.
fn legged_options(
    args: &ModuleArgs,
    robot: &str,
) -> anyhow::Result<tca_legged_walk::LeggedWalkOptions> {
    super::legged_walk::module_options(&super::legged_walk::ModuleWalk {
        robot,
        course: args.course.as_deref(),
        terrain: args.terrain.as_deref(),
        start: args.start.as_deref(),
        seed: args.seed,
        ground_truth: args.ground_truth,
        faults: &args.fault,
        planner: &args.planner,
        gait: args.gait.as_deref(),
        sag: args.sag,
    })
}

/// `tca module legged-controller --telemetry HZ --speed FACTOR`: the simulated Controller on
/// the wall clock, publishing telemetry.
async fn run_live_controller(
    args: &ModuleArgs,
    connector: &Connector,
    endpoint: &str,
) -> anyhow::Result<ExitCode> {
    let Some(robot) = &args.robot else {
        anyhow::bail!(
            "module legged-controller is a multi-legged robot's: give its robot with --robot NAME|FILE.urdf"
        );
    };
    let options = legged_options(args, robot)?;
    let prepared = tca_legged_walk::walk::prepare(&options)?;
    let mut config = prepared.setup.controller_config();
    config.telemetry_hz = args.telemetry;
    config.speed = args.speed;
    let module = tca_legged_controller::connect(connector, config)
        .await
        .with_context(|| format!("module {} cannot join central at {endpoint}", args.name))?;
    serve(module, &args.name, endpoint).await
}

/// `tca module cgspace-worker --index K --robot R --terrain F`: builds its CG-space (the
/// robot's tables on the terrain; the seed builds a course) and serves its strip's joins.
async fn run_cgspace_worker(
    args: &ModuleArgs,
    connector: &Connector,
    endpoint: &str,
) -> anyhow::Result<ExitCode> {
    let Some(index) = args.index else {
        anyhow::bail!(
            "the CG-space worker needs its index: --index K (0 to N-1 for a planner with N workers)"
        );
    };
    let Some(robot) = args.robot.clone() else {
        anyhow::bail!("the CG-space worker needs the planner's robot: --robot NAME|FILE.urdf");
    };
    let terrain = match (&args.terrain, &args.course) {
        (Some(path), _) => path.to_string_lossy().into_owned(),
        (None, Some(course)) => course.clone(),
        (None, None) => anyhow::bail!(
            "the CG-space worker needs the planner's terrain: --terrain COURSE|FILE.asc (and --seed for a course)"
        ),
    };
    let setup = tca_cg_space_bus::WorkerSetup {
        robot,
        terrain: tca_cg_space_bus::TerrainSource::parse(&terrain, args.seed),
        params: match &args.cg_params {
            None => tca_cg_space::CgParams::default(),
            Some(text) => serde_json::from_str(text).with_context(|| {
                format!("--cg-params {text:?} is not a CG-space layout (the JSON of tca_cg_space::CgParams)")
            })?,
        },
        region_cap: args.region_cap,
    };
    let built = setup.clone();
    let space = tokio::task::spawn_blocking(move || built.space())
        .await
        .context("the CG-space worker's set-up stopped")?
        .with_context(|| format!("cgspace-worker {index} cannot be set up"))?;
    let name = tca_cg_space_bus::worker_name(index);
    let module = tca_cg_space_bus::connect_worker(connector, index, space, setup.region_cap)
        .await
        .with_context(|| format!("module {name} cannot join central at {endpoint}"))?;
    serve(module, &name, endpoint).await
}

/// `tca module nav-NAME`: one navigation module, set up as `tca navigate` sets it up.
async fn run_nav_module(
    args: &ModuleArgs,
    inner: &str,
    connector: &Connector,
    endpoint: &str,
) -> anyhow::Result<ExitCode> {
    let terrain = match (&args.terrain, &args.course) {
        (Some(path), _) => path.to_string_lossy().into_owned(),
        (None, Some(course)) => course.clone(),
        (None, None) => anyhow::bail!(
            "module {} needs the navigation's terrain: --course ramps|hill or --terrain FILE.asc (with --start)",
            args.name
        ),
    };
    if !(args.drift.is_finite() && args.drift >= 0.0) {
        anyhow::bail!(
            "--drift {} is not valid; give a percentage of at least 0",
            args.drift
        );
    }
    // A terrain file needs a start; the goal is the navigator's goal's, not the modules'.
    let goal = args.start.as_ref().map(|_| "0,0");
    let course = super::navigate::nav_course(&terrain, args.start.as_deref(), goal)?;
    let (base, params) = super::navigate::nav_robot(
        args.robot.as_deref().unwrap_or("wheeled"),
        None,
        args.matcher,
    )?;
    let setup = tca_nav_bus::NavSetup {
        terrain: std::sync::Arc::new(course.terrain.clone()),
        base,
        params,
        start: course.start,
        drift: args.drift / 100.0,
        seed: args.seed,
    };
    let module = tca_nav_bus::connect_module(inner, connector, &setup)
        .await
        .with_context(|| format!("module {} cannot join central at {endpoint}", args.name))?;
    serve(module, &args.name, endpoint).await
}

/// `tca module footfall-planner|footfall-exec`: the FootFall planner (ground side, with the
/// terrain: `--course`, default rock-field, or `--terrain FILE.asc`) or the executor (robot
/// side, beside the Controller).
async fn run_footfall_module(
    args: &ModuleArgs,
    connector: &Connector,
    endpoint: &str,
) -> anyhow::Result<ExitCode> {
    let module = match args.name.as_str() {
        "footfall-exec" => tca_footfall_bus::connect_executor(connector, "footfall-exec").await,
        "footfall-planner" => {
            let terrain = match (&args.terrain, &args.course) {
                (Some(path), _) => tca_footfall_bus::TerrainSource::File(path.clone()),
                (None, course) => tca_footfall_bus::TerrainSource::parse(
                    course.as_deref().unwrap_or("rock-field"),
                    args.seed,
                ),
            };
            let (field, _) = terrain.load()?;
            tca_footfall_bus::connect_planner(
                connector,
                tca_footfall_bus::PlannerConfig {
                    terrain: std::sync::Arc::new(field),
                    options: tca_footfall::plan::PlanOptions::default(),
                    module_name: "footfall-planner".into(),
                },
            )
            .await
        }
        other => anyhow::bail!(
            "no built-in module named {other:?}; the FootFall modules are footfall-planner and footfall-exec"
        ),
    }
    .with_context(|| format!("module {} cannot join central at {endpoint}", args.name))?;
    serve(module, &args.name, endpoint).await
}

/// Runs a connected module until Ctrl-C or until central closes its link.
async fn serve(module: tca_module::Module, name: &str, endpoint: &str) -> anyhow::Result<ExitCode> {
    eprintln!("module {name} connected to central at {endpoint}");
    tokio::select! {
        r = tokio::signal::ctrl_c() => { r.context("cannot wait for Ctrl-C")?; }
        _ = module.closed() => {
            anyhow::bail!("central closed the link to module {name}");
        }
        launcher = launcher_gone() => {
            eprintln!("module {name}: its launcher (process {launcher}) has gone; stopping");
        }
    }
    module.close().await;
    Ok(ExitCode::SUCCESS)
}

/// Resolves when this module was started by `tca up` (see [`tca_launch::LAUNCHER_PID_ENV`])
/// and its parent is no longer that launcher; never otherwise. Returns the launcher's id.
async fn launcher_gone() -> u32 {
    let launcher = std::env::var(tca_launch::LAUNCHER_PID_ENV)
        .ok()
        .and_then(|v| v.parse::<u32>().ok());
    let Some(launcher) = launcher else {
        return std::future::pending().await;
    };
    let mut every = tokio::time::interval(std::time::Duration::from_millis(500));
    loop {
        every.tick().await;
        if std::os::unix::process::parent_id() != launcher {
            return launcher;
        }
    }
}
