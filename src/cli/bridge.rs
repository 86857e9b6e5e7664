//! `tca bridge run|play|delays|demo`: the telemetry bridge between a robot's central and its
//! operators'.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use tca_bridge::{BridgeFile, DelayStats, Direction, PlaybackOptions, Recorded};
use tca_module::Connector;

#[derive(Debug, Subcommand)]
pub(crate) enum BridgeCommand {
    /// Join a robot-side and a ground-side central as a bridge file says: forward the
    /// messages it names each way with a delay, log all that crosses; Ctrl-C stops it.
    Run(RunArgs),
    /// Play a bridge's log back to a ground-side central, with the recorded timing.
    Play(PlayArgs),
    /// The delays a bridge's log measured, against the setting (and between the two centrals,
    /// from their logs).
    Delays(DelaysArgs),
    /// A whole operator session across the bridge on this machine: two centrals, the
    /// simulated Controller with telemetry, the monitor, ten leg moves from the ground; then
    /// the log played back and the telemetry compared.
    Demo(DemoArgs),
}

#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// The bridge file (TOML; see bridge.toml).
    file: PathBuf,
    /// The robot-side central's endpoint, instead of the file's.
    #[arg(long, value_name = "ENDPOINT")]
    robot: Option<String>,
    /// The ground-side central's endpoint, instead of the file's.
    #[arg(long, value_name = "ENDPOINT")]
    ground: Option<String>,
    /// The delay up (ground to robot), seconds, instead of the file's.
    #[arg(long, value_name = "SECONDS")]
    up_delay: Option<f64>,
    /// The delay down (robot to ground), seconds, instead of the file's.
    #[arg(long, value_name = "SECONDS")]
    down_delay: Option<f64>,
    /// Log every crossing here (MCAP), instead of the file's `log`.
    #[arg(long, value_name = "FILE.mcap")]
    log: Option<PathBuf>,
    /// Print the summary at the end as one line of JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub(crate) struct PlayArgs {
    /// The bridge's log.
    log: PathBuf,
    /// The ground-side central to play to.
    #[arg(long, value_name = "ENDPOINT")]
    ground: String,
    /// Times faster than recorded.
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// The module name to play under (default: the recorded bridge's).
    #[arg(long)]
    name: Option<String>,
    /// After the recorded timeline, stay at most this long, seconds, for the recorded
    /// requests the ground side has not sent again yet.
    #[arg(long, default_value_t = 10.0)]
    linger: f64,
    /// Print what was played as one line of JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub(crate) struct DelaysArgs {
    /// The bridge's log.
    log: PathBuf,
    /// The robot-side central's traffic log, to measure between the centrals.
    #[arg(long, value_name = "FILE.mcap", requires = "ground_log")]
    robot_log: Option<PathBuf>,
    /// The ground-side central's traffic log.
    #[arg(long, value_name = "FILE.mcap", requires = "robot_log")]
    ground_log: Option<PathBuf>,
    /// Also list the N crossings furthest past their way's setting, worst first (message,
    /// way, when in the session), to find what made a tail.
    #[arg(long, value_name = "N", default_value_t = 0)]
    worst: usize,
    /// Print the figures as one line of JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub(crate) struct DemoArgs {
    /// The robot: a shipped one or a URDF file.
    #[arg(long, default_value = "athlete")]
    robot: String,
    /// The course it stands on.
    #[arg(long, default_value = "flat")]
    course: String,
    /// The delay each way, seconds (1.3: the light time to the Moon).
    #[arg(long, default_value_t = 1.3)]
    delay: f64,
    /// The delay up instead, seconds.
    #[arg(long, value_name = "SECONDS")]
    up_delay: Option<f64>,
    /// The delay down instead, seconds.
    #[arg(long, value_name = "SECONDS")]
    down_delay: Option<f64>,
    /// Leg moves the operator sends.
    #[arg(long, default_value_t = 10)]
    steps: usize,
    /// Telemetry samples a second.
    #[arg(long, default_value_t = 10.0)]
    telemetry_hz: f64,
    /// The Controller's speed on the wall clock (1: as fast as the robot).
    #[arg(long, default_value_t = 4.0)]
    speed: f64,
    /// Play the log back this many times faster than recorded.
    #[arg(long, default_value_t = 1.0)]
    playback_speed: f64,
    /// Do not play the log back.
    #[arg(long)]
    no_playback: bool,
    /// Where the logs go.
    #[arg(long, default_value = "out/bridge-demo")]
    out: PathBuf,
    /// Print the report as one line of JSON at the end.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(command: BridgeCommand) -> anyhow::Result<ExitCode> {
    match command {
        BridgeCommand::Run(args) => run_bridge(args).await,
        BridgeCommand::Play(args) => play(args).await,
        BridgeCommand::Delays(args) => delays(args),
        BridgeCommand::Demo(args) => demo(args).await,
    }
}

