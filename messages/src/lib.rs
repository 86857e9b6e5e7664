//! The TCA wire protocol: envelopes, message classes, data formats and the codec.
//!
//! Every message in the system, between modules and central and in the traffic log, is an
//! [`Envelope`]: a header (id, [`Class`], name, sender, task-node context, timestamp) and the
//! postcard-encoded message data. A message type declares its name and class with
//! [`message!`]; its [`DataFormat`] is derived from the type and registered with central, which
//! refuses a registration whose format differs from the one already known for the name.
//!
//! # Layout
//!
//! - [`id`]: validated [`MessageName`], [`ModuleName`] and [`MessageId`].
//! - [`class`]: the message classes of §3.2 (query, goal, command, inform, exception) and the
//!   classes that answer them (reply, success, failure, error) or control central.
//! - [`envelope`]: the [`Envelope`], task-node ids and temporal-constraint references.
//! - [`message`]: the [`Message`] trait, the [`message!`] macro and the classes as types
//!   ([`kind`]), so that sending a message as the wrong class does not compile.
//! - [`format`]: [`DataFormat`], a type's serde shape, compared field by field.
//! - `trace`: derives a [`DataFormat`] by driving the type's `Deserialize` impl.
//! - [`value`]: decoding data through a format without its Rust type (for the log viewer).
//! - `from_json`: data from JSON through a format, encoded as postcard (`tca call`, `tca send`).
//! - [`control`]: payloads of central's own `tca.*` control traffic.
//! - [`route_error`]: [`RouteError`], what central answers when it cannot route a message.
//! - [`sim_time`]: [`HandlingClock`], when a module's handlers start in simulated time.
//! - [`codec`]: the single encode/decode entry point (postcard), strict and size-limited.
//! - [`error`]: error types.

pub mod class;
pub mod codec;
pub mod control;
pub mod envelope;
pub mod error;
pub mod format;
mod from_json;
pub mod id;
pub mod message;
pub mod route_error;
pub mod sim_time;
pub mod spelling;
mod trace;
pub mod value;

pub use class::Class;
pub use codec::{
    DEFAULT_MAX_FRAME_BYTES, PROTOCOL_VERSION, decode, decode_data, encode, encode_data,
};
pub use envelope::{
    ConstraintSpec, Envelope, Failure, NodeId, PointRef, SendOptions, TaskRef, TimePoint, now_ns,
};
pub use error::{CodecError, FormatError, NameError};
pub use format::DataFormat;
pub use id::{MAX_NAME_LEN, MessageId, MessageName, ModuleName};
pub use message::{Message, class_of, kind};
pub use route_error::RouteError;
pub use sim_time::{HandlingClock, SIMULATED_TIME_BELOW_NS, is_simulated_stamp};
pub use value::Value;

#[cfg(test)]
mod codec_tests;
