//! A whole operator session across the bridge on one machine: a robot-side central with the
//! simulated Controller publishing telemetry, a ground-side central with the telemetry
//! monitor and the operator, the bridge joining them over zenoh (loopback) with a delay
//! each way; then the bridge's log played back to a fresh ground side and the telemetry
//! compared with what came live. Every central logs its traffic, so the delays are measured
//! twice: by the bridge, and from the two centrals' logs.
//!
//! The operator either sends leg moves it plans itself ([`Operator::LegMoves`]) or works
//! with FootFall ([`Operator::Footfall`]): then the robot side also runs FootFall's executor,
//! the robot sags under load as in the field, the ground side runs FootFall's planner on its
//! copy of the terrain, and each step is picked from the leg's maps, planned and sent up.

use std::path::PathBuf;
use std::time::Duration;

use serde::Serialize;
use tca_bridge::{
    BridgeConfig, DelayStats, NamePattern, PlaybackOptions, PlaybackReport, Recorded, end_to_end,
};
use tca_central::{RunningCentral, StartOptions};
use tca_legged_walk::LeggedTerrain;
use tca_legged_walk::walk::{LeggedWalkOptions, prepare};
use tca_module::{Connector, Module};
use tokio::sync::mpsc;

use crate::error::GroundError;
use crate::footfall::{FootfallSessionOptions, FootfallStep, run_footfall_session};
use crate::monitor::{MonitorOptions, Received, connect_monitor};
use crate::session::{SessionOptions, SessionReport, StepRecord, run_session};

/// What the operator does across the bridge.
#[derive(Clone, Debug, PartialEq)]
pub enum Operator {
    /// Leg moves planned on the ground from the legs' states, sent as `legged.legMove`.
    LegMoves(SessionOptions),
    /// FootFall steps: maps, a target from their green cells, a plan by FootFall's planner on
    /// the ground side, carried out by its executor on the robot side.
    Footfall(FootfallSessionOptions),
}

impl Operator {
    /// Steps to take.
    pub fn steps(&self) -> usize {
        match self {
            Operator::LegMoves(o) => o.steps,
            Operator::Footfall(o) => o.steps,
        }
    }
}

/// What crosses up in the session: the Controller's queries and commands.
pub const UP: &[&str] = &[
    "legged.robotModel",
    "legged.bodyPose",
    "legged.legState",
    "legged.controllerStatus",
    "legged.legMove",
    "legged.bodyMove",
    "legged.halt",
    "legged.resume",
];

/// What else crosses up when the operator works with FootFall: the plans.
pub const FOOTFALL_UP: &[&str] = &["footfall.execute"];

/// What crosses down: telemetry, support states and foot contacts.
pub const DOWN: &[&str] = &[
    "legged.telemetry",
    "legged.supportState",
    "legged.footContact",
];

/// How the session runs.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// The robot: a shipped one or a URDF file.
    pub robot: String,
    /// The built-in course it stands on.
    pub course: String,
    /// Ground to robot.
    pub up_delay: Duration,
    /// Robot to ground.
    pub down_delay: Duration,
    /// Telemetry samples a second.
    pub telemetry_hz: f64,
    /// The Controller's speed on the wall clock (1: as fast as the robot).
    pub speed: f64,
    /// What the operator does.
    pub operator: Operator,
    /// Where the logs go: `robot.mcap`, `ground.mcap`, `bridge.mcap`, `telemetry.jsonl`.
    pub out: PathBuf,
    /// Play the bridge's log back this many times faster than recorded (`None`: no
    /// playback).
    pub playback_speed: Option<f64>,
}

impl Default for DemoOptions {
    fn default() -> Self {
        DemoOptions {
            robot: "athlete".into(),
            course: "flat".into(),
            up_delay: Duration::from_millis(1300),
            down_delay: Duration::from_millis(1300),
            telemetry_hz: 10.0,
            speed: 4.0,
            operator: Operator::LegMoves(SessionOptions::default()),
            out: PathBuf::from("out/bridge-demo"),
            playback_speed: Some(1.0),
        }
    }
}

/// How the played-back telemetry compares with what came live.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ReplayCheck {
    /// What the player did.
    pub playback: PlaybackReport,
    /// Telemetry samples that came live.
    pub live: usize,
    /// Telemetry samples that came in the playback.
    pub replayed: usize,
    /// Whether every sample came again, in order, with the same data.
    pub same_telemetry: bool,
    /// The first difference, if any.
    pub difference: Option<String>,
    /// Largest difference of a sample's arrival after the first one, live against played
    /// back (scaled to recorded time), milliseconds.
    pub max_timing_error_ms: f64,
}

