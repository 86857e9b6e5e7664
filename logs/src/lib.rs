//! The TCA traffic log (§3.1, §3.3 of the report: "the ability to log all message traffic has
//! proven invaluable in detecting timing problems and interface errors").
//!
//! Central records every frame in and out, every link event and registration, every task-tree
//! operation and every problem with bad input, in an MCAP file (see [`layout`] for the mapping).
//! A log survives `kill -9` of central: the writer flushes every 50 ms, and the reader reads a
//! file cut short up to its last complete record.
//!
//! # Layout
//!
//! - [`record`]: the record types central produces.
//! - [`layout`]: how records map onto MCAP channels, schemas and encodings.
//! - [`writer`]: [`LogWriter`] (MCAP).
//! - [`sink`]: [`LogSink`], the writer on its own thread.
//! - [`reader`]: [`LogFile`], reading a log back (lenient about a truncated tail).
//! - [`show`]: rendering a log as readable lines with filters.
//! - [`stats`]: the Figure 18 breakdown (computing, waiting, idle per module), latencies.
//! - [`export`]: a JSON-encoded copy of a log for Foxglove Studio.
//! - [`script`]: what one module did in a recorded run, as a script to play it back.
//! - [`audit`](mod@audit): lost and doubly handled messages, proved from the log.
//! - [`timecheck`]: constraints, capacity and answer stamps held in time, proved from the log.
//! - [`compare`](mod@compare): comparing what modules sent in two runs, field by field (`tca log replay`).
//! - [`error`][]: [`LogError`].

pub mod audit;
pub mod compare;
pub mod error;
pub mod export;
pub mod layout;
pub mod reader;
pub mod record;
pub mod script;
pub mod show;
pub mod sink;
pub mod stats;
pub mod timecheck;
pub mod writer;

pub use audit::{Audit, audit};
pub use compare::{Comparison, Difference, Divergence, Rules, Side, compare};
pub use error::{LogError, Result};
pub use export::export_json;
pub use reader::{KnownFormat, LogFile};
pub use record::{
    Direction, FrameRecord, LinkEvent, LinkRecord, LogRecord, ProblemRecord, RecordKind,
    RegisteredRecord, TreeRecord,
};
pub use script::{ModuleScript, RootTask, connection_order, module_script, root_tasks};
pub use show::{ShowFilter, render, tree_at};
pub use sink::LogSink;
pub use stats::{LogStats, ModuleStats, QueryStats, Span, TimeBase, stats};
pub use timecheck::{TimeCheck, time_check};
pub use writer::{FLUSH_INTERVAL, LogWriter, aside_name, set_aside};
