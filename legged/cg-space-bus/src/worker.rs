//! A worker: one part of CG-space (a strip of the [`Partition`]), lazily built under a region
//! cap, answering the A* joins its strip owns.

use std::collections::BTreeSet;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

use tca_cg_space::{CgCell, CgSpace, Partition, astar, fingerprint};
use tca_messages::{decode_data, encode_data};
use tca_module::{Connector, HandlerError, Module, ModuleError};
use thiserror::Error;

use crate::messages::{JoinBatch, JoinReply, WorkerCounters, join_registration, worker_name};

/// The widest block margin a worker accepts, cells (the roadmap's default is 3).
pub const MAX_MARGIN: i32 = 64;

/// Why a worker refused a batch.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum WorkerError {
    /// The planner's space is not the worker's.
    #[error(
        "worker {index} was set up for another robot, terrain or CG-space parameters (fingerprint {mine:#018x}, the planner's {theirs:#018x}); start it with the planner's --robot, --terrain and --seed"
    )]
    Fingerprint {
        /// The worker.
        index: usize,
        /// Its fingerprint.
        mine: u64,
        /// The planner's.
        theirs: u64,
    },
    /// The batch is for another number of workers than this worker can be one of.
    #[error("worker {index} cannot be one of {workers} workers: {reason}")]
    Workers {
        /// The worker.
        index: usize,
        /// The planner's number of workers.
        workers: u32,
        /// Why.
        reason: String,
    },
    /// A query lies outside the map, has a margin out of range, or belongs to another
    /// worker's strip.
    #[error("worker {index} refuses query {query}: {reason}")]
    Query {
        /// The worker.
        index: usize,
        /// The query's position in the batch.
        query: usize,
        /// Why.
        reason: String,
    },
}

/// A worker's state: its space and what it has done.
#[derive(Debug)]
pub struct Worker {
    index: usize,
    space: CgSpace,
    region_cap: Option<usize>,
    fingerprint: u64,
    marks: BTreeSet<CgCell>,
    counters: WorkerCounters,
    /// Cells evaluated and regions materialised by spaces dropped when the marks were reset.
    earlier: (u64, u64),
}

impl Worker {
    /// Worker `index` over `space` (built for the planner's robot and terrain), holding at
    /// most `region_cap` regions at once.
    pub fn new(index: usize, space: CgSpace, region_cap: Option<usize>) -> Self {
        let space = Self::fresh(&space, region_cap);
        Worker {
            index,
            fingerprint: fingerprint(&space),
            space,
            region_cap,
            marks: BTreeSet::new(),
            counters: WorkerCounters {
                region_cap: region_cap.unwrap_or(0) as u64,
                ..WorkerCounters::default()
            },
            earlier: (0, 0),
        }
    }

    /// An empty space over the same robot, grid and foot map.
    fn fresh(space: &CgSpace, region_cap: Option<usize>) -> CgSpace {
        CgSpace::with_foot_map(space.robot().clone(), *space.grid(), space.foot_shared())
            .with_region_cap(region_cap)
    }

    /// The worker's index.
    pub fn index(&self) -> usize {
        self.index
    }

