//! CG-space route planning distributed over worker modules, as on PolyBot (Eldershaw and
//! Yim, §4.2): the roadmap's A* joins between nearby cells are independent, so they run on
//! workers; each worker owns one strip of CG-space (a [`Partition`] of whole regions along
//! x), so the regions it materialises stay within its memory cap, and never materialises
//! regions of the others' strips beyond a block's half-width.
//!
//! - [`messages`]: `cgspace.join.K`, a batch of joins for worker K and their routes with
//!   the worker's counters.
//! - [`setup`]: what a worker is started with (robot, terrain, parameters, region cap).
//! - [`worker`]: the worker module `cgspace-worker-K`.
//! - [`client`]: [`DistributedJoiner`], the [`Joiner`] the planner hands to
//!   [`plan_route_batched`]; it replaces dead workers through a [`WorkerFactory`]
//!   ([`InProcessWorkers`], [`ProcessWorkers`], or [`ExternalWorkers`] for workers started
//!   elsewhere).
//!
//! ```no_run
//! # async fn run(connector: tca_module::Connector, mut space: tca_cg_space::CgSpace,
//! #     start: tca_cg_space::CgCell, goal: tca_cg_space::CgCell) -> Result<(), Box<dyn std::error::Error>> {
//! use tca_cg_space::{BatchParams, RouteParams, plan_route_batched};
//! use tca_cg_space_bus::{DistributedJoiner, InProcessWorkers, JoinerOptions};
//! use tca_module::Module;
//!
//! let planner = Module::builder("cgspace-planner").connect(&connector).await?;
//! let workers = InProcessWorkers::new(connector.clone(), &space, Some(40));
//! let mut joiner = DistributedJoiner::start(planner, 3, workers, JoinerOptions::default()).await?;
//! // The joiner blocks while the workers search: plan on a blocking thread.
//! let (route, joiner) = tokio::task::spawn_blocking(move || {
//!     let r = plan_route_batched(&mut space, &mut joiner, start, goal,
//!         &RouteParams::default(), &BatchParams::default());
//!     (r, joiner)
//! }).await?;
//! println!("{} cells, {} replacements", route?.cells.len(), joiner.stats().replacements);
//! joiner.shutdown().await;
//! # Ok(()) }
//! ```
//!
//! [`Partition`]: tca_cg_space::Partition
//! [`Joiner`]: tca_cg_space::Joiner
//! [`plan_route_batched`]: tca_cg_space::plan_route_batched

pub mod client;
pub mod messages;
pub mod setup;
pub mod worker;

pub use client::{
    DistributedJoiner, ExternalWorkers, InProcessWorkers, JoinStats, JoinerOptions, ProcessWorkers,
    WorkerFactory, WorkerHandle,
};
pub use messages::{
    JOIN_STEM, JoinBatch, JoinReply, WORKER_STEM, WorkerCounters, join_name, join_registration,
    worker_name,
};
pub use setup::{SetupError, TerrainSource, WorkerSetup};
pub use worker::{MAX_MARGIN, Worker, WorkerError, connect_worker};

#[cfg(test)]
mod distributed_tests;
