//! The `tca` command's library: the pieces the command assembles, shared with the
//! whole-system tests and benchmarks.
//!
//! # Layout
//!
//! - [`builtin`]: modules built into the command (`tca module NAME`): the echo used by
//!   `tca ping`.
//! - [`chaos`]: `tca chaos`: walks while modules are killed and restarted, audited.
//! - [`launch`]: launch files for `tca up`.
//! - [`load`]: load on central: many modules exchanging queries, goals and informs, every
//!   message accounted for (the load benchmark and its CI check).
//! - [`map`]: `tca map`: map pictures from a running system or a traffic log.
//! - [`ping`]: timing query round trips through central.
//! - [`replay`]: `tca log replay`: a recorded walk run again with modules played from its log.
//! - [`timeline`]: the per-module timeline of Figure 18, as text and PNG.
//! - [`walk`]: `tca walk`: the walking system assembled, walked, and reported.

pub mod builtin;
pub mod chaos;
pub mod launch;
pub mod load;
pub mod map;
pub mod ping;
pub mod replay;
pub mod timeline;
pub mod walk;

/// The allocator of every program built on this crate (the `tca` command, its tests, benches
/// and examples). Central and the modules allocate small buffers for every envelope and log
/// record; mimalloc's thread-local free lists cut that cost by about a third against glibc's
/// malloc on the goal-throughput path (see BENCHMARKS.md).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
