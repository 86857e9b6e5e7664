//! Central's configuration.

use std::time::Duration;

use serde::{Deserialize, Serialize};

/// Limits and defaults of central. Every field has a sensible default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CentralConfig {
    /// Largest frame accepted, in bytes.
    pub max_frame_bytes: usize,
    /// Most messages that may wait in central for one module while it is down.
    pub max_waiting: u32,
    /// Longest a message waits for a module that is down before its sender gets an error.
    #[serde(with = "duration_ms")]
    pub max_wait: Duration,
    /// Goals/commands a module handles at once when its hello says 0.
    pub default_capacity: u32,
}

impl Default for CentralConfig {
    fn default() -> Self {
        CentralConfig {
            max_frame_bytes: tca_messages::DEFAULT_MAX_FRAME_BYTES,
            max_waiting: 1024,
            max_wait: Duration::from_secs(60),
            default_capacity: 1,
        }
    }
}

mod duration_ms {
    use serde::{Deserialize, Deserializer, Serializer};
    use std::time::Duration;

    pub(super) fn serialize<S: Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(d.as_millis() as u64)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Duration, D::Error> {
        Ok(Duration::from_millis(u64::deserialize(d)?))
    }
}
