//! Command-line parsing and the subcommands.

mod bridge;
mod bus;
mod central;
mod chaos;
mod course;
mod footfall;
mod foxglove;
mod legged_walk;
mod log;
mod map;
mod module;
mod navigate;
mod ping;
mod plan;
mod realtime;
mod registry;
mod replay;
mod robot;
mod tree;
mod up;
mod walk;

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use tca_central::DEFAULT_ENDPOINT;

/// Task Control Architecture: central control, modules and the tools around them.
#[derive(Debug, Parser)]
#[command(name = "tca", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Run every thread of this process (and the processes it starts) under the kernel's
    /// real-time FIFO scheduler at this priority, 1-99, so that it keeps its timing on a
    /// loaded machine (central, a bridge, a controller). Needs CAP_SYS_NICE or an rtprio
    /// limit; a computation under it holds its core until it is done.
    #[arg(long, global = true, value_name = "PRIORITY",
          value_parser = clap::value_parser!(u8).range(1..=99))]
    realtime: Option<u8>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Walk the leg down an obstacle course (or, with --robot, a multi-legged robot across
    /// a course or terrain), autonomously, and report what happened.
    Walk(walk::WalkArgs),
    /// Run central control, serving modules over zenoh.
    Central(central::CentralArgs),
    /// Run one built-in module as its own process.
    Module(module::ModuleArgs),
    /// Start central and the modules of a launch file; Ctrl-C stops them all.
    Up(up::UpArgs),
    /// Time query round trips between two modules through central.
    Ping(ping::PingArgs),
    /// Print the registry: every registered message, its handler and data format.
    Registry(registry::RegistryArgs),
    /// Print the live task trees of a running central.
    Tree(tree::TreeArgs),
    /// Read traffic logs.
    #[command(subcommand)]
    Log(log::LogCommand),
    /// Walk with the modules as processes while killing them at random; audit the log.
    Chaos(chaos::ChaosArgs),
    /// Draw a terrain map (elevation, uncertainty, footfall, slope) to PNG, from a running
    /// system or a traffic log.
    Map(map::MapArgs),
    /// Multi-legged robot descriptions (URDF): what they say.
    #[command(subcommand)]
    Robot(robot::RobotCommand),
    /// Built-in courses for multi-legged robots: list them, write them as .asc files.
    #[command(subcommand)]
    Course(course::CourseCommand),
    /// List the modules of a running system, their messages, formats and JSON templates.
    List(bus::list::ListArgs),
    /// Print the traffic of message names as it happens, decoded.
    Echo(bus::echo::EchoArgs),
    /// Ask a query, data given as JSON; print the reply as JSON.
    Call(bus::call::CallArgs),
    /// Send a goal, command or inform, data given as JSON; print a task's outcome.
    Send(bus::send::SendArgs),
    /// Kill a task and its subtree, by node (n5) or by the id of its message (m3.7).
    Kill(bus::kill::KillArgs),
    /// Emergency stop: kill every task tree, then send the halt.
    Stop(bus::stop::StopArgs),
    /// Serve a live view of a running system to Foxglove (its WebSocket protocol): every
    /// message name, maps, frames, the robot, its plan, images and a log.
    Foxglove(foxglove::FoxgloveArgs),
    /// Plan a multi-legged robot's walk without walking it.
    #[command(subcommand)]
    Plan(plan::PlanCommand),
    /// Navigate toward a goal given relative to the start over terrain discovered on the way
    /// (depth camera, drifting odometry, danger map, D* Lite).
    Navigate(navigate::NavigateArgs),
    /// A telemetry bridge between a robot's central and its operators': messages forwarded
    /// each way with a delay, all logged; a recorded session played back.
    #[command(subcommand)]
    Bridge(bridge::BridgeCommand),
    /// FootFall for an ATHLETE-like rover: one leg's reachability and stability maps, a
    /// step planned (A* or SBL) and previewed, sent to the robot; the acceptance campaign.
    #[command(subcommand)]
    Footfall(footfall::FootfallCommand),
}

/// Where to find central (shared by the commands that connect).
#[derive(Debug, Clone, Args)]
pub(crate) struct ConnectArgs {
    /// zenoh endpoint of central, e.g. tcp/127.0.0.1:7447.
    #[arg(long, value_name = "ENDPOINT")]
    pub(crate) connect: Option<String>,
}

