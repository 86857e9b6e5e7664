//! What central records: every frame in and out, link events, registrations, task-tree
//! operations and problems with bad input.

use bytes::Bytes;
use serde::{Deserialize, Serialize};
use tca_messages::control::Registration;
use tca_messages::{Class, MessageName, ModuleName};

/// Which way a frame went, seen from central.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Direction {
    /// From a module to central.
    In,
    /// From central to a module.
    Out,
}

/// One log record with central's time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogRecord {
    /// When central handled it: nanoseconds since the UNIX epoch.
    pub at_ns: u64,
    /// What happened.
    pub kind: RecordKind,
}

/// What a record holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum RecordKind {
    /// A frame that passed through central.
    Frame(FrameRecord),
    /// A link opened, closed or was refused.
    Link(LinkRecord),
    /// A module registered a message.
    Registered(RegisteredRecord),
    /// A task-tree operation (replayable: see `tca_task_tree::TaskTree::apply`).
    Tree(TreeRecord),
    /// Bad input or a refused request.
    Problem(ProblemRecord),
}

/// A frame in or out. `frame` is the exact wire frame (version byte and postcard envelope).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// In or out.
    pub direction: Direction,
    /// The link it travelled on.
    pub link: u32,
    /// The module at the other end of the link, if known.
    pub peer: Option<ModuleName>,
    /// The message name (the log channel).
    pub name: MessageName,
    /// The class.
    pub class: Class,
    /// The frame bytes.
    #[serde(with = "bytes_serde")]
    pub frame: Bytes,
}

/// Link life-cycle events.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LinkEvent {
    /// A transport link opened.
    Opened,
    /// A module said hello and was accepted.
    Connected,
    /// A module's hello was refused.
    Refused,
    /// The link closed (module left or crashed).
    Closed,
}

/// A link event.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LinkRecord {
    /// Link number.
    pub link: u32,
    /// The event.
    pub event: LinkEvent,
    /// The module, once known.
    pub module: Option<ModuleName>,
    /// Details (refusal reason, pid and host).
    pub detail: String,
}

/// An accepted registration, with its data format (the log viewer decodes data with it).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegisteredRecord {
    /// The module.
    pub module: ModuleName,
    /// What it registered.
    pub registration: Registration,
}

/// A task-tree operation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TreeRecord {
    /// The operation, replayable into a fresh tree.
    pub op: tca_task_tree::TreeOp,
    /// The message that caused it, if any, as `(link, seq)` of its id.
    pub message: Option<u64>,
}

/// Bad input or a refusal.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ProblemRecord {
    /// Link it came on, if any.
    pub link: Option<u32>,
    /// Module, if known.
    pub module: Option<ModuleName>,
    /// What was wrong.
    pub error: String,
    /// The first bytes of the offending frame, if any (at most 64).
    pub frame_prefix: Vec<u8>,
}

/// `bytes::Bytes` (de)serialized as a byte string (for `#[serde(with = ...)]`): compact in
/// postcard, where the default would be a sequence of numbers.
pub mod bytes_serde {
    use bytes::Bytes;
    use serde::{Deserializer, Serializer};

    /// Serializes `v` as a byte string.
    pub fn serialize<S: Serializer>(v: &Bytes, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(v)
    }

    /// Deserializes a byte string.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Bytes, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Bytes;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a byte string")
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<Bytes, E> {
                Ok(Bytes::copy_from_slice(v))
            }
            fn visit_byte_buf<E: serde::de::Error>(self, v: Vec<u8>) -> Result<Bytes, E> {
                Ok(Bytes::from(v))
            }
        }
        d.deserialize_byte_buf(V)
    }
}
