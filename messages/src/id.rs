//! Validated identifiers: message names, module names and message ids.

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize};

use crate::error::NameError;

/// Longest accepted module or message name, in bytes.
pub const MAX_NAME_LEN: usize = 128;

fn check_name(kind: &'static str, name: &str) -> Result<(), NameError> {
    if name.is_empty() {
        return Err(NameError::Empty { kind });
    }
    if name.len() > MAX_NAME_LEN {
        return Err(NameError::TooLong {
            kind,
            len: name.len(),
        });
    }
    if let Some(bad) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.')))
    {
        return Err(NameError::BadChar {
            kind,
            name: name.to_owned(),
            bad,
        });
    }
    Ok(())
}

macro_rules! name_type {
    ($(#[$doc:meta])* $ty:ident, $kind:literal) => {
        $(#[$doc])*
        #[derive(Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $ty(std::sync::Arc<str>);

        impl Serialize for $ty {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(&self.0)
            }
        }

        impl $ty {
            /// Validates `name`: 1 to 128 ASCII letters, digits, `_`, `-` or `.`.
            pub fn new(name: impl Into<String>) -> Result<Self, NameError> {
                let name = name.into();
                Self::from_checked(&name)
            }

            fn from_checked(name: &str) -> Result<Self, NameError> {
                check_name($kind, name)?;
                Ok(Self(std::sync::Arc::from(name)))
            }

            /// The name as a string slice.
            pub fn as_str(&self) -> &str {
                &self.0
            }
        }

        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(&self.0)
            }
        }

        impl fmt::Debug for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "{:?}", self.0)
            }
        }

        impl AsRef<str> for $ty {
            fn as_ref(&self) -> &str {
                &self.0
            }
        }

        impl std::str::FromStr for $ty {
            type Err = NameError;
            fn from_str(s: &str) -> Result<Self, NameError> {
                Self::new(s)
            }
        }

        impl<'de> Deserialize<'de> for $ty {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct V;
                impl serde::de::Visitor<'_> for V {
                    type Value = $ty;
                    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                        write!(f, "a {}", $kind)
                    }
                    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<$ty, E> {
                        $ty::from_checked(v).map_err(|e| {
                            let text = e.to_string();
                            crate::error::note_custom(&text);
                            E::custom(text)
                        })
                    }
                }
                d.deserialize_str(V)
            }
        }
    };
}

name_type!(
    /// The name of a message, e.g. `moveBase`. Central routes by it.
    ///
    /// Names under `tca.` are reserved for central's own control traffic.
    MessageName,
    "message name"
);

name_type!(
    /// The name of a module, e.g. `controller`. At most one connected module has a given name.
    ModuleName,
    "module name"
);

impl MessageName {
    /// True for the reserved names of central's control traffic (`tca.` prefix).
    pub fn is_control(&self) -> bool {
        self.0.starts_with(crate::control::CONTROL_PREFIX)
    }

    /// A spelling-insensitive key: lower case with `_`, `-` and `.` removed, so that
    /// `move_base`, `move-base` and `moveBase` share a key (§7.1 met exactly this mix-up).
    pub fn fold(&self) -> String {
        fold_name(&self.0)
    }
}

/// Lower-cases `name` and drops `_`, `-` and `.`: the key used to suggest near-miss names.
pub fn fold_name(name: &str) -> String {
    name.chars()
        .filter(|c| !matches!(c, '_' | '-' | '.'))
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

/// Identifies one message for the life of a central process.
///
/// The high 32 bits are the sender's link number (given by central when the module connects), the
/// low 32 bits a counter of the sender's, so ids are unique without coordination and central can
/// check that a module does not forge another's ids.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct MessageId(pub u64);

impl MessageId {
    /// Builds an id from a link number and a per-link sequence number.
    pub fn new(link: u32, seq: u32) -> Self {
        Self((u64::from(link) << 32) | u64::from(seq))
    }

    /// The link number part.
    pub fn link(self) -> u32 {
        (self.0 >> 32) as u32
    }

    /// The sequence number part.
    pub fn seq(self) -> u32 {
        self.0 as u32
    }
}

impl fmt::Display for MessageId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "m{}.{}", self.link(), self.seq())
    }
}

impl fmt::Debug for MessageId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_validated() {
        assert!(MessageName::new("moveBase").is_ok());
        assert!(MessageName::new("tca.register").unwrap().is_control());
        assert!(matches!(MessageName::new(""), Err(NameError::Empty { .. })));
        let err = MessageName::new("body move").unwrap_err();
        assert!(err.to_string().contains("' '"), "{err}");
        assert!(ModuleName::new("x".repeat(129)).is_err());
    }

    #[test]
    fn folding_catches_spelling_variants() {
        let a = MessageName::new("move_base").unwrap();
        let b = MessageName::new("moveBase").unwrap();
        assert_eq!(a.fold(), b.fold());
    }

    #[test]
    fn message_id_parts() {
        let id = MessageId::new(7, 42);
        assert_eq!((id.link(), id.seq()), (7, 42));
        assert_eq!(id.to_string(), "m7.42");
    }

    #[test]
    fn bad_names_are_refused_when_decoding() {
        let bytes = postcard::to_allocvec("a b").unwrap();
        assert!(postcard::from_bytes::<MessageName>(&bytes).is_err());
    }
}
