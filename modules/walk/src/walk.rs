//! Walking the leg down an obstacle course, autonomously, from one goal message (§1: sense,
//! plan, execute until the carriage reaches the goal), and reporting what happened.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use serde::Serialize;
use tca_central::StartOptions;
use tca_controller_sim::sim::ScheduledFault;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module};
use tca_single_leg_messages::{
    BodyPosition, ControllerStatus, StepPlanned, Walk, WalkMode, WorldPoint,
};
use tokio::sync::mpsc;

use crate::report;
use crate::system::{ComputeModel, SystemSetup, connect_all};
use crate::terrain::TerrainChoice;

/// The default goal along the rails, metres (the rails run from 0.5 to 10.5 m).
pub const DEFAULT_GOAL_Y_M: f64 = 9.5;

/// A walk is over at the latest after this much wall time.
pub const WALK_TIMEOUT: Duration = Duration::from_secs(900);

/// How long the walker waits for a central that went away to be back (on its journal, the
/// walk goes on) before it gives up.
pub const CENTRAL_PATIENCE: Duration = Duration::from_secs(120);

/// What to walk.
#[derive(Clone, Debug)]
pub struct WalkOptions {
    /// The terrain.
    pub terrain: TerrainChoice,
    /// Carriage goal on the rails (default [`DEFAULT_GOAL_Y_M`]).
    pub goal_y_m: Option<f64>,
    /// Then walk back to the start, using the maps made walking forward.
    pub backward: bool,
    /// Sequential or concurrent stepping.
    pub mode: WalkMode,
    /// Seed of the scanner noise.
    pub seed: u64,
    /// Where to write the log and pictures (in-process only).
    pub out: Option<PathBuf>,
    /// Also write the planners' per-step pictures (cost maps, C-space searches).
    pub step_pictures: bool,
    /// Walk with modules already running behind central at this zenoh endpoint.
    pub connect: Option<String>,
    /// What the planners charge to simulated time (in-process only; modules running
    /// elsewhere were started with their own).
    pub compute: ComputeModel,
    /// Inject this fault in the simulated Controller (in-process only).
    pub fault: Option<ScheduledFault>,
    /// A rigid leg instead of the report's compliant one (in-process only).
    pub rigid: bool,
    /// How the simulated Controller propels the carriage (in-process only): the servo, or
    /// the report's first, open-loop procedure.
    pub body_move_law: tca_controller_sim::sim::BodyMoveLaw,
    /// Started once central is up, before the modules connect (in-process only): a live
    /// view, for example.
    pub attach: Option<tca_module::Attachment>,
}

/// One leg of a walk (forward, or back).
#[derive(Clone, Debug, Serialize)]
pub struct WalkLeg {
    /// The goal.
    pub goal_y_m: f64,
    /// Achieved, and the carriage at the goal.
    pub reached: bool,
    /// Why not, if not.
    pub reason: Option<String>,
    /// Steps planned.
    pub steps: usize,
    /// Simulated seconds from the start of the walk to the end of this leg.
    pub sim_time_s: f64,
}

/// What happened.
#[derive(Clone, Debug, Serialize)]
pub struct WalkReport {
    /// The terrain.
    pub terrain: String,
    /// Sequential or concurrent.
    pub mode: String,
    /// Every leg of the walk reached its goal.
    pub reached: bool,
    /// Why not, if not.
    pub reason: Option<String>,
    /// Steps planned, in all.
    pub steps: usize,
    /// Metres the carriage travelled.
    pub distance_m: f64,
    /// Times the leg struck terrain.
    pub collisions: u32,
    /// Messages central delivered (from the log; in-process only).
    pub messages: Option<usize>,
    /// Messages per step.
    pub messages_per_step: Option<f64>,
    /// Simulated time of the walk, seconds (the mechanism's time, comparable with §7.2).
    pub sim_time_s: f64,
    /// Wall-clock time of the walk, seconds.
    pub wall_time_s: f64,
    /// Wall-clock planning time per step (Gait Planner and Leg Recovery Planner computing),
    /// milliseconds (from the log; in-process only).
    pub planning_ms_per_step: Option<f64>,
    /// Simulated seconds at which each step's body move ended, in order (from the log;
    /// in-process only).
    pub step_ends_s: Vec<f64>,
    /// Where the carriage started and ended.
    pub start_y_m: f64,
    /// Where the carriage ended.
    pub final_y_m: f64,
    /// The legs of the walk.
    pub legs: Vec<WalkLeg>,
    /// The footfalls, in order.
    #[serde(skip)]
    pub footfalls: Vec<WorldPoint>,
    /// Files written.
    pub outputs: Vec<PathBuf>,
}

