//! `tca course`: the built-in courses for multi-legged robots.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};
use tca_legged_courses::{Course, write_course};

/// `tca course ...`.
#[derive(Debug, Subcommand)]
pub(crate) enum CourseCommand {
    /// List the built-in courses: extent, cell, start, goal and the robot each suits.
    List(ListArgs),
    /// Write a built-in course's terrain as an ESRI ASCII grid (.asc).
    #[command(after_help = "Example:
  tca course write boulders boulders.asc --seed 3
  tca walk --robot ambler --terrain boulders.asc --start 3,0 --goal 23,0")]
    Write(WriteArgs),
}

#[derive(Debug, Args)]
pub(crate) struct ListArgs {
    /// Seed of the random courses.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

#[derive(Debug, Args)]
pub(crate) struct WriteArgs {
    /// The course (one of `tca course list`).
    name: String,
    /// The file to write.
    file: PathBuf,
    /// Seed of the random courses.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub(crate) async fn run(command: CourseCommand) -> anyhow::Result<ExitCode> {
    match command {
        CourseCommand::List(args) => {
            for course in Course::ALL {
                let c = course
                    .build(args.seed)
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
                let (lo, hi) = c.terrain.extent();
                println!(
                    "{:<14} for {:<8} X {:.1}..{:.1} m, Y {:.1}..{:.1} m, heights {:.2}..{:.2} m; start ({:.2}, {:.2}), goal ({:.2}, {:.2})",
                    c.name,
                    c.robot_hint,
                    lo.x,
                    hi.x,
                    lo.y,
                    hi.y,
                    c.terrain.min_height_m(),
                    c.terrain.max_height_m(),
                    c.start.x_m,
                    c.start.y_m,
                    c.goal.x,
                    c.goal.y
                );
            }
            Ok(ExitCode::SUCCESS)
        }
        CourseCommand::Write(args) => {
            let c = write_course(&args.name, args.seed, &args.file)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            println!(
                "wrote {} (course {}, seed {}): start ({:.2}, {:.2}), goal ({:.2}, {:.2})",
                args.file.display(),
                c.name,
                c.seed,
                c.start.x_m,
                c.start.y_m,
                c.goal.x,
                c.goal.y
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}
