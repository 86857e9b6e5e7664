//! `tca walk --robot`: a multi-legged robot walking a course or a terrain file.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;

use tca_legged_walk::walk::Progress;
use tca_legged_walk::{LeggedPlanner, LeggedTerrain, LeggedWalkOptions};
use tokio::sync::mpsc;

use super::walk::WalkArgs;

/// Parses `X,Y` (two numbers) or `X,Y,YAW` (three, when `yaw` is allowed).
pub(crate) fn parse_place(what: &str, text: &str, yaw: bool) -> anyhow::Result<Vec<f64>> {
    let values: Result<Vec<f64>, _> = text.split(',').map(|v| v.trim().parse::<f64>()).collect();
    let form = if yaw { "X,Y or X,Y,YAW" } else { "X,Y" };
    match values {
        Ok(v) if v.len() == 2 || (yaw && v.len() == 3) => {
            if v.iter().all(|x| x.is_finite()) {
                Ok(v)
            } else {
                anyhow::bail!("--{what} {text:?} holds a value that is not a finite number")
            }
        }
        _ => anyhow::bail!(
            "--{what} {text:?} is not a place; give {form} in world metres{}, e.g. --{what} 3,0{}",
            if yaw { " (and radians)" } else { "" },
            if yaw { ",0.5" } else { "" }
        ),
    }
}

/// Parses `FIRST..LAST` (or one seed).
fn parse_seeds(text: &str) -> anyhow::Result<std::ops::RangeInclusive<u64>> {
    let bad = || {
        anyhow::anyhow!(
            "--seeds {text:?} is not a range of seeds; give FIRST..LAST, e.g. --seeds 1..5"
        )
    };
    let (a, b) = match text.split_once("..") {
        Some((a, b)) => (a, b),
        None => (text, text),
    };
    let (a, b) = (
        a.trim().parse::<u64>().map_err(|_| bad())?,
        b.trim().parse::<u64>().map_err(|_| bad())?,
    );
    if a > b {
        return Err(bad());
    }
    Ok(a..=b)
}