fn delay(direction: Direction, s: f64) -> anyhow::Result<Duration> {
    Ok(tca_bridge::file::delay(direction, s)?)
}

async fn run_bridge(args: RunArgs) -> anyhow::Result<ExitCode> {
    let file = BridgeFile::load(&args.file)?;
    let mut config = file.config(args.robot.as_deref(), args.ground.as_deref())?;
    if let Some(s) = args.up_delay {
        config.up.delay = delay(Direction::Up, s)?;
    }
    if let Some(s) = args.down_delay {
        config.down.delay = delay(Direction::Down, s)?;
    }
    if args.log.is_some() {
        config.log = args.log.clone();
    }
    eprintln!(
        "bridge {}: robot side {}, ground side {}; up {:.3} s, down {:.3} s; waiting for the \
         messages it forwards",
        config.name,
        config.robot.describe(),
        config.ground.describe(),
        config.up.delay.as_secs_f64(),
        config.down.delay.as_secs_f64()
    );
    let bridge = tca_bridge::start(config.clone()).await?;
    for d in Direction::BOTH {
        let names: Vec<String> = bridge
            .forwarded()
            .iter()
            .filter(|f| f.direction == d)
            .map(|f| match f.class() {
                tca_messages::Class::Query => format!(
                    "{} (query, answered within {:.1} s)",
                    f.name(),
                    config.answer_within(d, f.name()).as_secs_f64()
                ),
                c => format!("{} ({c})", f.name()),
            })
            .collect();
        eprintln!(
            "{d} ({} to {}): {}",
            d.from(),
            d.to(),
            if names.is_empty() {
                "nothing".to_owned()
            } else {
                names.join(", ")
            }
        );
    }
    if let Some(log) = &config.log {
        eprintln!("logging every crossing to {}", log.display());
    }
    eprintln!("bridge running; Ctrl-C stops it");
    let ended = tokio::select! {
        r = tokio::signal::ctrl_c() => { r.context("cannot wait for Ctrl-C")?; None }
        side = bridge.closed() => Some(side),
    };
    let summary = bridge.stop().await;
    for d in &summary.delays {
        eprintln!("{}", d.line());
    }
    if args.json {
        println!("{}", serde_json::to_string(&summary)?);
    }
    match ended {
        None => Ok(ExitCode::SUCCESS),
        Some(side) => {
            anyhow::bail!("the link to the {side} side's central closed; the bridge stopped")
        }
    }
}

async fn play(args: PlayArgs) -> anyhow::Result<ExitCode> {
    let recorded = Recorded::open(&args.log)?;
    eprintln!(
        "playing {} back to the ground side at {} ({} crossings recorded)",
        args.log.display(),
        args.ground,
        recorded.crossings.len()
    );
    let report = tca_bridge::play(
        &recorded,
        PlaybackOptions {
            ground: Connector::endpoint(args.ground.clone()),
            speed: args.speed,
            name: args.name.clone(),
            linger: Duration::try_from_secs_f64(args.linger)
                .context("--linger must be zero or more seconds")?,
        },
    )
    .await?;
    println!(
        "played {} messages ({} informs) over {:.1} s of recording, latest {:.1} ms late; \
         answered {} requests as recorded ({} with other data), {} not in the recording",
        report.sent,
        report.informs,
        report.recorded_s,
        report.max_late_ms,
        report.answered,
        report.differing,
        report.unmatched
    );
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    }
    Ok(ExitCode::SUCCESS)
}

fn print_delays(title: &str, stats: &[DelayStats]) {
    println!("{title}:");
    for s in stats {
        println!("  {}", s.line());
    }
}

fn print_worst(worst: &[tca_bridge::LateCrossing]) {
    if worst.is_empty() {
        return;
    }
    println!("  furthest past the setting:");
    for l in worst {
        println!(
            "    {:+.1} ms  #{} {} {} {} at {:.3} s",
            l.error_ms, l.id, l.direction, l.class, l.name, l.at_s
        );
    }
}

