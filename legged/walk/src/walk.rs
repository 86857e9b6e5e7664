//! A whole legged walk in one process: central (simulated time, the traffic logged), the
//! Controller's simulator, the body-mounted scanner, the terrain map and the walking module,
//! one `legged.walk` goal, and the report with every support change the Controller informed.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::Context as _;
use nalgebra::Point2;
use tca_central::StartOptions;
use tca_free_gait::GaitParams;
use tca_legged_controller::InjectedFault;
use tca_legged_messages::{BodyPose, FootContact, LeggedStatus, LeggedWalk, SupportState};
use tca_legged_model::{BUILTIN_ROBOTS, RobotModel};
use tca_legged_sim::StartPose;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module};
use tokio::sync::mpsc;

use crate::cg_workers::{CgWorkerStart, CgWorkers};
use crate::check::check_states;
use crate::messages::{RoutePlanned, StepPlanned};
use crate::picture;
use crate::report::{LeggedWalkReport, RouteSummary, StateRecord};
use crate::system::{LeggedPlanner, LeggedSetup, connect_all};
use crate::terrain::{LeggedTerrain, check_place, footprint_radius};

/// A walk is over at the latest after this much wall time.
pub const WALK_TIMEOUT: Duration = Duration::from_secs(1800);

/// What to walk.
#[derive(Clone, Debug)]
pub struct LeggedWalkOptions {
    /// A shipped robot's name or a URDF file's path.
    pub robot: String,
    /// The ground; `None`: the robot's own scale's rough course.
    pub terrain: Option<LeggedTerrain>,
    /// Where the body starts `[x, y, yaw]`; `None`: the course's start, or a terrain file's
    /// west edge.
    pub start: Option<[f64; 3]>,
    /// The goal `[x, y]`; `None`: the course's goal, or a terrain file's east edge.
    pub goal: Option<[f64; 2]>,
    /// How near the goal the body must come, metres; `None`: the free gait's default.
    pub tolerance_m: Option<f64>,
    /// Plan each step while the one before executes.
    pub concurrent: bool,
    /// Seed of the scanner noise.
    pub seed: u64,
    /// Plan on the true terrain instead of the LTM Manager's maps (the scanner and the map
    /// still run): tells the free gait's failings from perception's.
    pub ground_truth: bool,
    /// Where to write the log (`traffic.mcap`), the map picture (`map.png`) and the report
    /// (`report.json`).
    pub out: Option<PathBuf>,
    /// Walk with the modules already running behind central at this endpoint (each its own
    /// process, `tca module legged-NAME`, started with the same robot, terrain, start and
    /// seed) instead of starting central and the modules here; the log is then central's.
    pub connect: Option<String>,
    /// Hardware faults the simulated Controller injects (none by default).
    pub faults: Vec<InjectedFault>,
    /// What plans the steps (the free gait by default).
    pub planner: LeggedPlanner,
    /// Started once central is up, before the modules connect (in-process only): a live
    /// view, for example.
    pub attach: Option<tca_module::Attachment>,
    /// The simulated robot sags under load when a leg lifts (`None`: rigid).
    pub sag: Option<tca_legged_sim::SagParams>,
    /// With the CG-space planner: worker modules that run its route's roadmap joins
    /// (`None`: the walking module runs them itself). In-process walks only.
    pub cg_workers: Option<WalkWorkers>,
    /// With the CG-space planner: its parameters (`None`: the defaults); the route's seed is
    /// always the walk's.
    pub cg_plan: Option<tca_cg_space::PlanParams>,
}

/// CG-space workers for a walk.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkWorkers {
    /// How many.
    pub count: usize,
    /// Most CG-space regions each holds (`None`: no cap).
    pub region_cap: Option<usize>,
    /// `Some(program)`: each worker its own process, `program module cgspace-worker ...`
    /// (the `tca` binary), on central listening on a free loopback port; `None`: modules in
    /// this process.
    pub program: Option<PathBuf>,
}