pub(crate) async fn run(args: WalkArgs) -> anyhow::Result<ExitCode> {
    let Some(seeds) = &args.seeds else {
        return run_one(args).await;
    };
    let seeds = parse_seeds(seeds)?;
    let base = args.out.clone().unwrap_or_else(|| default_out(&args));
    let (mut clean, mut total) = (0, 0);
    for seed in seeds {
        let mut one = args.clone();
        one.seeds = None;
        one.seed = seed;
        one.json = false;
        one.out = Some(base.join(format!("seed-{seed}")));
        let report = walk_quietly(one).await?;
        total += 1;
        let ok = report.reached
            && report.falls == 0
            && report.collisions == 0
            && report.self_collisions == 0
            && report.state_problems.is_empty()
            && report.walls.is_none_or(|w| w.as_intended());
        clean += usize::from(ok);
        println!(
            "seed {seed}: {} in {} steps, {} falls, {} collisions, {} self-collisions, least margin {}, {} inconsistent states, {:.2} m from the goal, planning {:.1} ms per step, simulated {:.0} s, wall {:.1} s{}",
            if report.reached {
                "reached"
            } else {
                "not reached"
            },
            report.steps,
            report.falls,
            report.collisions,
            report.self_collisions,
            report
                .min_stability_margin_m
                .map_or("-".into(), |m| format!("{m:.3} m")),
            report.state_problems.len(),
            report.distance_to_goal_m,
            report.planning_ms_per_step,
            report.sim_time_s,
            report.wall_time_s,
            report
                .reason
                .as_ref()
                .map(|r| format!(": {r}"))
                .unwrap_or_default()
        );
        if let Some(w) = &report.walls {
            println!("  {}", w.describe());
        }
        if args.json {
            println!("{}", serde_json::to_string(&report)?);
        }
    }
    println!(
        "{clean} of {total} walks reached the goal with no fall, no collision of any kind and every state consistent"
    );
    Ok(if clean == total {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}

/// One walk with no progress display.
async fn walk_quietly(args: WalkArgs) -> anyhow::Result<tca_legged_walk::LeggedWalkReport> {
    let options = options_of(&args)?;
    let (tx, _rx) = mpsc::unbounded_channel();
    tca_legged_walk::walk(&options, tx).await
}

async fn run_one(args: WalkArgs) -> anyhow::Result<ExitCode> {
    let options = options_of(&args)?;
    let (tx, rx) = mpsc::unbounded_channel();
    let display = tokio::spawn(show_progress(rx));
    let result = tca_legged_walk::walk(&options, tx).await;
    let _ = display.await;
    let report = result?;
    super::finish_walk(
        &report.summary(),
        args.json
            .then(|| serde_json::to_string(&report))
            .transpose()?,
        report.reached,
    )
}

/// The walk the arguments ask for.
fn options_of(args: &WalkArgs) -> anyhow::Result<LeggedWalkOptions> {
    let robot = args.robot.clone().unwrap_or_default();
    let terrain = match (&args.course, &args.terrain) {
        (_, Some(path)) => Some(LeggedTerrain::File(path.clone())),
        (Some(name), None) => Some(LeggedTerrain::Course {
            name: name.clone(),
            seed: args.seed,
        }),
        (None, None) => None,
    };
    let start = match &args.start {
        Some(text) => {
            let v = parse_place("start", text, true)?;
            Some([v[0], v[1], v.get(2).copied().unwrap_or(0.0)])
        }
        None => None,
    };
    let goal = match &args.goal {
        Some(text) => {
            let v = parse_place("goal", text, false)?;
            Some([v[0], v[1]])
        }
        None => None,
    };
    Ok(LeggedWalkOptions {
        robot,
        terrain,
        start,
        goal,
        tolerance_m: None,
        concurrent: args.concurrent,
        seed: args.seed,
        ground_truth: args.ground_truth,
        out: Some(args.out.clone().unwrap_or_else(|| default_out(args))),
        connect: args.connect.clone(),
        faults: parse_faults(&args.fault)?,
        planner: LeggedPlanner::parse(&args.planner, args.gait.as_deref())
            .map_err(|e| anyhow::anyhow!("--planner: {e}"))?,
        attach: args
            .foxglove
            .as_deref()
            .map(super::foxglove::live_attachment)
            .transpose()?,
        sag: None,
        cg_plan: None,
        cg_workers: match args.workers {
            None => None,
            Some(n) => {
                if args.planner != "cgspace" {
                    anyhow::bail!(
                        "--workers {n} runs the CG-space planner's joins; walk with --planner cgspace"
                    );
                }
                Some(tca_legged_walk::WalkWorkers {
                    count: n as usize,
                    region_cap: args.region_cap,
                    program: Some(
                        std::env::current_exe()
                            .context("cannot find this program to start the CG-space workers")?,
                    ),
                })
            }
        },
    })
}

/// The legged robot's injected faults, each LEG@SECONDS.
pub(crate) fn parse_faults(
    texts: &[String],
) -> anyhow::Result<Vec<tca_legged_walk::InjectedFault>> {
    texts
        .iter()
        .map(|t| {
            t.parse()
                .map_err(|e: String| anyhow::anyhow!("--fault {t:?}: {e}"))
        })
        .collect()
}

/// What `tca module legged-NAME` was told of its walk.
#[derive(Clone, Copy)]
pub(crate) struct ModuleWalk<'a> {
    pub(crate) robot: &'a str,
    pub(crate) course: Option<&'a str>,
    pub(crate) terrain: Option<&'a std::path::Path>,
    pub(crate) start: Option<&'a str>,
    pub(crate) seed: u64,
    pub(crate) ground_truth: bool,
    pub(crate) faults: &'a [String],
    pub(crate) planner: &'a str,
    pub(crate) gait: Option<&'a str>,
    /// The simulated Controller's robot sags under load (the shipped athlete's compliance).
    pub(crate) sag: bool,
}

/// The walk a legged module (`tca module legged-NAME`) serves: the robot, the terrain (a
/// course or a file), the start and the seed it shares with the walker and the other
/// modules.
pub(crate) fn module_options(m: &ModuleWalk<'_>) -> anyhow::Result<LeggedWalkOptions> {
    let ModuleWalk {
        robot,
        course,
        terrain,
        start,
        seed,
        ground_truth,
        faults,
        planner,
        gait,
        sag,
    } = *m;
    let terrain = match (course, terrain) {
        (_, Some(path)) => Some(LeggedTerrain::File(path.to_path_buf())),
        (Some(name), None) => Some(LeggedTerrain::Course {
            name: name.to_owned(),
            seed,
        }),
        (None, None) => None,
    };
    let start = match start {
        Some(text) => {
            let v = parse_place("start", text, true)?;
            Some([v[0], v[1], v.get(2).copied().unwrap_or(0.0)])
        }
        None => None,
    };
    Ok(LeggedWalkOptions {
        terrain,
        start,
        seed,
        ground_truth,
        faults: parse_faults(faults)?,
        planner: LeggedPlanner::parse(planner, gait)
            .map_err(|e| anyhow::anyhow!("--planner: {e}"))?,
        sag: sag.then(tca_legged_sim::SagParams::athlete),
        ..LeggedWalkOptions::new(robot)
    })
}

/// `out/walk-ROBOT`, ROBOT the shipped robot's name or the file's stem.
fn default_out(args: &WalkArgs) -> PathBuf {
    let robot = args.robot.clone().unwrap_or_default();
    let stem = std::path::Path::new(&robot)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "robot".into());
    PathBuf::from(format!("out/walk-{stem}"))
}

/// One line per step (rewritten in place on a terminal), on stderr.
async fn show_progress(mut rx: mpsc::UnboundedReceiver<Progress>) {
    let tty = std::io::stderr().is_terminal();
    while let Some(p) = rx.recv().await {
        match p {
            Progress::Started { describe } => eprintln!("walking {describe}"),
            Progress::Step(s) => {
                let legs: Vec<&str> = s.footholds.iter().map(|(l, _)| l.as_str()).collect();
                let line = format!(
                    "step {:>3}: {} to ({:.2}, {:.2}), margin {:.3} m, planned in {:.1} ms",
                    s.step,
                    if legs.is_empty() {
                        "body".to_string()
                    } else {
                        format!("{} swung, body", legs.join(" "))
                    },
                    s.body_target.x_m,
                    s.body_target.y_m,
                    s.min_margin_m,
                    s.planning_ms
                );
                super::progress_line(tty, &line);
            }
        }
    }
    if tty {
        eprintln!();
    }
}
