//! The workers' messages: one query per worker, `cgspace.join.K`, carrying a batch of A*
//! joins and answering their routes with the worker's counters.
//!
//! Central routes a message name to exactly one module, and the planner must address the
//! worker that owns each part of CG-space; so worker K registers its own name,
//! `cgspace.join.K` (all with the same data format), as module `cgspace-worker-K`. A worker
//! that comes back under the same module name gets whatever waited for it in central.

use serde::{Deserialize, Serialize};
use tca_cg_space::{CgCell, JoinQuery};
use tca_messages::control::Registration;
use tca_messages::{Class, DataFormat, MessageName};

/// The query names' stem: worker K answers `cgspace.join.K`.
pub const JOIN_STEM: &str = "cgspace.join";

/// The worker modules' name stem: worker K is `cgspace-worker-K`.
pub const WORKER_STEM: &str = "cgspace-worker";

/// The query worker `index` answers.
pub fn join_name(index: usize) -> String {
    format!("{JOIN_STEM}.{index}")
}

/// Worker `index`'s module name.
pub fn worker_name(index: usize) -> String {
    format!("{WORKER_STEM}-{index}")
}

/// Query `cgspace.join.K`: a batch of A* joins for worker K, all owned by its strip.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct JoinBatch {
    /// The planner's space's [`fingerprint`](tca_cg_space::fingerprint): the worker
    /// answers only if its own space has the same (same robot tables, grid and foot map).
    pub fingerprint: u64,
    /// How many workers share the space: the worker checks that it owns every query
    /// ([`Partition`](tca_cg_space::Partition) of this many strips).
    pub workers: u32,
    /// Every cell the planner has marked invalid (sorted): the worker marks them too.
    pub marked: Vec<CgCell>,
    /// The searches, answered in this order.
    pub queries: Vec<JoinQuery>,
}

/// What a worker has done since it started.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct WorkerCounters {
    /// CG cells evaluated (a cell of a region dropped under the cap and needed again counts
    /// again).
    pub cells_evaluated: u64,
    /// Regions materialised (allocated), counting those materialised again after a drop.
    pub regions_materialised: u64,
    /// Regions held when the batch was answered (at most the cap).
    pub regions_held: u64,
    /// The region cap (0: none).
    pub region_cap: u64,
    /// A* searches run.
    pub searches: u64,
    /// Cells A* took off its open lists.
    pub cells_expanded: u64,
    /// Batches answered.
    pub batches: u64,
    /// Time spent searching, microseconds.
    pub busy_us: u64,
}

/// The reply to [`JoinBatch`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct JoinReply {
    /// One entry per query, in order: the route (both ends included) or `None`.
    pub routes: Vec<Option<Vec<CgCell>>>,
    /// The worker's counters after the batch.
    pub counters: WorkerCounters,
}

/// The registration of `cgspace.join.K`: a query of [`JoinBatch`] answered by [`JoinReply`].
pub fn join_registration(index: usize) -> Result<Registration, tca_messages::FormatError> {
    let name = MessageName::new(join_name(index))
        .map_err(|e| tca_messages::FormatError::Invalid(e.to_string()))?;
    Ok(Registration {
        name,
        class: Class::Query,
        format: DataFormat::of::<JoinBatch>()?,
        reply: Some(DataFormat::of::<JoinReply>()?),
        replace: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_formats() {
        assert_eq!(join_name(3), "cgspace.join.3");
        assert_eq!(worker_name(0), "cgspace-worker-0");
        let r = join_registration(12).unwrap();
        assert_eq!(r.name.as_str(), "cgspace.join.12");
        assert_eq!(r.class, Class::Query);
        assert!(r.reply.is_some());
        let batch = JoinBatch {
            fingerprint: 7,
            workers: 3,
            marked: vec![CgCell::new(1, 2, 3)],
            queries: vec![JoinQuery::new(
                CgCell::new(0, 0, 0),
                CgCell::new(4, 5, 1),
                3,
            )],
        };
        let bytes = tca_messages::encode_data(&batch).unwrap();
        let back: JoinBatch = tca_messages::decode_data(&bytes).unwrap();
        assert_eq!(back, batch);
    }
}