impl LeggedWalkOptions {
    /// A walk of `robot` on its default course with every other setting its default.
    pub fn new(robot: impl Into<String>) -> Self {
        LeggedWalkOptions {
            robot: robot.into(),
            terrain: None,
            start: None,
            goal: None,
            tolerance_m: None,
            concurrent: false,
            seed: 1,
            ground_truth: false,
            out: None,
            connect: None,
            faults: Vec::new(),
            planner: LeggedPlanner::FreeGait,
            attach: None,
            sag: None,
            cg_workers: None,
            cg_plan: None,
        }
    }
}

/// Progress events for a display.
#[derive(Clone, Debug)]
pub enum Progress {
    /// The walk starts.
    Started {
        /// Robot, terrain, start and goal, for people.
        describe: String,
    },
    /// A step was planned.
    Step(StepPlanned),
}

/// The robot's description and its URDF text.
pub fn load_robot(name_or_path: &str) -> anyhow::Result<(RobotModel, String)> {
    let model = RobotModel::load(name_or_path)
        .map_err(|e| anyhow::anyhow!("cannot use the robot {name_or_path}: {e}"))?;
    let urdf = match BUILTIN_ROBOTS.iter().find(|r| r.name == name_or_path) {
        Some(r) => r.urdf.to_string(),
        None => std::fs::read_to_string(name_or_path)
            .with_context(|| format!("cannot read the robot description {name_or_path}"))?,
    };
    Ok((model, urdf))
}

/// What the walker module collects.
#[derive(Default)]
struct Collected {
    states: Vec<StateRecord>,
    steps: Vec<StepPlanned>,
    routes: Vec<RoutePlanned>,
}

/// A walk's robot, terrain, start and goal, loaded and checked: what the walker and each of
/// the modules it walks with must agree on.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The modules' shared settings.
    pub setup: LeggedSetup,
    /// Where the body starts `[x, y, yaw]`.
    pub start: [f64; 3],
    /// The goal `[x, y]`.
    pub goal: [f64; 2],
    /// How near the goal the body must come, metres.
    pub tolerance_m: f64,
    /// The terrain, for people.
    pub terrain: String,
}

