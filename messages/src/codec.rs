//! The one codec entry point: postcard for frames and message data.
//!
//! A frame is one protocol version byte followed by the postcard encoding of an
//! [`Envelope`]. Decoding is strict: the version must match, the frame must fit the size limit,
//! every name must be valid and no byte may be left over. Swapping postcard for another encoding
//! means changing this file only.

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::envelope::Envelope;
use crate::error::{CodecError, take_custom};

/// Explains a postcard error, recovering the message of a validating `Deserialize` impl.
fn reason(e: postcard::Error) -> String {
    match e {
        postcard::Error::SerdeDeCustom => {
            take_custom().unwrap_or_else(|| "a value failed validation".to_owned())
        }
        other => other.to_string(),
    }
}

/// Version of the frame layout; bumped on any incompatible change.
pub const PROTOCOL_VERSION: u8 = 2;

/// Default limit on a frame's size (16 MiB), configurable in central and modules.
pub const DEFAULT_MAX_FRAME_BYTES: usize = 16 << 20;

/// Encodes a message value (the `data` of an envelope).
pub fn encode_data<T: Serialize + ?Sized>(value: &T) -> Result<Vec<u8>, CodecError> {
    postcard::to_allocvec(value).map_err(|e| CodecError::Encode {
        what: std::any::type_name::<T>(),
        reason: e.to_string(),
    })
}

/// Decodes a message value, refusing trailing bytes.
pub fn decode_data<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CodecError> {
    let what = std::any::type_name::<T>();
    take_custom();
    let (value, rest) =
        postcard::take_from_bytes::<T>(bytes).map_err(|e| CodecError::Malformed {
            what,
            reason: reason(e),
        })?;
    if !rest.is_empty() {
        return Err(CodecError::Trailing {
            what,
            extra: rest.len(),
        });
    }
    Ok(value)
}

/// Encodes an envelope into a frame.
pub fn encode(envelope: &Envelope) -> Result<Vec<u8>, CodecError> {
    let mut out = Vec::with_capacity(64 + envelope.data.len());
    out.push(PROTOCOL_VERSION);
    postcard::to_io(envelope, &mut out).map_err(|e| CodecError::Encode {
        what: "envelope",
        reason: e.to_string(),
    })?;
    Ok(out)
}

/// Decodes a frame into an envelope, refusing frames over `max_bytes`.
pub fn decode(frame: &[u8], max_bytes: usize) -> Result<Envelope, CodecError> {
    if frame.len() > max_bytes {
        return Err(CodecError::TooLarge {
            size: frame.len(),
            limit: max_bytes,
        });
    }
    let (&version, body) = frame.split_first().ok_or(CodecError::Empty)?;
    if version != PROTOCOL_VERSION {
        return Err(CodecError::Version {
            found: version,
            expected: PROTOCOL_VERSION,
        });
    }
    take_custom();
    let (envelope, rest) =
        postcard::take_from_bytes::<Envelope>(body).map_err(|e| CodecError::Malformed {
            what: "envelope",
            reason: reason(e),
        })?;
    if !rest.is_empty() {
        return Err(CodecError::Trailing {
            what: "envelope",
            extra: rest.len(),
        });
    }
    Ok(envelope)
}

/// Serde helper so `Vec<u8>` fields use postcard's compact byte-string form.
pub(crate) mod bytes_field {
    use serde::{Deserializer, Serializer};

    pub(crate) fn serialize<S: Serializer>(v: &[u8], s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(v)
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u8>, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Vec<u8>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a byte string")
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<Vec<u8>, E> {
                Ok(v.to_vec())
            }
            fn visit_byte_buf<E: serde::de::Error>(self, v: Vec<u8>) -> Result<Vec<u8>, E> {
                Ok(v)
            }
        }
        d.deserialize_byte_buf(V)
    }
}
