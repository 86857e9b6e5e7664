//! Timing query round trips through central: the echo module and the pinger (`tca ping`),
//! after zenoh's `z_ping`/`z_pong` pair (warm-up, then `n` timed queries).
//!
//! # Layout
//!
//! - [`echo`]: the echo module, answering [`Ping`] queries with their own payload (and taking
//!   [`PingGoal`]s, for throughput).
//! - [`ping`](mod@ping): connects an echo and a pinger, times `n` round trips, and summarises
//!   them ([`PingReport`]).

pub mod echo;
pub mod ping;

pub use echo::{Ping, PingGoal};
pub use ping::{PingReport, report, run, run_target};
