//! `tca footfall maps|plan|send|campaign`: the FootFall operator's loop for an ATHLETE-like
//! rover (one leg's maps, a step's plan previewed as a ghost, the plan sent to the robot
//! and its telemetry watched), and the acceptance campaign.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::{Args, Subcommand, ValueEnum};
use tca_footfall::Scene;
use tca_footfall::campaign::{CampaignParams, run_campaign};
use tca_footfall::collision::CheckerParams;
use tca_footfall::maps::{LegMaps, MapParams, PolygonKind, brute_force_verdict, leg_maps};
use tca_footfall::picture::{draw_maps, draw_plan};
use tca_footfall::plan::{FootfallPlan, PlanOptions, PlannerKind, StepPlanner};
use tca_footfall::verify::check_plan;
use tca_footfall_bus::{
    FootfallMaps, FootfallPlanStep, FootfallSetup, Telemetry, TerrainSource, scene_from_telemetry,
    send_plan,
};
use tca_legged_sim::StartPose;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module};

use super::legged_walk::parse_place;

/// Pixels per metre of the pictures.
const PPM: f64 = 80.0;

/// `tca footfall ...`.
#[derive(Debug, Subcommand)]
pub(crate) enum FootfallCommand {
    /// One leg's maps: where its foot can be placed (green), cannot (red), would leave the
    /// robot unstable (orange) or could not pass the way-point 20 cm above (blue); the
    /// support and conservative polygons and the stability margin.
    #[command(after_help = "Examples:
  tca footfall maps --leg left_front --png out/footfall
  tca footfall maps --leg right_rear --polygon support --json
  tca footfall maps --leg left_middle --verify          # check every cell by brute force
  tca footfall maps --leg left_front --connect tcp/127.0.0.1:7447   # a running system

The rover is the shipped athlete standing at the start of the built-in rock field unless
--robot, --terrain, --seed and --start say otherwise; with --connect its state comes from
the Controller's telemetry and the planner module answers.")]
    Maps(MapsArgs),
    /// Plan a step of one leg to a target: task-space A* (SBL when A* finds no way) or SBL,
    /// smoothed; the plan drawn over the maps (the ghost), saved for `tca footfall send`.
    #[command(after_help = "Examples:
  tca footfall plan --leg left_front --to 9.2,0.8 --png out/footfall --out step.json
  tca footfall plan --leg left_front --to 9.2,0.8 --planner sbl --json
  tca footfall plan --leg left_front --to 9.2,0.8 --no-heuristics
  tca footfall plan --leg left_front --to 9.2,0.8 --connect tcp/127.0.0.1:7447 --out step.json

Exit status 2 when no plan was found (the reason is printed).")]
    Plan(PlanArgs),
    /// Send a saved plan to the robot (the robot-side executor, `tca module footfall-exec`)
    /// and print its telemetry as it comes back.
    #[command(after_help = "Examples:
  tca footfall send step.json --connect tcp/127.0.0.1:7447

Exit status 0 when the step was carried out, 2 when it failed or was refused (a plan made
for the leg where it no longer stands is refused: plan again), 3 when it was killed.")]
    Send(SendArgs),
    /// The acceptance campaign: (leg, target) pairs from the green cells of the rock field,
    /// planned by SBL, A* and a dense reference planner, and carried out on the rover with
    /// and without sag.
    #[command(after_help = "Examples:
  tca footfall campaign                     # 100 pairs, seed 1
  tca footfall campaign --pairs 20 --seed 2 --json
  tca footfall campaign --out out/footfall/campaign.json")]
    Campaign(CampaignArgs),
    /// An operator's session of FootFall steps across the telemetry bridge, all on this
    /// machine: a robot-side central (the rover's Controller on the rock field, sagging, and
    /// FootFall's executor), a ground-side central (FootFall's planner and the telemetry
    /// monitor), the bridge between them with a delay each way; each step's target picked
    /// from the leg's maps, planned, sent and waited for; the delays measured and the
    /// bridge's log played back against the telemetry that came live.
    #[command(after_help = "Examples:
  tca footfall session                              # ten steps, 1.3 s each way
  tca footfall session --steps 3 --delay 0.3 --json
  tca footfall session --planner sbl --out out/footfall-session

Exit status 0 when every step was achieved and the playback gave the same telemetry, 2
otherwise. The logs (robot.mcap, ground.mcap, bridge.mcap, telemetry.jsonl) go to --out.")]
    Session(SessionArgs),
}