/// What the session did.
#[derive(Clone, Debug, Serialize)]
pub struct DemoReport {
    /// The operator's session.
    pub session: SessionReport,
    /// With FootFall, what each step picked, planned and landed (in the steps' order).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub footfall: Vec<FootfallStep>,
    /// The delays as the bridge measured them, up then down.
    pub bridge_delays: Vec<DelayStats>,
    /// The delays between the two centrals, from their logs, up then down.
    pub central_delays: Vec<DelayStats>,
    /// Telemetry samples received live.
    pub telemetry: usize,
    /// The playback's check, when played back.
    pub replay: Option<ReplayCheck>,
    /// The logs written.
    pub files: Vec<PathBuf>,
}

async fn central(endpoint: &str, log: PathBuf) -> Result<RunningCentral, GroundError> {
    tca_central::start(StartOptions {
        listen: vec![endpoint.to_owned()],
        log: Some(log),
        ..StartOptions::default()
    })
    .await
    .map_err(|e| GroundError::Setup(format!("cannot start a central on {endpoint}: {e}")))
}

fn endpoint() -> Result<String, GroundError> {
    tca_link::net::free_loopback_endpoint()
        .map_err(|e| GroundError::Setup(format!("no free loopback port: {e}")))
}

fn drain(rx: &mut mpsc::UnboundedReceiver<Received>) -> Vec<Received> {
    let mut out = Vec::new();
    while let Ok(r) = rx.try_recv() {
        out.push(r);
    }
    out
}

/// Runs the session; `progress` hears of each step as it ends (with FootFall's details when
/// the operator works with it).
pub async fn demo(
    options: &DemoOptions,
    progress: impl Fn(&StepRecord, Option<&FootfallStep>),
) -> Result<DemoReport, GroundError> {
    std::fs::create_dir_all(&options.out)
        .map_err(|e| GroundError::Setup(format!("cannot create {}: {e}", options.out.display())))?;
    let files = [
        "robot.mcap",
        "ground.mcap",
        "bridge.mcap",
        "telemetry.jsonl",
    ]
    .map(|f| options.out.join(f));
    for f in &files[..3] {
        // A fresh session each run.
        let _ = std::fs::remove_file(f);
    }
    let (robot_ep, ground_ep) = (endpoint()?, endpoint()?);
    let robot_central = central(&robot_ep, files[0].clone()).await?;
    let ground_central = central(&ground_ep, files[1].clone()).await?;
    let robot = Connector::endpoint(robot_ep.clone());
    let ground = Connector::endpoint(ground_ep.clone());

    let footfall = matches!(options.operator, Operator::Footfall(_));
    let mut walk = LeggedWalkOptions::new(options.robot.clone());
    walk.terrain = Some(LeggedTerrain::Course {
        name: options.course.clone(),
        seed: 1,
    });
    if footfall {
        walk.sag = Some(tca_legged_sim::SagParams::athlete());
    }
    let prepared = prepare(&walk).map_err(|e| GroundError::Setup(format!("{e:#}")))?;
    let mut controller = prepared.setup.controller_config();
    controller.telemetry_hz = Some(options.telemetry_hz);
    controller.speed = Some(options.speed);
    let controller = tca_legged_controller::connect(&robot, controller).await?;
    // FootFall's two halves: the executor beside the robot, the planner on the ground with
    // its own copy of the terrain.
    let footfall_modules = if footfall {
        let executor =
            tca_footfall_bus::connect_executor(&robot, tca_footfall_bus::EXECUTOR_MODULE).await?;
        let planner = tca_footfall_bus::connect_planner(
            &ground,
            tca_footfall_bus::PlannerConfig {
                terrain: prepared.setup.terrain.clone(),
                options: tca_footfall::plan::PlanOptions::default(),
                module_name: tca_footfall_bus::PLANNER_MODULE.into(),
            },
        )
        .await?;
        vec![executor, planner]
    } else {
        Vec::new()
    };
    let (monitor, mut live) = connect_monitor(
        &ground,
        MonitorOptions {
            record: Some(files[3].clone()),
            ..MonitorOptions::default()
        },
    )
    .await?;

    let mut config = BridgeConfig::new(robot.clone(), ground.clone());
    config.up.delay = options.up_delay;
    config.down.delay = options.down_delay;
    let extra_up: &[&str] = if footfall { FOOTFALL_UP } else { &[] };
    let up_names: Vec<&str> = UP.iter().chain(extra_up).copied().collect();
    for (way, names) in [(&mut config.up, &up_names[..]), (&mut config.down, DOWN)] {
        for n in names {
            way.messages
                .push(NamePattern::parse(n).map_err(GroundError::Setup)?);
        }
    }
    config.log = Some(files[2].clone());
    let round_trip = options.up_delay + options.down_delay;
    let bridge = tca_bridge::start(config).await?;

    let operator = Module::builder("operator").connect(&ground).await?;
    let session = match &options.operator {
        Operator::LegMoves(o) => {
            let o = SessionOptions {
                query_timeout: round_trip + o.query_timeout,
                ..o.clone()
            };
            run_session(&operator, &o, |s| progress(s, None))
                .await
                .map(|r| (r, Vec::new()))
        }
        Operator::Footfall(o) => {
            // The planner's own questions cross the bridge twice before it answers.
            let o = FootfallSessionOptions {
                query_timeout: round_trip * 2 + o.query_timeout,
                ..o.clone()
            };
            run_footfall_session(&operator, &o, |s, d| progress(s, Some(d))).await
        }
    };
    // No more telemetry; what is on its way comes down before the bridge stops.
    for m in footfall_modules {
        m.close().await;
    }
    controller.close().await;
    tokio::time::sleep(options.down_delay + Duration::from_millis(200)).await;
    operator.close().await;
    bridge.stop().await;
    monitor.close().await;
    let live = drain(&mut live);
    for c in [robot_central, ground_central] {
        c.shutdown()
            .await
            .map_err(|e| GroundError::Setup(format!("a central did not stop cleanly: {e}")))?;
    }
    let (session, footfall) = session?;

    let recorded = Recorded::open(&files[2])?;
    let bridge_delays = recorded.delay_stats();
    let read = |p: &PathBuf| {
        tca_logs::LogFile::open(p)
            .map_err(|e| GroundError::Setup(format!("cannot read {}: {e}", p.display())))
    };
    let central_delays = end_to_end(&recorded, &read(&files[0])?, &read(&files[1])?);
    let replay = match options.playback_speed {
        Some(speed) => Some(replay(&recorded, &live, speed).await?),
        None => None,
    };
    Ok(DemoReport {
        session,
        footfall,
        bridge_delays,
        central_delays,
        telemetry: live.len(),
        replay,
        files: files.to_vec(),
    })
}

