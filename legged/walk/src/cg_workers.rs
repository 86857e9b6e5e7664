//! CG-space workers for a walk: the route's roadmap joins run on worker modules, each owning
//! a strip of CG-space, as the paper's PolyBot planner handed regions to its modules.
//!
//! The walking module starts them when it connects and stops them when it closes. Each plan
//! asks its joins as the planning handler's own queries, so that on central's simulated
//! clock the handler counts as waiting for them while the workers (wall-clock modules)
//! answer in parallel.

use std::path::PathBuf;

use tca_cg_space::{CgParams, CgSpace, JoinError};
use tca_cg_space_bus::{DistributedJoiner, InProcessWorkers, JoinerOptions, ProcessWorkers};
use tca_module::{Connector, Module, ModuleError};

/// Worker modules for a walk's CG-space planner.
#[derive(Debug, Clone, PartialEq)]
pub struct CgWorkers {
    /// How many (each owns one strip of CG-space).
    pub count: usize,
    /// How they are started.
    pub start: CgWorkerStart,
}

/// How a walk's CG-space workers are started.
#[derive(Debug, Clone, PartialEq)]
pub enum CgWorkerStart {
    /// As modules in this process, on the walking module's central, each with its own
    /// CG-space holding at most `region_cap` regions.
    InProcess {
        /// Most regions a worker holds (`None`: no cap).
        region_cap: Option<usize>,
    },
    /// As processes: `program args... --cg-params JSON --index K` for worker K, where `args`
    /// make it a worker on the walk's central with the walk's robot and terrain (for the
    /// `tca` binary: `module cgspace-worker --connect ENDPOINT --robot R --terrain T --seed
    /// S [--region-cap C]`). The CG-space layout is the planner's, added here.
    Processes {
        /// The program.
        program: PathBuf,
        /// Its arguments before `--cg-params` and `--index`.
        args: Vec<String>,
    },
}

/// Starts the workers and the joiner that hands them the joins; returns when every worker
/// has registered with central. `space` gives in-process workers their robot tables, grid
/// and foot map; `cg` is the layout process workers build theirs with.
pub async fn start(
    connector: &Connector,
    walker: &str,
    workers: &CgWorkers,
    space: &CgSpace,
    cg: &CgParams,
) -> Result<DistributedJoiner, ModuleError> {
    let failed = |e: JoinError| {
        ModuleError::Config(format!(
            "the CG-space planner's {} workers: {e}",
            workers.count
        ))
    };
    let planner = Module::builder(format!("{walker}-cgspace-planner"))
        .connect(connector)
        .await?;
    let options = JoinerOptions::default();
    match &workers.start {
        CgWorkerStart::InProcess { region_cap } => {
            let factory = InProcessWorkers::new(connector.clone(), space, *region_cap);
            DistributedJoiner::start(planner, workers.count, factory, options)
                .await
                .map_err(failed)
        }
        CgWorkerStart::Processes { program, args } => {
            let layout = serde_json::to_string(cg).map_err(|e| {
                ModuleError::Config(format!("the CG-space layout cannot be written: {e}"))
            })?;
            let mut args = args.clone();
            args.extend(["--cg-params".to_owned(), layout]);
            let factory = ProcessWorkers::new(program.clone(), args);
            DistributedJoiner::start(planner, workers.count, factory, options)
                .await
                .map_err(failed)
        }
    }
}
