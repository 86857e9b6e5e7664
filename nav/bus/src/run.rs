//! A whole navigation run on the bus in one process: central (simulated time, the traffic
//! logged if asked), the four modules, one `nav.navigate` goal, and the report assembled
//! from the navigator's `nav.frame` informs and the simulated Controller's record.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::Context as _;
use nalgebra::Point2;
use tca_central::StartOptions;
use tca_messages::control::TaskOutcome;
use tca_module::{Attachment, Connector, Module};
use tca_nav_danger_map::CellDanger;
use tca_nav_messages::{
    AcquireDepth, DangerMapQuery, FrameOutcome, InsertDepth, NavFrame, Navigate, SimStatus,
};
use tca_nav_navigator::{
    LastReplan, RunOptions, RunReport, true_danger_map, true_map_path_m, untraversable_along,
};
use tca_robot::Grid;

use crate::convert::grid_of;
use crate::system::{NavSetup, connect_all};

/// A run is over at the latest after this much wall time.
pub const RUN_TIMEOUT: Duration = Duration::from_secs(1800);

/// What a run on the bus gives: the report and the danger map as the LTM Manager ended.
#[derive(Debug, Clone)]
pub struct BusRun {
    /// The report, in the same shape as the one-process loop's.
    pub report: RunReport,
    /// The perceived danger map at the end.
    pub danger: Grid<CellDanger>,
    /// Where the traffic was logged, if it was.
    pub log: Option<PathBuf>,
}

/// Runs the navigation modules on an in-process central toward `opts`'s goal, logging the
/// traffic to `log` if given. The report is the one [`tca_nav_navigator::run`] gives for the
/// same setup, apart from `loop_hz`, which here includes the bus's round trips.
pub async fn run_on_bus(
    setup: &NavSetup,
    opts: &RunOptions,
    log: Option<PathBuf>,
) -> anyhow::Result<BusRun> {
    run_on_bus_with(setup, opts, log, None).await
}

/// [`run_on_bus`] with `attach` joining central before the modules connect (a live view).
pub async fn run_on_bus_with(
    setup: &NavSetup,
    opts: &RunOptions,
    log: Option<PathBuf>,
    attach: Option<&Attachment>,
) -> anyhow::Result<BusRun> {
    let central = tca_central::start(StartOptions::simulated(log.clone()))
        .await
        .context("cannot start central")?;
    let connector = Connector::from(central.in_process());
    if let Some(a) = attach {
        a.attach(connector.clone())
            .await
            .map_err(|e| anyhow::anyhow!("cannot start {e}"))?;
    }
    let modules = connect_all(&connector, setup)
        .await
        .map_err(|e| anyhow::anyhow!("cannot start the navigation modules: {e}"))?;
    let run = run_with(&connector, setup, opts, log).await;
    for m in modules {
        m.close().await;
    }
    central
        .shutdown()
        .await
        .context("central did not shut down cleanly")?;
    run
}

/// Runs one `nav.navigate` goal on the modules already connected behind `connector`'s
/// central (in this process or others, started with the same setup), and assembles the
/// report. `log` is only passed on to the result.
pub async fn run_with(
    connector: &Connector,
    setup: &NavSetup,
    opts: &RunOptions,
    log: Option<PathBuf>,
) -> anyhow::Result<BusRun> {
    let frames: Arc<Mutex<Vec<NavFrame>>> = Arc::default();
    let f1 = frames.clone();
    let runner = Module::builder(format!("nav-runner-{}", std::process::id()))
        .simulated_time(true)
        .handle(move |_ctx, f: NavFrame| {
            f1.lock().unwrap_or_else(|p| p.into_inner()).push(f);
            async { Ok(()) }
        })
        .connect(connector)
        .await
        .with_context(|| format!("the runner cannot join central ({})", connector.describe()))?;
    let task = runner.send_watched(
        &Navigate {
            dx_m: opts.goal_offset[0],
            dy_m: opts.goal_offset[1],
            max_frames: opts.max_frames as u64,
        },
        [],
    )?;
    let outcome = tokio::time::timeout(RUN_TIMEOUT, task.outcome())
        .await
        .map_err(|_| anyhow::anyhow!("the run did not end within {RUN_TIMEOUT:?}"))??;
    // The informs go out before the goal ends, but give them a moment to arrive.
    tokio::time::sleep(Duration::from_millis(20)).await;
    let frames = std::mem::take(&mut *frames.lock().unwrap_or_else(|p| p.into_inner()));
    let last = frames.last().map(|f| f.outcome);
    // Out of frames, the odometry has not yet seen the last drive: one more image moves
    // it, and the LTM Manager corrects it as it corrects every frame.
    let final_estimate = match last {
        Some(FrameOutcome::Drive) => {
            let frame = runner.query(&AcquireDepth).await?;
            Some(runner.query(&InsertDepth { frame }).await?.estimate)
        }
        _ => frames.last().map(|f| f.estimate),
    };
    let sim = runner.query(&SimStatus).await?;
    let danger = grid_of(&runner.query(&DangerMapQuery).await?)?;
    runner.close().await;

    let goal = Point2::new(
        opts.start.x + opts.goal_offset[0],
        opts.start.y + opts.goal_offset[1],
    );
    let truth = true_danger_map(&setup.terrain, &setup.params)?;
    let true_path = true_map_path_m(
        &truth,
        setup.params.beta,
        Point2::new(opts.start.x, opts.start.y),
        goal,
    )?;
    let mut path: Vec<[f64; 2]> = sim.poses.iter().map(|p| [p.x_m, p.y_m]).collect();
    if matches!(
        last,
        Some(FrameOutcome::Reached | FrameOutcome::NoPath | FrameOutcome::NoProgress)
    ) {
        path.push([sim.pose.x_m, sim.pose.y_m]);
    }
    let untraversable_at = untraversable_along(&truth, &path);
    let (reached, reason) = match outcome {
        TaskOutcome::Achieved => (true, "goal reached by the estimate".to_string()),
        TaskOutcome::Failed(r) => (false, r),
        TaskOutcome::Killed => (false, "the navigate goal was killed".to_string()),
    };
    let computing: f64 = frames.iter().map(|f| f.loop_s).sum();
    let est = final_estimate.unwrap_or(sim.pose);
    let report = RunReport {
        robot: setup.base.name(),
        reached,
        reason,
        distance_m: sim.distance_m,
        final_error_m: (Point2::new(sim.pose.x_m, sim.pose.y_m) - goal).norm(),
        estimate_error_m: (sim.pose.x_m - est.x_m).hypot(sim.pose.y_m - est.y_m),
        estimated_path: frames
            .iter()
            .map(|f| [f.estimate.x_m, f.estimate.y_m])
            .collect(),
        planned_path: {
            let mut last = LastReplan::default();
            for f in &frames {
                last.frame(f.replans, || f.path.clone());
            }
            last.into_path()
        },
        replans: frames.last().map_or(0, |f| f.replans),
        exploration_turns: frames.last().map_or(0, |f| f.exploration_turns),
        registrations: frames.last().map_or(0, |f| f.registrations),
        frames: frames.len(),
        loop_hz: if computing > 0.0 {
            frames.len() as f64 / computing
        } else {
            0.0
        },
        collisions: sim.collisions,
        falls: sim.falls,
        untraversable_frames: untraversable_at.len() as u64,
        untraversable_at,
        true_map_path_m: true_path,
        path,
    };
    Ok(BusRun {
        report,
        danger,
        log,
    })
}
