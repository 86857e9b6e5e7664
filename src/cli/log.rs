//! `tca log`: reading traffic logs.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use tca_logs::{LogFile, ShowFilter};
use tca_messages::Class;

#[derive(Debug, Subcommand)]
pub(crate) enum LogCommand {
    /// Print the traffic readably, one line per message.
    Show(ShowArgs),
    /// Write a copy of the log for Foxglove: JSON-encoded (--json) or with schemas and
    /// Foxglove's well-known messages (--foxglove).
    Export(ExportArgs),
    /// Print the Figure 18 breakdown (per module: computing, waiting, idle), message counts
    /// and query latencies.
    Stats(StatsArgs),
    /// Replay a recorded walk with some modules played from the log; report the first divergence.
    Replay(super::replay::ReplayArgs),
    /// Prove from the log that no message was lost or handled twice, and that time was kept:
    /// constraints, capacity and answer stamps (exit 1 if not).
    Audit(AuditArgs),
}

#[derive(Debug, Args)]
pub(crate) struct AuditArgs {
    /// The log file (of a run that ended cleanly; a crashed central's log ends mid-flight).
    /// Several files are audited as one history, in the order given: the logs of a central
    /// restarted on its journal (`traffic.1.mcap traffic.2.mcap ... traffic.mcap`).
    #[arg(required = true, num_args = 1..)]
    file: Vec<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub(crate) struct ExportArgs {
    /// The log file.
    file: PathBuf,
    /// Where to write the JSON-encoded MCAP copy.
    #[arg(long, value_name = "OUT.mcap", required_unless_present = "foxglove")]
    json: Option<PathBuf>,
    /// Where to write the Foxglove MCAP copy: every message name a channel with a JSON schema
    /// from its registered format, plus Foxglove's well-known maps, frames, scene, images and
    /// log (see docs/foxglove.md).
    #[arg(long, value_name = "OUT.mcap")]
    foxglove: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct StatsArgs {
    /// The log file.
    file: PathBuf,
    /// Use central's clock instead of the messages' timestamps (which are simulated time
    /// when the modules ran on it).
    #[arg(long)]
    central_clock: bool,
    /// Count messages per step as deliveries divided by the number of messages of this name
    /// (default `bodyMove`: a walking step is one body move; a `planStep` that finds the
    /// carriage at the goal plans nothing).
    #[arg(long, default_value = "bodyMove")]
    step: String,
    /// Also draw the timeline (busy and waiting per module) to this PNG file.
    #[arg(long, value_name = "FILE")]
    png: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub(crate) struct ShowArgs {
    /// The log file (written by `tca central --log`).
    file: PathBuf,
    /// Only traffic from or to this module.
    #[arg(long)]
    module: Option<String>,
    /// Only this message name.
    #[arg(long)]
    name: Option<String>,
    /// Only this class (query, goal, command, inform, exception, reply, success, failure,
    /// error, control).
    #[arg(long)]
    class: Option<Class>,
    /// Print every frame in both directions.
    #[arg(long)]
    all: bool,
    /// Print the task trees instead, rebuilt from the logged tree operations.
    #[arg(long)]
    tree: bool,
    /// With --tree: as they stood this many seconds after the log's start (default: the end).
    #[arg(long, value_name = "SECONDS", requires = "tree")]
    at: Option<f64>,
}

pub(crate) async fn run(cmd: LogCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        LogCommand::Replay(args) => super::replay::run(args).await,
        LogCommand::Audit(args) => {
            let mut logs = Vec::new();
            for file in &args.file {
                logs.push(
                    LogFile::open(file)
                        .with_context(|| format!("cannot read log {}", file.display()))?,
                );
            }
            let log = LogFile::chain(logs);
            let audit = tca_logs::audit(&log);
            let time = tca_logs::time_check(&log);
            if args.json {
                let mut v = serde_json::to_value(&audit)?;
                v["time"] = serde_json::to_value(&time)?;
                println!("{v}");
            } else {
                print!("{}", audit.text());
                print!("{}", time.text());
                if let Some(t) = &log.truncated {
                    println!(
                        "note: the log ends early ({t}); messages in flight then show as lost"
                    );
                }
            }
            Ok(if audit.is_clean() && time.holds() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            })
        }
        LogCommand::Export(args) => {
            let log = LogFile::open(&args.file)
                .with_context(|| format!("cannot read log {}", args.file.display()))?;
            if let Some(out) = &args.json {
                let n = tca_logs::export_json(&log, out)
                    .with_context(|| format!("cannot write {}", out.display()))?;
                eprintln!("wrote {n} JSON messages to {}", out.display());
            }
            if let Some(out) = &args.foxglove {
                let s = tca_foxglove::export_foxglove(&log, out)?;
                let well_known: Vec<String> = s
                    .well_known
                    .iter()
                    .map(|(t, n)| format!("{t} {n}"))
                    .collect();
                eprintln!(
                    "wrote {} messages to {} ({} traffic, {} left out undecoded; well-known: {})",
                    s.messages,
                    out.display(),
                    s.traffic,
                    s.undecoded,
                    well_known.join(", ")
                );
            }
            Ok(ExitCode::SUCCESS)
        }
        LogCommand::Stats(args) => {
            let log = LogFile::open(&args.file)
                .with_context(|| format!("cannot read log {}", args.file.display()))?;
            let base = if args.central_clock {
                tca_logs::TimeBase::Central
            } else {
                tca_logs::TimeBase::Envelope
            };
            let stats = tca_logs::stats(&log, base);
            let steps = stats.by_name.get(&args.step).copied().unwrap_or(0);
            if let Some(png) = &args.png {
                tca_timeline::write_png(&stats, png)
                    .with_context(|| format!("cannot write {}", png.display()))?;
            }
            if args.json {
                let mut v = serde_json::to_value(&stats)?;
                v["steps"] = steps.into();
                v["messages_per_step"] = if steps > 0 {
                    (stats.messages as f64 / steps as f64).into()
                } else {
                    serde_json::Value::Null
                };
                println!("{v}");
            } else {
                print!("{}", tca_timeline::text(&stats, steps));
            }
            Ok(ExitCode::SUCCESS)
        }
        LogCommand::Show(args) => {
            let log = LogFile::open(&args.file)
                .with_context(|| format!("cannot read log {}", args.file.display()))?;
            if args.tree {
                let text = tca_logs::tree_at(&log, args.at).map_err(anyhow::Error::msg)?;
                println!("{text}");
                if let Some(t) = &log.truncated {
                    println!("(note: {t})");
                }
                return Ok(ExitCode::SUCCESS);
            }
            let filter = ShowFilter {
                module: args.module,
                name: args.name,
                class: args.class,
                all_frames: args.all,
            };
            use std::io::Write as _;
            let mut out = std::io::stdout().lock();
            for line in tca_logs::render(&log, &filter) {
                if writeln!(out, "{line}").is_err() {
                    break; // reader closed the pipe (e.g. `| head`)
                }
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}