/// Loads the robot and the terrain of a walk and settles its start and goal; bad robots,
/// terrains, starts and goals are refused, saying what to change.
pub fn prepare(options: &LeggedWalkOptions) -> anyhow::Result<Prepared> {
    let (model, urdf) = load_robot(&options.robot)?;
    let model = Arc::new(model);
    let params = GaitParams::for_model(&model);
    let terrain_choice = options
        .terrain
        .clone()
        .unwrap_or_else(|| LeggedTerrain::default_for(&model, options.seed));
    let loaded = terrain_choice.load()?;
    let field = Arc::new(loaded.field);
    let reach = footprint_radius(&model);
    let (lo, hi) = field.extent();
    let mid_y = 0.5 * (lo.y + hi.y);
    let start = options.start.or(loaded.start).unwrap_or([
        lo.x + reach + 0.05 * (hi.x - lo.x).min(1.0),
        mid_y,
        0.0,
    ]);
    let goal = options
        .goal
        .or(loaded.goal.map(|g| [g.x, g.y]))
        .unwrap_or([hi.x - reach - 0.05 * (hi.x - lo.x).min(1.0), mid_y]);
    check_place(
        "start",
        Point2::new(start[0], start[1]),
        start[2],
        &field,
        &model,
    )?;
    let heading = (goal[1] - start[1]).atan2(goal[0] - start[0]);
    check_place(
        "goal",
        Point2::new(goal[0], goal[1]),
        heading,
        &field,
        &model,
    )?;
    for fault in &options.faults {
        fault.check(&model).map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    let tolerance_m = options.tolerance_m.unwrap_or(params.goal_tolerance_m);
    if !(tolerance_m > 0.0 && tolerance_m.is_finite()) {
        anyhow::bail!("the goal tolerance {tolerance_m} m must be a positive distance");
    }
    let setup = LeggedSetup {
        model: model.clone(),
        urdf,
        terrain: field.clone(),
        start: StartPose {
            x_m: start[0],
            y_m: start[1],
            yaw_rad: start[2],
        },
        seed: options.seed,
        ground_truth: options.ground_truth,
        faults: options.faults.clone(),
        planner: options.planner,
        sag: options.sag,
        cg_workers: None,
        cg_plan: options.cg_plan.clone(),
    };
    Ok(Prepared {
        setup,
        start,
        goal,
        tolerance_m,
        terrain: loaded.describe,
    })
}

/// Connects one legged walking module (`controller`, `ism`, `ltm` or `gait`) for the walk
/// `options` describe, to run as its own process beside the walker of `tca walk --connect`.
pub async fn connect_module_for(
    name: &str,
    connector: &Connector,
    options: &LeggedWalkOptions,
) -> anyhow::Result<Module> {
    let prepared = prepare(options)?;
    crate::system::connect_module(name, connector, &prepared.setup)
        .await
        .map_err(|e| anyhow::anyhow!("cannot start the legged module {name}: {e}"))
}

/// The arguments that make the `tca` binary a CG-space worker of this walk (its central,
/// robot, terrain and seed); the layout and the index are added when each starts.
fn worker_args(
    options: &LeggedWalkOptions,
    model: &RobotModel,
    endpoint: &str,
    region_cap: Option<usize>,
) -> Vec<String> {
    let terrain = options
        .terrain
        .clone()
        .unwrap_or_else(|| LeggedTerrain::default_for(model, options.seed));
    let (terrain, seed) = match terrain {
        LeggedTerrain::Course { name, seed } => (name, seed),
        LeggedTerrain::File(path) => (path.display().to_string(), options.seed),
    };
    let mut args: Vec<String> = [
        "module",
        "cgspace-worker",
        "--connect",
        endpoint,
        "--robot",
        &options.robot,
        "--terrain",
        &terrain,
        "--seed",
        &seed.to_string(),
    ]
    .iter()
    .map(|a| (*a).to_owned())
    .collect();
    if let Some(cap) = region_cap {
        args.extend(["--region-cap".to_owned(), cap.to_string()]);
    }
    args
}

/// Walks, reporting progress through `progress`. Bad robots, terrains, starts and goals are
/// refused before anything starts; a walk that cannot go on ends with the reason.
pub async fn walk(
    options: &LeggedWalkOptions,
    progress: mpsc::UnboundedSender<Progress>,
) -> anyhow::Result<LeggedWalkReport> {
    let started = Instant::now();
    let Prepared {
        setup,
        start,
        goal,
        tolerance_m,
        terrain: terrain_described,
    } = prepare(options)?;
    let model = setup.model.clone();
    let field = setup.terrain.clone();
    let describe = format!(
        "{} on {}, from ({:.2}, {:.2}) to ({:.2}, {:.2})",
        model.name(),
        terrain_described,
        start[0],
        start[1],
        goal[0],
        goal[1]
    );
    let _ = progress.send(Progress::Started {
        describe: describe.clone(),
    });

    if let Some(dir) = &options.out {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    // Here: central (logging to DIR) and the modules in this process. Connected: the
    // walker alone, beside modules that run behind central elsewhere.
    let mut setup = setup;
    if let Some(w) = &options.cg_workers
        && options.connect.is_some()
    {
        anyhow::bail!(
            "CG-space workers ({} asked for) are started by an in-process walk only; walk without --connect, or without workers",
            w.count
        );
    }
    if options.cg_workers.is_some() && options.planner != LeggedPlanner::CgSpace {
        anyhow::bail!("CG-space workers are for the CG-space planner; walk with --planner cgspace");
    }
    let (central, connector, modules, log_path) = match &options.connect {
        None => {
            let log_path = options.out.as_ref().map(|d| d.join("traffic.mcap"));
            let mut start_options = StartOptions::simulated(log_path.clone());
            if let Some(w) = &options.cg_workers {
                setup.cg_workers = Some(match &w.program {
                    None => CgWorkers {
                        count: w.count,
                        start: CgWorkerStart::InProcess {
                            region_cap: w.region_cap,
                        },
                    },
                    Some(program) => {
                        let endpoint = tca_link::net::free_loopback_endpoint()
                            .context("no free loopback port for the CG-space workers' central")?;
                        start_options.listen = vec![endpoint.clone()];
                        CgWorkers {
                            count: w.count,
                            start: CgWorkerStart::Processes {
                                program: program.clone(),
                                args: worker_args(options, &model, &endpoint, w.region_cap),
                            },
                        }
                    }
                });
            }
            let central = tca_central::start(start_options)
                .await
                .context("cannot start central")?;
            let connector = Connector::from(central.in_process());
            if let Some(a) = &options.attach {
                a.attach(connector.clone())
                    .await
                    .map_err(|e| anyhow::anyhow!("cannot start {e}"))?;
            }
            let modules = connect_all(&connector, &setup)
                .await
                .map_err(|e| anyhow::anyhow!("cannot start the legged walking modules: {e}"))?;
            (Some(central), connector, modules, log_path)
        }
        Some(endpoint) => (
            None,
            Connector::endpoint(endpoint.clone()),
            Vec::new(),
            None,
        ),
    };

    let collected = Arc::new(Mutex::new(Collected::default()));
    let (c1, c2, c3) = (collected.clone(), collected.clone(), collected.clone());
    let progress_for_steps = progress.clone();
    let walker = Module::builder(format!("legged-walker-{}", std::process::id()))
        // The latest walker takes the support states and step reports over (an earlier
        // `tca walk --robot ... --connect` on the same system registered them too).
        .replace(true)
        .simulated_time(true)
        .requery_after_crash(tca_module::REQUERIES_AFTER_CRASH)
        .handle(move |_ctx, s: SupportState| {
            lock(&c1).states.push(StateRecord::from(&s));
            async { Ok(()) }
        })
        // Touch-downs are in the support states too; taken so that the Controller's informs
        // have a receiver.
        .handle(|_ctx, _contact: FootContact| async { Ok(()) })
        .handle(move |_ctx, s: StepPlanned| {
            lock(&c2).steps.push(s.clone());
            let _ = progress_for_steps.send(Progress::Step(s));
            async { Ok(()) }
        })
        .handle(move |_ctx, r: RoutePlanned| {
            lock(&c3).routes.push(r);
            async { Ok(()) }
        })
        .connect(&connector)
        .await
        .with_context(|| format!("the walker cannot join central ({})", connector.describe()))?;

    // Asked once, so that the traffic log holds the robot's description (a Foxglove
    // export of the log then shows the robot in 3D).
    if let Err(e) = walker.query(&tca_legged_messages::RobotModel).await {
        tracing::warn!(error = %e, "the Controller did not describe the robot");
    }
    let task = walker.send_watched(
        &LeggedWalk {
            goal_x_m: goal[0],
            goal_y_m: goal[1],
            tolerance_m,
            concurrent: options.concurrent,
        },
        [],
    )?;
    let outcome = walker
        .unless_interrupted(
            task.id(),
            tokio::time::timeout(WALK_TIMEOUT, task.outcome()),
        )
        .await
        .ok_or_else(|| anyhow::anyhow!("interrupted: the walk is stopped (the walker left)"))?
        .map_err(|_| anyhow::anyhow!("the walk did not end within {WALK_TIMEOUT:?}"))??;
    let status = walker.query(&LeggedStatus).await?;
    let body = walker.query(&BodyPose).await?;
    let sim_time_s = walker.time_ns() as f64 / 1e9;
    let distance_to_goal_m = (body.x_m - goal[0]).hypot(body.y_m - goal[1]);
    // The last informs are delivered before the walk's outcome, but give them a moment.
    tokio::time::sleep(Duration::from_millis(20)).await;
    let (states, steps, routes) = {
        let mut c = lock(&collected);
        (
            std::mem::take(&mut c.states),
            std::mem::take(&mut c.steps),
            std::mem::take(&mut c.routes),
        )
    };
    let (reached, reason) = match outcome {
        TaskOutcome::Achieved if distance_to_goal_m <= tolerance_m => (true, None),
        TaskOutcome::Achieved => (
            false,
            Some(format!(
                "the walk ended with the body {distance_to_goal_m:.2} m from the goal, more than the tolerance {tolerance_m:.2} m"
            )),
        ),
        TaskOutcome::Failed(reason) => (false, Some(reason)),
        TaskOutcome::Killed => (false, Some("the walk was killed".into())),
    };
    let planning_ms_per_step = if steps.is_empty() {
        0.0
    } else {
        steps.iter().map(|s| s.planning_ms).sum::<f64>() / steps.len() as f64
    };
    let mut report = LeggedWalkReport {
        reached,
        reason,
        steps: steps.len(),
        falls: status.falls,
        collisions: status.collisions,
        self_collisions: status.self_collisions,
        min_stability_margin_m: states.iter().map(|s| s.margin_m).reduce(f64::min),
        sim_time_s,
        wall_time_s: 0.0,
        planning_ms_per_step,
        states,
        robot: model.name().to_string(),
        terrain: terrain_described,
        mode: format!(
            "{}{}",
            if options.concurrent {
                "concurrent"
            } else {
                "sequential"
            },
            if options.ground_truth {
                ", planned on the true terrain"
            } else {
                ""
            }
        ),
        start,
        goal,
        distance_to_goal_m,
        footholds: steps
            .iter()
            .flat_map(|s| {
                s.footholds
                    .iter()
                    .map(|(leg, p)| (leg.clone(), [p.x_m, p.y_m, p.z_m]))
            })
            .collect(),
        state_problems: Vec::new(),
        planner: options.planner.describe(),
        routes: routes.iter().map(RouteSummary::from).collect(),
        walls: None,
        outputs: Vec::new(),
    };
    if matches!(&options.terrain, Some(LeggedTerrain::Course { name, .. }) if name == "hexapod-walls")
    {
        let path: Vec<[f64; 2]> = report
            .states
            .iter()
            .map(|s| [s.body[0], s.body[1]])
            .collect();
        report.walls = Some(tca_legged_courses::walls::WallsChecks::of_path(&path));
    }
    report.state_problems = check_states(&report.states, &field)
        .iter()
        .map(ToString::to_string)
        .collect();
    walker.close().await;
    for m in modules {
        m.close().await;
    }
    if let Some(central) = central {
        central
            .shutdown()
            .await
            .context("central did not shut down cleanly")?;
    }
    report.wall_time_s = started.elapsed().as_secs_f64();
    if let Some(dir) = &options.out {
        if let Some(log) = log_path {
            report.outputs.push(log);
        }
        let map = dir.join("map.png");
        picture::map_picture(&field, &report)
            .write_png(&map)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", map.display()))?;
        report.outputs.push(map);
        if !routes.is_empty() {
            let path = dir.join("rrt.png");
            picture::route_picture(&field, crate::system::foot_radius(&model), &routes)
                .write_png(&path)
                .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
            report.outputs.push(path);
        }
        let json = dir.join("report.json");
        report.outputs.push(json.clone());
        std::fs::write(&json, serde_json::to_vec_pretty(&report)?)
            .with_context(|| format!("cannot write {}", json.display()))?;
    }
    Ok(report)
}

fn lock(c: &Mutex<Collected>) -> std::sync::MutexGuard<'_, Collected> {
    c.lock().unwrap_or_else(|p| p.into_inner())
}
