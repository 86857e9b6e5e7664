//! `tca walk`: the main job.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;
use tca_controller_sim::sim::{BodyMoveLaw, ScheduledFault};
use tca_single_leg_messages::WalkMode;
use tca_walk::{Progress, TerrainChoice, WalkOptions};
use tokio::sync::mpsc;

#[derive(Debug, Clone, Args)]
#[command(after_help = "Examples:
  tca walk                                  the single leg on obstacle course 3
  tca walk --course 4 --concurrent --json   course 4, planning during execution
  tca walk --robot ambler --course boulders the six-legged Ambler across a boulder field
  tca walk --robot hexapod                  the small hexapod on its rough course
  tca walk --robot my_robot.urdf --terrain ground.asc --start 1,2 --goal 9,2")]
pub(crate) struct WalkArgs {
    /// Walk a multi-legged robot instead of the single leg: a shipped robot (ambler,
    /// hexapod, athlete) or the path of a URDF file (conventions in the README).
    #[arg(long, value_name = "NAME|FILE.urdf")]
    pub(crate) robot: Option<String>,
    /// Built-in course: for the single leg 1, 2, 3 (the default) or 4 (§7), or "random" (a
    /// course from --seed); with --robot one of `tca course list` (default: the robot's own
    /// scale's rough ground).
    #[arg(long, conflicts_with = "terrain")]
    pub(crate) course: Option<String>,
    /// Walk on a terrain loaded from an ESRI ASCII grid (.asc) file instead.
    #[arg(long, value_name = "FILE.asc")]
    pub(crate) terrain: Option<PathBuf>,
    /// The goal: for the single leg the carriage's place on the rails, metres (the rails
    /// run from 0.5 to 10.5 m); with --robot the body's goal X,Y in world metres (default:
    /// the course's goal, or near a terrain file's east edge).
    #[arg(long, value_name = "METRES|X,Y", allow_negative_numbers = true)]
    pub(crate) goal: Option<String>,
    /// With --robot: where the body starts, X,Y[,YAW] in world metres and radians
    /// (default: the course's start, or near a terrain file's west edge, facing east).
    #[arg(
        long,
        value_name = "X,Y[,YAW]",
        allow_negative_numbers = true,
        requires = "robot"
    )]
    pub(crate) start: Option<String>,
    /// With --robot: the walker plans on the true terrain instead of the LTM Manager's maps
    /// (the scanner and the map still run), to tell a planner's failings from perception's.
    #[arg(long, requires = "robot")]
    pub(crate) ground_truth: bool,
    /// With --robot: what plans the steps: `free` (the free gait, step by step on the LTM
    /// Manager's map), `rrt` (the integrated RRT-Connect planner) or `cgspace` (CG-space
    /// route and footfall planning); the last two plan the whole walk at once on the
    /// terrain given, and again from where the robot stands after a failed move.
    #[arg(
        long,
        value_name = "free|rrt|cgspace",
        default_value = "free",
        requires = "robot"
    )]
    pub(crate) planner: String,
    /// With --planner rrt: the gait of its moves, `tripod` (default) or `wave`.
    #[arg(long, value_name = "tripod|wave", requires = "robot")]
    pub(crate) gait: Option<String>,
    /// With --planner cgspace: run the route's roadmap joins on N worker processes (`tca
    /// module cgspace-worker`, each owning a strip of CG-space), started and stopped by this
    /// walk; central then also listens on a free loopback port for them.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=64), requires = "robot", conflicts_with = "connect")]
    pub(crate) workers: Option<u32>,
    /// With --workers: most CG-space regions (16 x 16 cells, every heading) each worker
    /// holds at once (default: no cap).
    #[arg(long, value_name = "N", requires = "workers")]
    pub(crate) region_cap: Option<usize>,
    /// With --robot: walk once per seed in FIRST..LAST (e.g. 1..5), each in DIR/seed-N, and
    /// print one line per walk and a tally (exit status 0 only when every walk reached its
    /// goal with no fall and no collision).
    #[arg(
        long,
        value_name = "FIRST..LAST",
        requires = "robot",
        conflicts_with = "connect"
    )]
    pub(crate) seeds: Option<String>,
    /// Then walk back to the start, using the maps made walking forward.
    #[arg(long, conflicts_with = "robot")]
    backward: bool,
    /// Plan the next step while this one executes (§3.3, §7.2).
    #[arg(long)]
    pub(crate) concurrent: bool,
    /// Seed of the random course and of the scanner noise.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Directory for the traffic log, the pictures and (with --robot) report.json
    /// (default: out/walk, or out/walk-ROBOT with --robot).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Also write every step's cost maps and leg search as pictures (in DIR/steps).
    #[arg(long, conflicts_with = "robot")]
    pictures: bool,
    /// Walk with the modules already running behind central at this endpoint (`tca up
    /// walk.toml`, or with --robot `tca up walk-legged.toml`: each module started with the
    /// same robot, course or terrain, start and seed as this walk); the log is then
    /// central's.
    #[arg(long, value_name = "ENDPOINT")]
    pub(crate) connect: Option<String>,
    /// What the planners' computing costs in simulated time: "paper" (the 1990 system's
    /// times, §7.2: Gait Planner 2 s, Leg Recovery Planner 12 s a step) or "measured" (this
    /// machine's milliseconds).
    #[arg(long, value_enum, default_value_t = super::Compute::Paper, conflicts_with = "robot")]
    compute: super::Compute,
    /// Inject a fault in the simulated Controller. For the single leg KIND@STEP, during
    /// the body move of step STEP (counting body moves from the start): `slip` (the foot
    /// slips; the Gait Planner replans from where the leg is), `force-drop` (the foot force
    /// drops off) or `limit-switch` (a limit switch trips); the last two are hardware faults
    /// that halt the walk with the reason. With --robot LEG@SECONDS: from that time on
    /// the Controller's motion clock (the states' t_s) the leg's drives stop responding, and a command that would move it raises a
    /// hardware fault that halts the walk (repeat for several legs).
    #[arg(long, value_name = "KIND@STEP|LEG@SECONDS", conflicts_with = "connect")]
    pub(crate) fault: Vec<String>,
    /// A rigid leg: no deflection in the simulated Controller and none compensated by the
    /// planners. By default the leg and rails deflect as the report's did (up to about 20 cm
    /// for a leg move far out to the side) and the planners' kinematics compensate.
    #[arg(long, conflicts_with_all = ["connect", "robot"])]
    rigid: bool,
    /// How the simulated Controller propels the carriage: `servo` (the default: a velocity
    /// law on the carriage position, within a few centimetres) or `open-loop` (the report's
    /// first procedure: the joints along a straight line in joint space to the angles for
    /// the target; the carriage falls short by up to about half a metre over a metre).
    #[arg(
        long,
        value_name = "LAW",
        default_value = "servo",
        conflicts_with_all = ["connect", "robot"]
    )]
    body_move: BodyMoveLaw,
    /// Watch the walk live in Foxglove: serve the Foxglove WebSocket protocol on
    /// `[HOST:]PORT` (loopback unless a host is given; Foxglove's usual port is 8765) from
    /// this process, for as long as the walk runs (in Foxglove: Open connection → Foxglove
    /// WebSocket → ws://127.0.0.1:PORT). With --connect, run `tca foxglove --connect` instead.
    #[arg(long, value_name = "[HOST:]PORT", conflicts_with = "connect")]
    pub(crate) foxglove: Option<String>,
    /// Print the summary as one JSON object on the last line of stdout.
    #[arg(long)]
    pub(crate) json: bool,
}