impl ConnectArgs {
    /// The endpoint, or the default one.
    pub(crate) fn endpoint_or_default(&self) -> String {
        self.connect
            .clone()
            .unwrap_or_else(|| DEFAULT_ENDPOINT.to_owned())
    }
}

/// What the planners' computing costs in simulated time (`--compute`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Compute {
    /// The 1990 system's planning times (§7.2).
    Paper,
    /// What the computing measures on this machine.
    Measured,
}

impl From<Compute> for tca_walk::ComputeModel {
    fn from(c: Compute) -> Self {
        match c {
            Compute::Paper => tca_walk::ComputeModel::Paper,
            Compute::Measured => tca_walk::ComputeModel::Measured,
        }
    }
}

/// Prints a walk's summary, and its report as one JSON line when given; the exit status is
/// success when the walk reached its goal, 2 when not.
pub(crate) fn finish_walk(
    summary: &str,
    json: Option<String>,
    reached: bool,
) -> anyhow::Result<ExitCode> {
    print!("{summary}");
    if let Some(line) = json {
        println!("{line}");
    }
    Ok(if reached {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}

/// Prints one progress line on stderr: rewritten in place on a terminal, one line each
/// otherwise.
pub(crate) fn progress_line(tty: bool, line: &str) {
    if tty {
        eprint!("\r{line:<100}");
    } else {
        eprintln!("{line}");
    }
}

fn init_tracing() {
    use tracing_subscriber::EnvFilter;
    let filter = EnvFilter::try_from_env("TCA_LOG")
        .or_else(|_| EnvFilter::try_from_default_env())
        // zenoh's Unix-socket link warns "Can not create a new UnixSocketStream link bound
        // to ..." for every connection it makes, because a connecting socket has no name of
        // its own (as is normal); it then carries on. Its real failures are errors.
        .unwrap_or_else(|_| EnvFilter::new("warn,zenoh_link_unixsock_stream=error"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}

/// Entry point: parses arguments, runs the command, prints errors with their causes.
pub(crate) fn main() -> ExitCode {
    let cli = Cli::parse();
    init_tracing();
    if let Some(priority) = cli.realtime
        && let Err(e) = realtime::enter(priority)
    {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    // The command runs as a task on the runtime's workers, not on this thread: a future
    // driven by `block_on` lives outside the worker pool, so every wake between it and the
    // tasks it talks to (central's driver, the modules' receive loops and handlers) would
    // cross threads. On a worker, a message and its answer mostly stay on one thread (see
    // BENCHMARKS.md, "Same-machine link", for the in-process round trip before and after).
    let command = runtime.spawn(async move {
        match cli.command {
            Command::Walk(args) => walk::run(args).await,
            Command::Chaos(args) => chaos::run(args).await,
            Command::Central(args) => central::run(args).await,
            Command::Module(args) => module::run(args).await,
            Command::Up(args) => up::run(args).await,
            Command::Ping(args) => ping::run(args).await,
            Command::Registry(args) => registry::run(args).await,
            Command::Tree(args) => tree::run(args).await,
            Command::Log(cmd) => log::run(cmd).await,
            Command::Map(args) => map::run(args).await,
            Command::Robot(cmd) => robot::run(cmd).await,
            Command::Course(cmd) => course::run(cmd).await,
            Command::List(args) => bus::list::run(args).await,
            Command::Echo(args) => bus::echo::run(args).await,
            Command::Call(args) => bus::call::run(args).await,
            Command::Send(args) => bus::send::run(args).await,
            Command::Kill(args) => bus::kill::run(args).await,
            Command::Stop(args) => bus::stop::run(args).await,
            Command::Foxglove(args) => foxglove::run(args).await,
            Command::Plan(cmd) => plan::run(cmd).await,
            Command::Navigate(args) => navigate::run_navigate(args).await,
            Command::Bridge(cmd) => bridge::run(cmd).await,
            Command::Footfall(cmd) => footfall::run(cmd).await,
        }
    });
    let result = match runtime.block_on(command) {
        Ok(result) => result,
        Err(e) if e.is_panic() => std::panic::resume_unwind(e.into_panic()),
        Err(e) => Err(anyhow::anyhow!("the command's task stopped: {e}")),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
