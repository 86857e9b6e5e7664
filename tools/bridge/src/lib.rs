//! A telemetry bridge between two centrals: the robot's (its Controller and sensors) and the
//! operators' far away (their tools and planners). It forwards the messages a bridge file
//! names each way, holding each back by that way's delay (commands up, telemetry down:
//! light time to the Moon is 1.3 s), logs everything that crosses, and plays a recorded
//! session back to a ground side.
//!
//! ```no_run
//! use std::time::Duration;
//! use tca_bridge::{BridgeConfig, NamePattern, start};
//! use tca_module::Connector;
//!
//! # async fn run() -> Result<(), tca_bridge::BridgeError> {
//! let mut config = BridgeConfig::new(
//!     Connector::endpoint("tcp/127.0.0.1:7447"), // the robot's central
//!     Connector::endpoint("tcp/127.0.0.1:7448"), // the ground's
//! );
//! config.up.delay = Duration::from_millis(1300);
//! config.up.messages = vec![NamePattern::parse("legged.legMove").unwrap()];
//! config.down.delay = Duration::from_millis(1300);
//! config.down.messages = vec![NamePattern::parse("legged.telemetry").unwrap()];
//! config.log = Some("out/bridge.mcap".into());
//! let bridge = start(config).await?;
//! // ... the ground side sends legged.legMove: it reaches the robot 1.3 s later, and its
//! // outcome comes back 1.3 s after it ended there.
//! let summary = bridge.stop().await;
//! # Ok(()) }
//! ```
//!
//! For the modules of each side the other side's messages are there like their own: the
//! bridge registers them with their handlers' formats, and a goal or command sent across
//! ends on the side it was sent as it ended on the other (its exceptions raised on the way
//! too). A query across waits at most twice the delay plus its own timeout; see
//! [`forward`] for every class, and for what happens when a central or the bridge dies.
//!
//! # Layout
//!
//! - [`side`]: [`Side`] (robot, ground) and [`Direction`] (up, down).
//! - [`file`]: the bridge file ([`BridgeFile`]) and the checked [`BridgeConfig`].
//! - [`select`]: what each way's names select in the handling side's registry.
//! - [`crossing`]: what crosses, and the delay lines.
//! - [`bridge`]: [`start`] and the [`RunningBridge`].
//! - [`forward`]: forwarding, class by class, on both sides.
//! - [`log`]: writing the bridge's log; [`recorded`]: reading it back ([`Recorded`]).
//! - [`stats`]: measured delays against the setting ([`DelayStats`]);
//!   [`end_to_end`](mod@end_to_end): the same from the two centrals' logs.
//! - [`playback`]: a recorded session played back to a ground side ([`play`]).
//! - [`error`]: the errors, [`BridgeError`].

pub mod bridge;
pub mod crossing;
pub mod end_to_end;
pub mod error;
pub mod file;
pub mod forward;
pub mod log;
pub mod playback;
pub mod recorded;
pub mod select;
pub mod side;
pub mod stats;
pub mod worst;

pub use bridge::{CAPACITY, Carry, RunningBridge, Summary, start};
pub use crossing::crossing_id;
pub use end_to_end::{end_to_end, worst_between};
pub use error::{BridgeError, Result};
pub use file::{BridgeConfig, BridgeFile, DEFAULT_NAME, NamePattern, WayConfig};
pub use log::Settings;
pub use playback::{PlaybackOptions, PlaybackReport, play};
pub use recorded::{Recorded, RecordedCrossing};
pub use select::Forwarded;
pub use side::{Direction, Side};
pub use stats::DelayStats;
pub use worst::LateCrossing;

#[cfg(test)]
mod bridge_tests;