#[derive(Debug, Args)]
pub(crate) struct SessionArgs {
    /// Steps to plan and carry out.
    #[arg(long, default_value_t = 10)]
    steps: usize,
    /// The delay each way, seconds (1.3: the light time to the Moon).
    #[arg(long, default_value_t = 1.3)]
    delay: f64,
    /// How far from where it stands each step aims a foot, metres.
    #[arg(long, default_value_t = 0.3)]
    stride: f64,
    /// Which planner plans the swings.
    #[arg(long, value_enum, default_value_t = PlannerArg::Astar)]
    planner: PlannerArg,
    /// Plan without the field heuristics.
    #[arg(long)]
    no_heuristics: bool,
    /// Telemetry samples a second.
    #[arg(long, default_value_t = 10.0)]
    telemetry_hz: f64,
    /// The Controller's speed on the wall clock (1: as fast as the robot).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Play the bridge's log back this many times faster than recorded.
    #[arg(long, default_value_t = 4.0)]
    playback_speed: f64,
    /// Do not play the bridge's log back.
    #[arg(long)]
    no_playback: bool,
    /// Where the logs go.
    #[arg(long, default_value = "out/footfall-session")]
    out: PathBuf,
    /// Print the report as one line of JSON at the end.
    #[arg(long)]
    json: bool,
}

/// The robot and its terrain.
#[derive(Debug, Args)]
pub(crate) struct SceneArgs {
    /// The robot: a shipped one (`tca robot list`) or a URDF file.
    #[arg(long, default_value = "athlete")]
    robot: String,
    /// The terrain: a built-in course's name (`tca course list`) or an .asc file.
    #[arg(long, default_value = "rock-field")]
    terrain: String,
    /// Seed of a built-in course.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Where the robot stands, X,Y[,YAW] in world metres and radians (a course's start by
    /// default).
    #[arg(long, value_name = "X,Y[,YAW]", allow_hyphen_values = true)]
    start: Option<String>,
}

impl SceneArgs {
    fn setup(&self) -> anyhow::Result<FootfallSetup> {
        let start = match &self.start {
            Some(text) => {
                let v = parse_place("start", text, true)?;
                Some(StartPose {
                    x_m: v[0],
                    y_m: v[1],
                    yaw_rad: v.get(2).copied().unwrap_or(0.0),
                })
            }
            None => None,
        };
        Ok(FootfallSetup {
            robot: self.robot.clone(),
            terrain: TerrainSource::parse(&self.terrain, self.seed),
            start,
        })
    }
}

/// `--polygon`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum PolygonArg {
    /// The convex hull of the standing feet.
    Support,
    /// The intersection of the support polygons with any one foot lifted.
    Conservative,
}

impl From<PolygonArg> for PolygonKind {
    fn from(p: PolygonArg) -> Self {
        match p {
            PolygonArg::Support => PolygonKind::Support,
            PolygonArg::Conservative => PolygonKind::Conservative,
        }
    }
}

/// `--planner`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum PlannerArg {
    /// Task-space A* over a 20 cm lattice, SBL when it finds no way.
    Astar,
    /// SBL alone.
    Sbl,
}

impl From<PlannerArg> for PlannerKind {
    fn from(p: PlannerArg) -> Self {
        match p {
            PlannerArg::Astar => PlannerKind::Astar,
            PlannerArg::Sbl => PlannerKind::Sbl,
        }
    }
}

