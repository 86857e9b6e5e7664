//! The echo module: answers [`Ping`] queries with their own payload. `tca ping` times round
//! trips to it through central.

use serde::{Deserialize, Serialize};
use tca_module::{Connector, Module, ModuleError};

/// A ping: echoed back unchanged.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Ping {
    /// Sequence number.
    pub seq: u64,
    /// Payload bytes.
    pub payload: Vec<u8>,
}
tca_messages::message!(Ping: query "tca-ping" -> Ping);

/// A one-way ping for throughput measurements.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PingGoal {
    /// Sequence number.
    pub seq: u64,
}
tca_messages::message!(PingGoal: goal "tca-ping-goal");

/// Connects an echo module named `name`. It takes the ping messages over from any earlier
/// echo (so a restarted echo, or a second `tca ping`, works without a name clash).
pub async fn connect(connector: &Connector, name: &str) -> Result<Module, ModuleError> {
    Module::builder(name)
        .capacity(1024)
        .replace(true)
        .handle(|_ctx, ping: Ping| async move { Ok(ping) })
        .handle(|_ctx, _goal: PingGoal| async move { Ok(()) })
        .connect(connector)
        .await
}