/// The single leg's fault: at most one, KIND@STEP.
fn single_leg_fault(faults: &[String]) -> anyhow::Result<Option<ScheduledFault>> {
    match faults {
        [] => Ok(None),
        [one] => ScheduledFault::parse(one)
            .map(Some)
            .map_err(|e| anyhow::anyhow!("--fault {one:?}: {e}")),
        _ => anyhow::bail!(
            "the single leg takes one --fault KIND@STEP; several legs' faults (LEG@SECONDS) are for a multi-legged robot (--robot NAME)"
        ),
    }
}

pub(crate) async fn run(args: WalkArgs) -> anyhow::Result<ExitCode> {
    if args.robot.is_some() {
        return super::legged_walk::run(args).await;
    }
    let course = args.course.as_deref().unwrap_or("3");
    let terrain = TerrainChoice::from_args(course, args.terrain.as_deref(), args.seed)?;
    let goal_y_m = match &args.goal {
        None => None,
        Some(text) => Some(text.trim().parse::<f64>().map_err(|_| {
            anyhow::anyhow!(
                "--goal {text:?} is not a place on the rails; give metres, e.g. --goal 9.5 (a goal X,Y is for a multi-legged robot: add --robot NAME)"
            )
        })?),
    };
    let options = WalkOptions {
        terrain,
        goal_y_m,
        backward: args.backward,
        mode: if args.concurrent {
            WalkMode::Concurrent
        } else {
            WalkMode::Sequential
        },
        seed: args.seed,
        out: args.connect.is_none().then(|| {
            args.out
                .clone()
                .unwrap_or_else(|| PathBuf::from("out/walk"))
        }),
        step_pictures: args.pictures,
        connect: args.connect.clone(),
        compute: args.compute.into(),
        fault: single_leg_fault(&args.fault)?,
        rigid: args.rigid,
        body_move_law: args.body_move,
        attach: args
            .foxglove
            .as_deref()
            .map(super::foxglove::live_attachment)
            .transpose()?,
    };
    let (tx, rx) = mpsc::unbounded_channel();
    let display = tokio::spawn(show_progress(rx));
    let result = tca_walk::walk(&options, tx).await;
    let _ = display.await;
    let report = result?;
    super::finish_walk(
        &tca_walk::report::summary(&report),
        args.json
            .then(|| serde_json::to_string(&report))
            .transpose()?,
        report.reached,
    )
}

/// Draws a progress bar on a terminal, one line per step otherwise (stderr).
async fn show_progress(mut rx: mpsc::UnboundedReceiver<Progress>) {
    let tty = std::io::stderr().is_terminal();
    let (mut from, mut goal) = (0.0f64, 1.0f64);
    while let Some(p) = rx.recv().await {
        match p {
            Progress::Leg { goal_y_m, from_y_m } => {
                from = from_y_m;
                goal = goal_y_m;
                if tty {
                    eprintln!();
                }
                eprintln!("walking from y = {from_y_m:.2} m to y = {goal_y_m:.2} m");
            }
            Progress::Step(s) => {
                let total = (goal - from).abs().max(1e-9);
                let done = ((s.body_target_y_m - from).abs() / total).clamp(0.0, 1.0);
                let width = 30;
                let filled = (done * width as f64).round() as usize;
                let bar = format!("[{}{}]", "#".repeat(filled), "-".repeat(width - filled));
                let line = format!(
                    "{bar} {:>3.0}%  step {:>2}: foot at ({:.2}, {:.2}) m, carriage to {:.2} m",
                    done * 100.0,
                    s.step,
                    s.footfall.x_m,
                    s.footfall.y_m,
                    s.body_target_y_m
                );
                super::progress_line(tty, &line);
            }
        }
    }
    if tty {
        eprintln!();
    }
}