#[derive(Debug, Args)]
pub(crate) struct MapsArgs {
    /// The leg, by its name in the robot's description (e.g. left_front).
    #[arg(long)]
    leg: String,
    #[command(flatten)]
    scene: SceneArgs,
    /// The polygon stability is judged against with the foot placed.
    #[arg(long, value_enum, default_value_t = PolygonArg::Conservative)]
    polygon: PolygonArg,
    /// Least distance of the centre of mass from that polygon's edge, metres.
    #[arg(long, value_name = "M")]
    min_margin: Option<f64>,
    /// Cell size, metres.
    #[arg(long, value_name = "M", default_value_t = 0.05)]
    resolution: f64,
    /// Draw the maps as DIR/maps-LEG.png.
    #[arg(long, value_name = "DIR")]
    png: Option<PathBuf>,
    /// Print the maps as one JSON line.
    #[arg(long)]
    json: bool,
    /// Check every cell against a brute-force evaluation of the same rules and print the
    /// agreement (slow: seconds to a minute).
    #[arg(long)]
    verify: bool,
    /// Ask the planner module of a running system (`tca module footfall-planner`); the
    /// robot's state comes from its Controller.
    #[arg(long, value_name = "ENDPOINT")]
    connect: Option<String>,
}

#[derive(Debug, Args)]
pub(crate) struct PlanArgs {
    /// The leg.
    #[arg(long)]
    leg: String,
    /// Where the wheel should go, X,Y in world metres.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    to: String,
    /// Which planner plans the swing.
    #[arg(long, value_enum, default_value_t = PlannerArg::Astar)]
    planner: PlannerArg,
    /// Plan without the field heuristics (terrain as it is, way-points just clear of the
    /// ground instead of 20 cm up).
    #[arg(long)]
    no_heuristics: bool,
    #[command(flatten)]
    scene: SceneArgs,
    /// Draw the plan over the leg's maps as DIR/plan-LEG.png.
    #[arg(long, value_name = "DIR")]
    png: Option<PathBuf>,
    /// Save the plan (JSON) for `tca footfall send`.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print the plan as one JSON line.
    #[arg(long)]
    json: bool,
    /// Ask the planner module of a running system.
    #[arg(long, value_name = "ENDPOINT")]
    connect: Option<String>,
}

#[derive(Debug, Args)]
pub(crate) struct SendArgs {
    /// The plan file (`tca footfall plan --out FILE`).
    plan: PathBuf,
    /// The central the robot-side executor is behind (default tcp/127.0.0.1:7447).
    #[arg(long, value_name = "ENDPOINT")]
    connect: Option<String>,
    /// Print the telemetry and the outcome as JSON lines.
    #[arg(long)]
    json: bool,
    /// Give up after this many seconds.
    #[arg(long, value_name = "S", default_value_t = 300.0)]
    timeout: f64,
}

#[derive(Debug, Args)]
pub(crate) struct CampaignArgs {
    /// How many (leg, target) pairs.
    #[arg(long, default_value_t = 100)]
    pairs: usize,
    /// Seed of the draw and of SBL.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Seed of the rock field.
    #[arg(long, default_value_t = 1)]
    course_seed: u64,
    /// Print the summary as one JSON line.
    #[arg(long)]
    json: bool,
    /// Write the whole report (every pair) as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

pub(crate) async fn run(cmd: FootfallCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        FootfallCommand::Maps(a) => maps(a).await,
        FootfallCommand::Plan(a) => plan(a).await,
        FootfallCommand::Send(a) => send(a).await,
        FootfallCommand::Session(a) => session(a).await,
        FootfallCommand::Campaign(a) => campaign(a).await,
    }
}

fn map_params(a: &MapsArgs) -> anyhow::Result<MapParams> {
    let mut p = MapParams {
        polygon: a.polygon.into(),
        resolution_m: a.resolution,
        ..MapParams::default()
    };
    if let Some(m) = a.min_margin {
        p.min_margin_m = m;
    }
    p.check()?;
    Ok(p)
}