fn delays(args: DelaysArgs) -> anyhow::Result<ExitCode> {
    let recorded = Recorded::open(&args.log)?;
    let bridge = recorded.delay_stats();
    print_delays("measured by the bridge", &bridge);
    let mut json = serde_json::json!({ "bridge": bridge });
    if args.worst > 0 {
        let worst = recorded.worst(args.worst);
        print_worst(&worst);
        json["bridge_worst"] = serde_json::to_value(&worst)?;
    }
    if let (Some(r), Some(g)) = (&args.robot_log, &args.ground_log) {
        let read = |p: &PathBuf| {
            tca_logs::LogFile::open(p).with_context(|| format!("cannot read {}", p.display()))
        };
        let (robot, ground) = (read(r)?, read(g)?);
        let between = tca_bridge::end_to_end(&recorded, &robot, &ground);
        print_delays("between the centrals (from their logs)", &between);
        json["centrals"] = serde_json::to_value(&between)?;
        if args.worst > 0 {
            let worst = tca_bridge::worst_between(&recorded, &robot, &ground, args.worst);
            print_worst(&worst);
            json["centrals_worst"] = serde_json::to_value(&worst)?;
        }
    }
    if args.json {
        println!("{json}");
    }
    Ok(ExitCode::SUCCESS)
}

async fn demo(args: DemoArgs) -> anyhow::Result<ExitCode> {
    let up = args.up_delay.unwrap_or(args.delay);
    let down = args.down_delay.unwrap_or(args.delay);
    let options = tca_legged_ground::DemoOptions {
        robot: args.robot.clone(),
        course: args.course.clone(),
        up_delay: delay(Direction::Up, up)?,
        down_delay: delay(Direction::Down, down)?,
        telemetry_hz: args.telemetry_hz,
        speed: args.speed,
        operator: tca_legged_ground::Operator::LegMoves(tca_legged_ground::SessionOptions {
            steps: args.steps,
            ..Default::default()
        }),
        out: args.out.clone(),
        playback_speed: (!args.no_playback).then_some(args.playback_speed),
    };
    println!(
        "operator session across the bridge: {} on {}, {} leg moves, {:.3} s up, {:.3} s down, \
         telemetry at {} Hz",
        args.robot, args.course, args.steps, up, down, args.telemetry_hz
    );
    run_session(&options, args.json).await
}

/// Runs an operator's session across the bridge on this machine and prints what it did;
/// exit code 2 unless every step was achieved and the playback gave the same telemetry.
pub(crate) async fn run_session(
    options: &tca_legged_ground::DemoOptions,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let report = tca_legged_ground::demo(options, |s, footfall| {
        println!(
            "  step {:>2}: {} {} ({:.3} s from sending to its outcome)",
            s.step,
            s.leg,
            s.outcome,
            s.round_trip_s()
        );
        if let Some(f) = footfall {
            println!(
                "           target ({:.2}, {:.2}) of {} green cells; maps {:.2} s, plan {:.2} s \
                 ({}, {} swing way-points); landed {}",
                f.target[0],
                f.target[1],
                f.green_cells,
                f.maps_s,
                f.plan_s,
                f.planner,
                f.swing_waypoints,
                f.landed_error_m.map_or_else(
                    || "with no touch-down seen".to_owned(),
                    |e| format!("{:.3} m from the target", e)
                )
            );
        }
    })
    .await?;
    let steps = options.operator.steps();
    println!(
        "{} of {} steps achieved; {} telemetry samples came down",
        report.session.achieved, steps, report.telemetry
    );
    print_delays("delays measured by the bridge", &report.bridge_delays);
    print_delays(
        "delays between the centrals (from their logs)",
        &report.central_delays,
    );
    let mut ok = report.session.achieved == steps;
    if let Some(r) = &report.replay {
        println!(
            "playback of the bridge's log: {} of {} telemetry samples again, {}; arrival times \
             within {:.1} ms of the live ones",
            r.replayed,
            r.live,
            if r.same_telemetry {
                "the same data in the same order".to_owned()
            } else {
                format!("DIFFERENT: {}", r.difference.clone().unwrap_or_default())
            },
            r.max_timing_error_ms
        );
        ok &= r.same_telemetry;
    }
    for f in &report.files {
        println!("wrote {}", f.display());
    }
    if json {
        println!("{}", serde_json::to_string(&report)?);
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}