/// Plays `recorded` back to a fresh ground central with a telemetry monitor, and compares
/// the telemetry that comes with `live`.
pub async fn replay(
    recorded: &Recorded,
    live: &[Received],
    speed: f64,
) -> Result<ReplayCheck, GroundError> {
    let ep = endpoint()?;
    let ground = tca_central::start(StartOptions {
        listen: vec![ep.clone()],
        ..StartOptions::default()
    })
    .await
    .map_err(|e| GroundError::Setup(format!("cannot start a central on {ep}: {e}")))?;
    let connector = Connector::endpoint(ep);
    let (monitor, mut rx) = connect_monitor(&connector, MonitorOptions::default()).await?;
    let playback = tca_bridge::play(
        recorded,
        PlaybackOptions {
            ground: connector,
            speed,
            name: None,
            linger: Duration::ZERO,
        },
    )
    .await?;
    // Informs sent last are routed before the monitor leaves.
    tokio::time::sleep(Duration::from_millis(200)).await;
    monitor.close().await;
    let _ = ground.shutdown().await;
    let replayed = drain(&mut rx);
    Ok(compare(live, &replayed, speed, playback))
}

/// Compares live and played-back telemetry.
pub fn compare(
    live: &[Received],
    replayed: &[Received],
    speed: f64,
    playback: PlaybackReport,
) -> ReplayCheck {
    let mut difference = None;
    if live.len() != replayed.len() {
        difference = Some(format!(
            "{} samples came live, {} in the playback",
            live.len(),
            replayed.len()
        ));
    }
    let mut max_timing_error_ms: f64 = 0.0;
    let (l0, r0) = (
        live.first().map_or(0, |r| r.at_ns),
        replayed.first().map_or(0, |r| r.at_ns),
    );
    for (k, (l, r)) in live.iter().zip(replayed).enumerate() {
        if difference.is_none() && l.telemetry != r.telemetry {
            difference = Some(format!(
                "sample {k} differs: live seq {} at t {:.3} s, played back seq {} at t {:.3} s",
                l.telemetry.seq, l.telemetry.t_s, r.telemetry.seq, r.telemetry.t_s
            ));
        }
        let lt = l.at_ns.saturating_sub(l0) as f64 / 1e6;
        let rt = r.at_ns.saturating_sub(r0) as f64 / 1e6 * speed;
        max_timing_error_ms = max_timing_error_ms.max((lt - rt).abs());
    }
    ReplayCheck {
        playback,
        live: live.len(),
        replayed: replayed.len(),
        same_telemetry: difference.is_none(),
        difference,
        max_timing_error_ms,
    }
}
