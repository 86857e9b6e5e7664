//! `tca chaos`: crash-proof walking, measured.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_chaos::ChaosOptions;
use tca_walk::TerrainChoice;

#[derive(Debug, Args)]
pub(crate) struct ChaosArgs {
    /// Walks to complete.
    #[arg(long, default_value_t = 5)]
    walks: usize,
    /// Module kills (SIGKILL, then a restart) to make across the walks.
    #[arg(long, default_value_t = 5)]
    kills: usize,
    /// Kill central itself instead of the modules: central runs as its own process on a
    /// journal (`tca central --journal`), is killed with SIGKILL at random moments of the walks
    /// and started again at once; every walk must still reach its goal without being sent again,
    /// and the logs of all the centrals, read in order, must pass the audit.
    #[arg(long, conflicts_with = "victims")]
    kill_central: bool,
    /// Plan the next step while the current one executes (§3.3).
    #[arg(long)]
    concurrent: bool,
    /// Only kill these modules (comma-separated; default: any of the six walking modules).
    #[arg(long, value_delimiter = ',', value_name = "MODULE,...")]
    victims: Vec<String>,
    /// Obstacle course 1, 2, 3 or 4, or "random" (from --seed).
    #[arg(long, default_value = "3", conflicts_with = "terrain")]
    course: String,
    /// Walk on a terrain from an ESRI ASCII grid (.asc) file instead.
    #[arg(long, value_name = "FILE.asc")]
    terrain: Option<PathBuf>,
    /// Seed of the kills (which module, when) and of the scanner noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The Controller's speed factor (simulated time runs FACTOR times the wall clock);
    /// default: as fast as it computes.
    #[arg(long, value_name = "FACTOR")]
    speed: Option<f64>,
    /// What the planners charge to simulated time: "paper" or "measured".
    #[arg(long, value_enum, default_value_t = super::Compute::Paper)]
    compute: super::Compute,
    /// Directory for the traffic log and the modules' state.
    #[arg(long, value_name = "DIR", default_value = "out/chaos")]
    out: PathBuf,
    /// Central's zenoh endpoint (default: a free loopback port).
    #[arg(long, value_name = "ENDPOINT")]
    listen: Option<String>,
    /// Print the report as one JSON object on the last line of stdout.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(args: ChaosArgs) -> anyhow::Result<ExitCode> {
    let terrain = TerrainChoice::from_args(&args.course, args.terrain.as_deref(), args.seed)?;
    let terrain_args = match &args.terrain {
        Some(file) => vec!["--terrain".to_owned(), file.display().to_string()],
        None => vec!["--course".to_owned(), args.course.clone()],
    };
    let options = ChaosOptions {
        walks: args.walks,
        kills: args.kills,
        terrain,
        terrain_args,
        seed: args.seed,
        speed: args.speed,
        compute: args.compute.into(),
        out: args.out.clone(),
        listen: args.listen.clone(),
        exe: std::env::current_exe().context("cannot find the tca executable")?,
        victims: args.victims.clone(),
        concurrent: args.concurrent,
        kill_central: args.kill_central,
    };
    let report = tca_chaos::run(&options, |line| eprintln!("{line}")).await?;
    print!("{}", tca_chaos::summary(&report));
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    }
    Ok(if report.passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