/// Progress events for a display.
#[derive(Clone, Debug)]
pub enum Progress {
    /// A walk leg started.
    Leg {
        /// Goal.
        goal_y_m: f64,
        /// Carriage position now.
        from_y_m: f64,
    },
    /// A step was planned.
    Step(StepPlanned),
}

/// Walks, reporting progress through `progress`.
pub async fn walk(
    options: &WalkOptions,
    progress: mpsc::UnboundedSender<Progress>,
) -> anyhow::Result<WalkReport> {
    let started = Instant::now();
    let goal = options.goal_y_m.unwrap_or(DEFAULT_GOAL_Y_M);
    // Refused before anything starts (a system joined with `--connect` refuses it too: the
    // Gait Planner checks every walk goal against its rails).
    let rails = tca_robot::LegParams::default().rails;
    tca_gait_planner::walk::check_goal(goal, &rails).map_err(|reason| anyhow::anyhow!(reason))?;
    let mut setup = SystemSetup::new(options.terrain.clone(), options.seed)?;
    setup.compute = options.compute;
    setup.set_rigid(options.rigid);
    if options.body_move_law == tca_controller_sim::sim::BodyMoveLaw::OpenLoop
        && options.mode == WalkMode::Concurrent
    {
        anyhow::bail!(
            "a concurrent walk plans each step from where the previous body move will leave the carriage, and the open-loop body move falls short by tens of centimetres; walk sequentially with --body-move open-loop, or concurrently with the servo"
        );
    }
    setup.set_body_move_law(options.body_move_law);
    if let Some(fault) = options.fault {
        if options.connect.is_some() {
            anyhow::bail!(
                "a fault is injected in the walk's own simulated Controller, so it cannot be \
                 given with --connect; walk in-process to inject {fault}"
            );
        }
        setup.faults.scheduled = Some(fault);
    }
    // In-process: central and every module here; else only the walker joins a running system.
    let (central, connector, _modules, log_path) = match &options.connect {
        Some(endpoint) => (None, Connector::zenoh(endpoint.clone()), Vec::new(), None),
        None => {
            let out = options.out.clone();
            if let Some(dir) = &out {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("cannot create {}", dir.display()))?;
            }
            setup.out = out.clone();
            setup.step_pictures = options.step_pictures;
            let log = out.as_ref().map(|d| d.join("traffic.mcap"));
            let central = tca_central::start(StartOptions::simulated(log.clone()))
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
                .context("cannot start the walking modules")?;
            (Some(central), connector, modules, log)
        }
    };
    let (steps_tx, mut steps_rx) = mpsc::unbounded_channel();
    let progress_for_steps = progress.clone();
    let walker = Module::builder(format!("walker-{}", std::process::id()))
        // The latest walker takes the step reports over (an earlier `tca walk --connect` on
        // the same system registered them too).
        .replace(true)
        .simulated_time(true)
        // A module that dies while answering one of our queries is restarted; ask again.
        .requery_after_crash(tca_module::REQUERIES_AFTER_CRASH)
        .handle(move |_ctx, s: StepPlanned| {
            let _ = steps_tx.send(s.clone());
            let _ = progress_for_steps.send(Progress::Step(s));
            async { Ok(()) }
        })
        .connect(&connector)
        .await
        .context("the walker cannot join central")?;

    // Positions and status are only read: asked again if central restarts meanwhile.
    let start_y = walker
        .query_through_restarts(&BodyPosition, CENTRAL_PATIENCE)
        .await?
        .y_m;
    let mut goals = vec![goal];
    if options.backward {
        goals.push(start_y);
    }
    let mut legs = Vec::new();
    let mut footfalls = Vec::new();
    for g in goals {
        let from = walker
            .query_through_restarts(&BodyPosition, CENTRAL_PATIENCE)
            .await?
            .y_m;
        let _ = progress.send(Progress::Leg {
            goal_y_m: g,
            from_y_m: from,
        });
        let walk_goal = Walk {
            goal_y_m: g,
            mode: options.mode,
        };
        // Refused while central is away (nothing was sent): sent once it is back.
        let task = loop {
            match walker.send_watched(&walk_goal, []) {
                Err(tca_module::ModuleError::CentralLost)
                    if walker.wait_online(CENTRAL_PATIENCE).await => {}
                other => break other?,
            }
        };
        let outcome = walker
            .unless_interrupted(
                task.id(),
                tokio::time::timeout(WALK_TIMEOUT, task.outcome()),
            )
            .await
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "interrupted: the walk is stopped (the walker left); the leg stands where \
                     it stopped"
                )
            })?
            .map_err(|_| anyhow::anyhow!("the walk did not end within {WALK_TIMEOUT:?}"))?
            .map_err(|e| match e {
                tca_module::ModuleError::CentralLost => anyhow::anyhow!(
                    "central went away during the walk and came back without it (a central \
                     started with --journal FILE comes back with its walks, and they go on by \
                     themselves); the leg stands where it stopped. Start central again on the \
                     same endpoint (the modules register again by themselves), then run the \
                     same `tca walk --connect` again: it walks on from where the leg stands"
                ),
                other => other.into(),
            })?;
        let mut steps = 0;
        while let Ok(s) = steps_rx.try_recv() {
            footfalls.push(s.footfall);
            steps += 1;
        }
        let now_y = walker
            .query_through_restarts(&BodyPosition, CENTRAL_PATIENCE)
            .await?
            .y_m;
        let (reached, reason) = match outcome {
            TaskOutcome::Achieved if (now_y - g).abs() <= 0.05 => (true, None),
            TaskOutcome::Achieved => (
                false,
                Some(format!(
                    "the walk ended with the carriage at {now_y:.2} m, not at the goal {g:.2} m"
                )),
            ),
            TaskOutcome::Failed(reason) => (false, Some(reason)),
            TaskOutcome::Killed => (false, Some("the walk was killed".into())),
        };
        legs.push(WalkLeg {
            goal_y_m: g,
            reached,
            reason,
            steps,
            sim_time_s: walker.time_ns() as f64 / 1e9,
        });
        if !reached {
            break; // the leg stands where it stopped, safely
        }
    }
    let status = walker
        .query_through_restarts(&ControllerStatus, CENTRAL_PATIENCE)
        .await?;
    let final_y = walker
        .query_through_restarts(&BodyPosition, CENTRAL_PATIENCE)
        .await?
        .y_m;
    let sim_time_s = walker.time_ns() as f64 / 1e9;
    let wall_time_s = started.elapsed().as_secs_f64();
    let mut report = WalkReport {
        terrain: options.terrain.describe(),
        mode: format!("{:?}", options.mode).to_lowercase(),
        reached: legs.iter().all(|l| l.reached),
        reason: legs.iter().find_map(|l| l.reason.clone()),
        steps: legs.iter().map(|l| l.steps).sum(),
        distance_m: {
            let mut d = 0.0;
            let mut at = start_y;
            for l in &legs {
                let end = if l.reached { l.goal_y_m } else { final_y };
                d += (end - at).abs();
                at = end;
            }
            d
        },
        collisions: status.collisions,
        messages: None,
        messages_per_step: None,
        sim_time_s,
        wall_time_s,
        planning_ms_per_step: None,
        step_ends_s: Vec::new(),
        start_y_m: start_y,
        final_y_m: final_y,
        legs,
        footfalls,
        outputs: Vec::new(),
    };
    if let (Some(central), Some(out)) = (central, options.out.as_ref()) {
        // The leg paths come from the log of the walk so far (flushed every 50 ms).
        tokio::time::sleep(tca_logs::FLUSH_INTERVAL * 3).await;
        let paths = match log_path.as_ref().map(|p| tca_logs::LogFile::open(p)) {
            Some(Ok(log)) => report::leg_paths(&log, start_y),
            _ => Vec::new(),
        };
        report::map_picture(&walker, &setup, &report, paths).await?;
        report.outputs.push(out.join("map.png"));
        walker.close().await;
        central.shutdown().await?;
        if let Some(log) = log_path {
            report::from_log(&mut report, &log, out)?;
        }
    } else {
        walker.close().await;
    }
    Ok(report)
}