/// An operator module joined to the central at `endpoint`.
async fn operator(endpoint: &str) -> anyhow::Result<Module> {
    Module::builder("footfall-operator")
        .query_timeout(Duration::from_secs(120))
        .connect(&Connector::endpoint(endpoint.to_owned()))
        .await
        .with_context(|| format!("cannot join central at {endpoint}"))
}

/// The scene as the robot reports it, on the terrain of `setup`.
async fn scene_over_bus(op: &Module, setup: &FootfallSetup) -> anyhow::Result<Scene> {
    let (terrain, _) = setup.terrain.load()?;
    scene_from_telemetry(op, &Arc::new(terrain), None)
        .await
        .map_err(|e| anyhow::anyhow!("{e}"))
}

fn write_png(
    canvas: &tca_footfall::picture::Canvas,
    dir: &Path,
    name: &str,
) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join(name);
    canvas
        .write_png(&path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

fn print_maps(maps: &LegMaps, what: &str, seconds: f64) {
    let k = maps.counts;
    println!(
        "maps of leg {} ({what}): {} cells of {:.0} cm in {seconds:.2} s",
        maps.leg,
        k.total(),
        maps.resolution_m * 100.0
    );
    println!(
        "  green {} (can be placed), red {} (cannot), orange {} (unstable), blue {} (way-point {:.0} cm up out of reach)",
        k.green,
        k.red,
        k.orange,
        k.blue,
        maps.params.waypoint_m * 100.0
    );
    println!(
        "  standing now: margin {:.2} m to the support polygon, {:.2} m to the conservative one; {:.2} m with {} lifted",
        maps.now.support_margin_m,
        maps.now.conservative_margin_m,
        maps.now.lifted_margin_m,
        maps.leg
    );
}

async fn maps(a: MapsArgs) -> anyhow::Result<ExitCode> {
    let setup = a.scene.setup()?;
    let params = map_params(&a)?;
    let started = Instant::now();
    let (scene, maps) = match &a.connect {
        Some(endpoint) => {
            let op = operator(endpoint).await?;
            let maps = op
                .query(&FootfallMaps {
                    leg: a.leg.clone(),
                    polygon: Some(params.polygon),
                    resolution_m: Some(params.resolution_m),
                })
                .await
                .with_context(|| format!("the planner could not make the maps of leg {}", a.leg))?;
            let scene = if a.png.is_some() || a.verify {
                Some(scene_over_bus(&op, &setup).await?)
            } else {
                None
            };
            op.close().await;
            (scene, maps)
        }
        None => {
            let scene = setup.scene()?;
            let leg = scene.leg_index(&a.leg)?;
            let maps = leg_maps(&scene, leg, &params)?;
            (Some(scene), maps)
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    let what = format!("{} on {}", setup.robot, setup.terrain.describe());
    if !a.json {
        print_maps(&maps, &what, seconds);
    }
    if let (Some(dir), Some(scene)) = (&a.png, &scene) {
        let path = write_png(
            &draw_maps(scene, &maps, PPM),
            dir,
            &format!("maps-{}.png", maps.leg),
        )?;
        if !a.json {
            println!("  wrote {}", path.display());
        }
    }
    let mut agreement = None;
    if a.verify
        && let Some(scene) = &scene
    {
        let leg = scene.leg_index(&a.leg)?;
        let (mut same, mut total) = (0usize, 0usize);
        for iy in 0..maps.ny {
            for ix in 0..maps.nx {
                if let Some(c) = maps.colour(ix, iy) {
                    total += 1;
                    if brute_force_verdict(scene, leg, &maps.params, maps.centre(ix, iy)) == c {
                        same += 1;
                    }
                }
            }
        }
        let share = same as f64 / total.max(1) as f64;
        agreement = Some((same, total, share));
        if !a.json {
            println!(
                "  brute-force check of the same rules: {same} of {total} cells agree ({:.2} %)",
                100.0 * share
            );
        }
    }
    if a.json {
        let mut v = serde_json::to_value(&maps)?;
        v["seconds"] = serde_json::json!(seconds);
        if let Some((same, total, share)) = agreement {
            v["brute_force"] = serde_json::json!({"agree": same, "cells": total, "share": share});
        }
        println!("{v}");
    }
    Ok(ExitCode::SUCCESS)
}

async fn plan(a: PlanArgs) -> anyhow::Result<ExitCode> {
    let setup = a.scene.setup()?;
    let to = parse_place("to", &a.to, false)?;
    let target = tca_footfall::nalgebra::Point2::new(to[0], to[1]);
    let mut options = PlanOptions {
        planner: a.planner.into(),
        ..PlanOptions::default()
    };
    if a.no_heuristics {
        options.heuristics = None;
    }
    let (scene, result) = match &a.connect {
        Some(endpoint) => {
            let op = operator(endpoint).await?;
            let result = op
                .query(&FootfallPlanStep {
                    leg: a.leg.clone(),
                    target: [target.x, target.y],
                    planner: options.planner,
                    heuristics: !a.no_heuristics,
                })
                .await
                .map_err(|e| anyhow::anyhow!("{e}"));
            let scene = scene_over_bus(&op, &setup).await?;
            op.close().await;
            (Arc::new(scene), result)
        }
        None => {
            let scene = Arc::new(setup.scene()?);
            let leg = scene.leg_index(&a.leg)?;
            let planner = StepPlanner::new(scene.clone(), options.clone())?;
            let result = planner
                .plan(leg, target)
                .map_err(|e| anyhow::anyhow!("{e}"));
            (scene, result)
        }
    };
    let plan = match result {
        Ok(p) => p,
        Err(e) => {
            if a.json {
                println!(
                    "{}",
                    serde_json::json!({"planned": false, "reason": e.to_string()})
                );
            } else {
                eprintln!("no plan: {e}");
            }
            return Ok(ExitCode::from(2));
        }
    };
    let check = check_plan(
        &scene,
        &plan,
        &CheckerParams {
            margins: options.map.margins.clone(),
            resolution_rad: options.resolution_rad,
            ..CheckerParams::default()
        },
    )?;
    if let Some(path) = &a.out {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        std::fs::write(path, plan.to_json())
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if !a.json {
        println!(
            "plan for leg {} to ({:.2}, {:.2}): {}{}, {} way-points in the swing, {:.1} ms",
            plan.leg,
            plan.target[0],
            plan.target[1],
            plan.planner,
            if plan.astar_failed {
                " (A* found no way)"
            } else {
                ""
            },
            plan.swing_waypoints,
            plan.times.total_ms
        );
        match plan.heuristics {
            Some(h) => println!(
                "  field heuristics: way-points {:.0} cm above the start and the target, terrain raised {:.0} cm",
                h.waypoint_m * 100.0,
                h.raise_m * 100.0
            ),
            None => println!(
                "  no heuristics: way-points {:.0} cm up, terrain as it is",
                plan.lift_m * 100.0
            ),
        }
        println!(
            "  checked along every {:.2} rad: {}; through the way-points: {}; swing length {:.2} rad (before smoothing {:.2})",
            options.resolution_rad,
            match &check.broken {
                None => "every margin kept".to_owned(),
                Some(b) => format!("a margin broken: {b}"),
            },
            if check.through_waypoints { "yes" } else { "no" },
            plan.swing_length_rad[1],
            plan.swing_length_rad[0]
        );
        if let Some(path) = &a.out {
            println!(
                "  wrote {} (send it with `tca footfall send {}`)",
                path.display(),
                path.display()
            );
        }
    }
    if let Some(dir) = &a.png {
        let leg = scene.leg_index(&plan.leg)?;
        let maps = leg_maps(&scene, leg, &options.map)?;
        let path = write_png(
            &draw_plan(&scene, &maps, &plan, PPM),
            dir,
            &format!("plan-{}.png", plan.leg),
        )?;
        if !a.json {
            println!("  wrote {}", path.display());
        }
    }
    if a.json {
        let mut v = serde_json::to_value(&plan)?;
        v["planned"] = serde_json::json!(true);
        v["check"] = serde_json::to_value(&check)?;
        println!("{v}");
    }
    Ok(ExitCode::SUCCESS)
}

async fn send(a: SendArgs) -> anyhow::Result<ExitCode> {
    let text = std::fs::read_to_string(&a.plan)
        .with_context(|| format!("cannot read the plan {}", a.plan.display()))?;
    let plan = FootfallPlan::from_json(&text)?;
    if !(a.timeout.is_finite() && a.timeout > 0.0) {
        anyhow::bail!(
            "--timeout {} is not valid; give a positive number of seconds",
            a.timeout
        );
    }
    let endpoint = a
        .connect
        .clone()
        .unwrap_or_else(|| tca_central::DEFAULT_ENDPOINT.to_owned());
    let op = operator(&endpoint).await?;
    if !a.json {
        println!(
            "sending the step of leg {} to ({:.2}, {:.2}) ({} way-points) to the robot at {endpoint}",
            plan.leg,
            plan.target[0],
            plan.target[1],
            plan.waypoints.len()
        );
    }
    let started = Instant::now();
    let json = a.json;
    let show = move |t: Telemetry| {
        let at = started.elapsed().as_secs_f64();
        match t {
            Telemetry::Contact(c) => {
                if json {
                    println!(
                        "{}",
                        serde_json::json!({"telemetry": "footContact", "received_s": at, "leg": c.leg, "stance": c.stance, "at": [c.at.x_m, c.at.y_m, c.at.z_m]})
                    );
                } else {
                    println!(
                        "  {at:7.2} s  {} {} at ({:.3}, {:.3}, {:.3})",
                        c.leg,
                        if c.stance {
                            "touched down"
                        } else {
                            "lifted off"
                        },
                        c.at.x_m,
                        c.at.y_m,
                        c.at.z_m
                    );
                }
            }
            Telemetry::Support(s) => {
                let standing = s.feet.iter().filter(|f| f.stance).count();
                if json {
                    println!(
                        "{}",
                        serde_json::json!({"telemetry": "supportState", "received_s": at, "t_s": s.t_s, "standing": standing, "margin_m": s.margin_m, "body": [s.body.x_m, s.body.y_m, s.body.z_m]})
                    );
                } else {
                    println!(
                        "  {at:7.2} s  support: {standing} feet standing, margin {:.2} m, body at z {:.3} m (robot clock {:.1} s)",
                        s.margin_m, s.body.z_m, s.t_s
                    );
                }
            }
        }
    };
    let outcome = tokio::time::timeout(
        Duration::from_secs_f64(a.timeout),
        send_plan(&op, &plan, Duration::from_millis(500), show),
    )
    .await
    .map_err(|_| anyhow::anyhow!("the robot did not finish the step within {} s", a.timeout))?
    .context("the plan could not be sent")?;
    op.close().await;
    let (code, text) = match &outcome {
        TaskOutcome::Achieved => (0, "carried out".to_owned()),
        TaskOutcome::Failed(why) => (2, format!("failed: {why}")),
        TaskOutcome::Killed => (3, "killed".to_owned()),
    };
    if a.json {
        println!(
            "{}",
            serde_json::json!({"outcome": text, "achieved": code == 0, "seconds": started.elapsed().as_secs_f64()})
        );
    } else {
        println!("step {text} after {:.2} s", started.elapsed().as_secs_f64());
    }
    Ok(ExitCode::from(code))
}

async fn session(a: SessionArgs) -> anyhow::Result<ExitCode> {
    use tca_bridge::Direction;
    let delay = |d, s| -> anyhow::Result<Duration> { Ok(tca_bridge::file::delay(d, s)?) };
    let options = tca_legged_ground::DemoOptions {
        robot: "athlete".into(),
        course: "rock-field".into(),
        up_delay: delay(Direction::Up, a.delay)?,
        down_delay: delay(Direction::Down, a.delay)?,
        telemetry_hz: a.telemetry_hz,
        speed: a.speed,
        operator: tca_legged_ground::Operator::Footfall(
            tca_legged_ground::FootfallSessionOptions {
                steps: a.steps,
                stride_m: a.stride,
                planner: a.planner.into(),
                heuristics: !a.no_heuristics,
                ..Default::default()
            },
        ),
        out: a.out.clone(),
        playback_speed: (!a.no_playback).then_some(a.playback_speed),
    };
    println!(
        "FootFall session across the bridge: athlete on the rock field, {} steps, {:.3} s each \
         way, telemetry at {} Hz",
        a.steps, a.delay, a.telemetry_hz
    );
    super::bridge::run_session(&options, a.json).await
}

async fn campaign(a: CampaignArgs) -> anyhow::Result<ExitCode> {
    if a.pairs == 0 {
        anyhow::bail!("--pairs 0: give at least one pair");
    }
    let params = CampaignParams {
        pairs: a.pairs,
        seed: a.seed,
        course_seed: a.course_seed,
        ..CampaignParams::default()
    };
    let json = a.json;
    let started = Instant::now();
    let report = tokio::task::spawn_blocking(move || {
        run_campaign(&params, |n, p| {
            if !json {
                println!(
                    "{:3} {:12} ({:5.2}, {:5.2})  reference {}  sbl {} {:6.1} ms {} wp  a* {} {:6.1} ms  sag: with {} without {}",
                    n + 1,
                    p.leg,
                    p.target[0],
                    p.target[1],
                    if p.feasible { "feasible  " } else { "infeasible" },
                    if p.sbl.ok { "ok  " } else { "FAIL" },
                    p.sbl.ms,
                    p.sbl.swing_waypoints,
                    if p.astar.ok { "ok  " } else { "FAIL" },
                    p.astar.ms,
                    p.sag_with_heuristics.as_ref().map_or("-".to_owned(), |e| e.collisions.to_string()),
                    p.sag_without_heuristics.as_ref().map_or("-".to_owned(), |e| e.collisions.to_string()),
                );
            }
        })
    })
    .await
    .context("the campaign stopped")??;
    let s = &report.summary;
    if let Some(path) = &a.out {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if json {
        let mut v = serde_json::to_value(s)?;
        v["wall_time_s"] = serde_json::json!(started.elapsed().as_secs_f64());
        println!("{v}");
    } else {
        println!(
            "campaign of {} pairs (seed {}, rock field {}) in {:.1} s",
            s.pairs,
            a.seed,
            a.course_seed,
            started.elapsed().as_secs_f64()
        );
        println!(
            "  posed {} of {}; the reference planner proved {} feasible (median {:.1} ms)",
            s.posed, s.pairs, s.feasible, s.reference_median_ms
        );
        println!(
            "  SBL + smoothing: {} of {} feasible ({:.1} %), median {:.1} ms, 90th percentile {:.1} ms; {} of {} plans pass the outside check; at most {} swing way-points",
            s.sbl_successes,
            s.feasible,
            100.0 * s.sbl_rate,
            s.sbl_ms[0],
            s.sbl_ms[1],
            s.sbl_checked,
            s.sbl_plans,
            s.sbl_max_waypoints
        );
        println!(
            "  A* alone: {} of {} feasible ({:.1} %), median {:.1} ms, 90th percentile {:.1} ms; A* then SBL: {} of {}, median {:.1} ms",
            s.astar_successes,
            s.feasible,
            100.0 * s.astar_rate,
            s.astar_ms[0],
            s.astar_ms[1],
            s.combined_successes,
            s.feasible,
            s.combined_ms[0]
        );
        println!(
            "  with sag: plans with the heuristics {} collisions in {} runs; without them {} collisions ({} of {} runs collided; on a rigid robot {}); way-points without the raise {} collisions in {} runs",
            s.sag_collisions_with,
            s.sag_runs_with,
            s.sag_collisions_without,
            s.sag_pairs_colliding_without,
            s.sag_runs_without,
            s.rigid_collisions_without,
            s.sag_collisions_waypoints_only,
            s.sag_runs_waypoints_only
        );
        if let Some(path) = &a.out {
            println!("  wrote {}", path.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}
