//! How records map onto MCAP: channel names, schema and message encodings.
//!
//! - Each message name gets a channel whose topic is the name. Its schema (encoding
//!   [`FORMAT_SCHEMA_ENCODING`]) is a JSON object `{"class": ..., "format": DataFormat,
//!   "reply": DataFormat|null}` holding the format registered for the name, or `{}` for traffic
//!   logged before any registration. The channel's message encoding is [`FRAME_ENCODING`]: each
//!   message is the postcard encoding of a [`crate::FrameRecord`], whose `frame` field is the
//!   exact wire frame (protocol version byte + postcard envelope, whose `data` is the message's
//!   postcard bytes). When a name is registered after traffic was logged, a new channel with the
//!   same topic and the new schema takes over.
//! - Link events, registrations, task-tree operations and problems go to the channels
//!   [`LINK_TOPIC`], [`REGISTERED_TOPIC`], [`TREE_TOPIC`] and [`PROBLEM_TOPIC`], postcard-encoded
//!   ([`RECORD_ENCODING`]), each with the data format of its record type as schema.

/// Schema encoding of the tca data formats (JSON of `tca_messages::DataFormat`).
pub const FORMAT_SCHEMA_ENCODING: &str = "tca-format+json";
/// Message encoding of frame channels.
pub const FRAME_ENCODING: &str = "tca-frame+postcard";
/// Message encoding of the record channels.
pub const RECORD_ENCODING: &str = "postcard";
/// Link events.
pub const LINK_TOPIC: &str = "tca.log.link";
/// Registrations.
pub const REGISTERED_TOPIC: &str = "tca.log.registered";
/// Task-tree operations.
pub const TREE_TOPIC: &str = "tca.log.tree";
/// Problems with bad input.
pub const PROBLEM_TOPIC: &str = "tca.log.problem";
/// MCAP profile name.
pub const PROFILE: &str = "tca";
