//! `tca robot`: what a multi-legged robot description says.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use tca_legged_model::RobotModel;
use tca_legged_view::RobotSummary;

/// `tca robot ...`.
#[derive(Debug, Subcommand)]
pub(crate) enum RobotCommand {
    /// Print a robot's legs, joints, limits, mass, standing pose and stability, and each
    /// foot's reachable workspace.
    Show(ShowArgs),
}

#[derive(Debug, Args)]
#[command(after_help = "Examples:
  tca robot show ambler
  tca robot show hexapod --png hexapod.png
  tca robot show my_robot.urdf --json")]
pub(crate) struct ShowArgs {
    /// A shipped robot (ambler, hexapod, athlete) or the path of a URDF file.
    robot: String,
    /// Also draw the robot standing, from above and from the side, to this PNG file.
    #[arg(long, value_name = "FILE")]
    png: Option<PathBuf>,
    /// Print the summary as one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(command: RobotCommand) -> anyhow::Result<ExitCode> {
    match command {
        RobotCommand::Show(args) => show(&args),
    }
}

fn show(args: &ShowArgs) -> anyhow::Result<ExitCode> {
    let robot = RobotModel::load(&args.robot)
        .with_context(|| format!("cannot load the robot {:?}", args.robot))?;
    let summary = RobotSummary::of(&robot)?;
    let mut out = if args.json {
        format!("{}\n", serde_json::to_string(&summary)?)
    } else {
        summary.to_string()
    };
    if let Some(path) = &args.png {
        tca_legged_view::draw(&robot)?
            .write_png(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        if !args.json {
            out.push_str(&format!("wrote {}\n", path.display()));
        }
    }
    print_all(&out)?;
    Ok(ExitCode::SUCCESS)
}

/// Writes `text` to stdout; a reader that stops early (`| head`) is not an error.
fn print_all(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