    /// Its space's fingerprint.
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }

    /// What it has done so far.
    pub fn counters(&self) -> WorkerCounters {
        let mut c = self.counters;
        c.cells_evaluated = self.earlier.0 + self.space.evaluations();
        c.regions_materialised = self.earlier.1 + self.space.regions_materialised();
        c.regions_held = self.space.regions_held() as u64;
        c
    }

    /// Checks a batch and answers it: every query searched in this worker's space, in order.
    pub fn answer(&mut self, batch: &JoinBatch) -> Result<JoinReply, WorkerError> {
        self.check(batch)?;
        self.sync_marks(&batch.marked);
        let began = Instant::now();
        let mut routes = Vec::with_capacity(batch.queries.len());
        for q in &batch.queries {
            let found = astar(&mut self.space, q.from, q.to, q.block());
            self.counters.searches += 1;
            self.counters.cells_expanded += found.expanded as u64;
            routes.push(found.route);
        }
        self.counters.batches += 1;
        self.counters.busy_us += began.elapsed().as_micros() as u64;
        Ok(JoinReply {
            routes,
            counters: self.counters(),
        })
    }

    fn check(&self, batch: &JoinBatch) -> Result<(), WorkerError> {
        let index = self.index;
        if batch.fingerprint != self.fingerprint {
            return Err(WorkerError::Fingerprint {
                index,
                mine: self.fingerprint,
                theirs: batch.fingerprint,
            });
        }
        let grid = *self.space.grid();
        let workers = batch.workers;
        let partition =
            Partition::new(&grid, workers as usize).map_err(|e| WorkerError::Workers {
                index,
                workers,
                reason: e.to_string(),
            })?;
        if index >= workers as usize {
            return Err(WorkerError::Workers {
                index,
                workers,
                reason: format!("its index is {index}; give indices 0 to {}", workers - 1),
            });
        }
        for (i, q) in batch.queries.iter().enumerate() {
            let refuse = |reason: String| WorkerError::Query {
                index,
                query: i,
                reason,
            };
            for c in [q.from, q.to] {
                if !grid.contains(c) {
                    return Err(refuse(format!(
                        "cell ({}, {}, {}) is outside the {} x {} x {} grid",
                        c.ix, c.iy, c.it, grid.nx, grid.ny, grid.theta_bins
                    )));
                }
            }
            if !(0..=MAX_MARGIN).contains(&q.margin) {
                return Err(refuse(format!(
                    "block margin {} is outside 0..={MAX_MARGIN}",
                    q.margin
                )));
            }
            let owner = partition.owner(q);
            if owner != index {
                return Err(refuse(format!(
                    "it belongs to worker {owner}'s strip (columns {:?})",
                    partition.strip(owner)
                )));
            }
        }
        Ok(())
    }

    /// Marks what the planner marked. Marks only grow while a planner replans; if the
    /// planner's set is not a superset of this worker's (another planning began), the space
    /// starts afresh.
    fn sync_marks(&mut self, marked: &[CgCell]) {
        let wanted: BTreeSet<CgCell> = marked.iter().copied().collect();
        if !self.marks.is_subset(&wanted) {
            self.earlier.0 += self.space.evaluations();
            self.earlier.1 += self.space.regions_materialised();
            self.space = Self::fresh(&self.space, self.region_cap);
            self.marks.clear();
        }
        for c in wanted.difference(&self.marks).copied().collect::<Vec<_>>() {
            self.space.mark_invalid(c);
            self.marks.insert(c);
        }
    }
}

/// Connects worker `index` as module `cgspace-worker-INDEX`, answering `cgspace.join.INDEX`
/// in `space` (the planner's robot and terrain) with at most `region_cap` regions held.
/// Searches run on tokio's blocking threads, one batch at a time.
pub async fn connect_worker(
    connector: &Connector,
    index: usize,
    space: CgSpace,
    region_cap: Option<usize>,
) -> Result<Module, ModuleError> {
    let worker = Arc::new(Mutex::new(Worker::new(index, space, region_cap)));
    let registration = join_registration(index)?;
    Module::builder(worker_name(index))
        .handle_raw(registration, move |_ctx, data: Vec<u8>| {
            let worker = worker.clone();
            async move {
                let batch: JoinBatch = decode_data(&data).map_err(|e| {
                    HandlerError::new(format!("a join batch that does not decode: {e}"))
                })?;
                let reply = tokio::task::spawn_blocking(move || {
                    worker
                        .lock()
                        .unwrap_or_else(PoisonError::into_inner)
                        .answer(&batch)
                })
                .await
                .map_err(|e| HandlerError::new(format!("the search stopped: {e}")))??;
                tracing::debug!(
                    index,
                    queries = reply.routes.len(),
                    evaluated = reply.counters.cells_evaluated,
                    held = reply.counters.regions_held,
                    "joins answered"
                );
                encode_data(&reply).map_err(|e| HandlerError::new(e.to_string()))
            }
        })
        .connect(connector)
        .await
}
