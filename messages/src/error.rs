//! Errors of the wire protocol.

use thiserror::Error;

/// A name that is not a valid module or message name.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum NameError {
    /// The name is empty.
    #[error("a {kind} must not be empty")]
    Empty {
        /// Which kind of name.
        kind: &'static str,
    },
    /// The name is longer than [`crate::MAX_NAME_LEN`].
    #[error("a {kind} is at most 128 bytes long; this one has {len}")]
    TooLong {
        /// Which kind of name.
        kind: &'static str,
        /// Its length in bytes.
        len: usize,
    },
    /// The name holds a character outside letters, digits, `_`, `-` and `.`.
    #[error("{kind} {name:?} holds {bad:?}; use only ASCII letters, digits, '_', '-' and '.'")]
    BadChar {
        /// Which kind of name.
        kind: &'static str,
        /// The offending name.
        name: String,
        /// The first bad character.
        bad: char,
    },
}

/// Why a frame could not be encoded or decoded.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum CodecError {
    /// The frame is empty.
    #[error("empty frame: a frame starts with the protocol version byte")]
    Empty,
    /// The frame is larger than the configured limit.
    #[error(
        "frame of {size} bytes exceeds the limit of {limit} bytes; send smaller data or raise the limit (max_frame_bytes)"
    )]
    TooLarge {
        /// The frame's size.
        size: usize,
        /// The limit.
        limit: usize,
    },
    /// The sender speaks another protocol version.
    #[error(
        "protocol version {found} is not supported (this build speaks {expected}); run the same tca version on both sides"
    )]
    Version {
        /// Version in the frame.
        found: u8,
        /// Version of this build.
        expected: u8,
    },
    /// The bytes do not decode as the expected type.
    #[error("malformed {what}: {reason}")]
    Malformed {
        /// What was being decoded.
        what: &'static str,
        /// The decoder's explanation.
        reason: String,
    },
    /// Bytes were left over after a complete value.
    #[error("malformed {what}: {extra} unexpected trailing bytes")]
    Trailing {
        /// What was being decoded.
        what: &'static str,
        /// How many bytes were left.
        extra: usize,
    },
    /// A value could not be encoded.
    #[error("could not encode {what}: {reason}")]
    Encode {
        /// What was being encoded.
        what: &'static str,
        /// The encoder's explanation.
        reason: String,
    },
}

/// Why a data format could not be derived, checked or used.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum FormatError {
    /// serde-reflection could not trace the type.
    #[error("cannot derive the data format of {type_name}: {reason}")]
    Trace {
        /// The Rust type.
        type_name: &'static str,
        /// Why tracing failed.
        reason: String,
    },
    /// The format description itself is inconsistent.
    #[error("invalid data format: {0}")]
    Invalid(String),
    /// Data does not match the format it was decoded with.
    #[error("data does not match its format at {path}: {reason}")]
    Mismatch {
        /// Where in the value.
        path: String,
        /// What was wrong.
        reason: String,
    },
}

thread_local! {
    /// The last custom message a validating `Deserialize` impl produced on this thread.
    ///
    /// postcard replaces custom deserialization errors with a fixed text; validating impls (the
    /// name types) record their message here so the codec can report what was actually wrong.
    static LAST_CUSTOM: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Records `message` as the reason of the custom deserialization error being raised.
pub(crate) fn note_custom(message: &str) {
    LAST_CUSTOM.with(|m| *m.borrow_mut() = Some(message.to_owned()));
}

/// Takes the recorded custom message, if any.
pub(crate) fn take_custom() -> Option<String> {
    LAST_CUSTOM.with(|m| m.borrow_mut().take())
}
