//! `tca log replay`: a recorded walk run again with some modules played from the log
//! (see `tca_walk::replay` and `tca_replay`).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use tca_walk::TerrainChoice;
use tca_walk::{WalkReplayOptions, replay_walk};

#[derive(Debug, Args)]
pub(crate) struct ReplayArgs {
    /// The recorded traffic log (`tca walk --out DIR` writes DIR/traffic.mcap).
    file: PathBuf,
    /// Modules to play from the log, comma-separated (e.g. controller,ism); the other walking
    /// modules run live.
    #[arg(
        long = "as",
        value_name = "MODULES",
        value_delimiter = ',',
        required = true
    )]
    stand_ins: Vec<String>,
    /// Run the Gait Planner with these parameters (the format of gait.toml).
    #[arg(long, value_name = "FILE.toml")]
    gait_params: Option<PathBuf>,
    /// The recorded course (1-4 or random), needed only when the Controller or ISM runs live.
    #[arg(long, conflicts_with = "terrain")]
    course: Option<String>,
    /// The recorded terrain file, needed only when the Controller or ISM runs live.
    #[arg(long, value_name = "FILE.asc")]
    terrain: Option<PathBuf>,
    /// The recorded seed (random course and scanner noise), for a live Controller or ISM.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// What the live planners' computing costs in simulated time, as in `tca walk --compute`
    /// (only the stamps depend on it, not the data compared).
    #[arg(long, value_enum, default_value_t = super::Compute::Paper)]
    compute: super::Compute,
    /// Keep the replay's own traffic log in DIR/traffic.mcap.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Give up on a replayed goal after this many wall-clock seconds (default: 20 times its
    /// recorded wall time, at least 30 s).
    #[arg(long, value_name = "SECONDS")]
    timeout: Option<u64>,
    /// Print the report as one JSON object on the last line of stdout.
    #[arg(long)]
    json: bool,
}

/// Exit status: 0 all match, 1 divergence, 2 the log cannot be replayed (the error is
/// printed here, not passed up, so that it keeps its own status).
pub(crate) async fn run(args: ReplayArgs) -> anyhow::Result<ExitCode> {
    let terrain = match (&args.terrain, args.course.as_deref()) {
        (None, None) => None,
        (file, course) => {
            match TerrainChoice::from_args(course.unwrap_or("3"), file.as_deref(), args.seed) {
                Ok(t) => Some(t),
                Err(e) => {
                    eprintln!("error: {e}");
                    return Ok(ExitCode::from(2));
                }
            }
        }
    };
    let options = WalkReplayOptions {
        log: args.file,
        stand_ins: args.stand_ins,
        gait_params: args.gait_params,
        terrain,
        seed: args.seed,
        compute: args.compute.into(),
        out: args.out,
        goal_timeout: args.timeout.map(|t| Duration::from_secs(t.max(1))),
    };
    let report = match replay_walk(&options).await {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: cannot replay: {}", causes(&e));
            return Ok(ExitCode::from(2));
        }
    };
    print!("{}", report.text());
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    }
    Ok(if report.all_match {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The error and its causes, each cause said once (some errors repeat their source).
fn causes(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text += ": ";
            text += &c;
        }
    }
    text
}
