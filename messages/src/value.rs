//! Dynamic values: message data decoded through a [`DataFormat`] without the Rust type.
//!
//! This is what lets `tca log show` print traffic of messages the viewer was not compiled with
//! (TCA displayed data through the registered format string for the same reason). The decoder
//! follows postcard's wire format and is strict and bounded: it refuses trailing bytes, nesting
//! deeper than [`MAX_DEPTH`] and more than [`MAX_VALUES`] values, so hostile input cannot exhaust
//! the stack or memory.

use std::fmt::{self, Write as _};

use crate::error::FormatError;
use crate::format::{Body, Container, DataFormat, Shape, ShapeIndex};

/// Deepest nesting the decoder follows.
pub const MAX_DEPTH: usize = 64;
/// Most values one decode may produce.
pub const MAX_VALUES: usize = 1 << 20;

/// A decoded value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// `()` or a unit struct/variant body.
    Unit,
    /// A boolean.
    Bool(bool),
    /// A signed integer.
    Int(i128),
    /// An unsigned integer.
    UInt(u128),
    /// A float.
    Float(f64),
    /// A character.
    Char(char),
    /// A string.
    Str(String),
    /// A byte string.
    Bytes(Vec<u8>),
    /// An optional value.
    Option(Option<Box<Value>>),
    /// A sequence, tuple or array.
    Seq(Vec<Value>),
    /// A map, as key/value pairs in wire order.
    Map(Vec<(Value, Value)>),
    /// A struct (or newtype/tuple struct, with numbered fields).
    Struct {
        /// Type name.
        name: String,
        /// Fields in order; tuple structs use "0", "1", ...
        fields: Vec<(String, Value)>,
    },
    /// An enum variant.
    Variant {
        /// Enum name.
        name: String,
        /// Variant name.
        variant: String,
        /// Variant body.
        body: Box<Value>,
    },
}

impl DataFormat {
    /// Decodes postcard `bytes` through this format.
    pub fn decode_value(&self, bytes: &[u8]) -> Result<Value, FormatError> {
        let mut d = Decoder {
            format: self,
            input: bytes,
            pos: 0,
            budget: MAX_VALUES,
        };
        let root = self.root_index();
        let value = d.shape(root, 0, "$")?;
        if d.pos != bytes.len() {
            return Err(FormatError::Mismatch {
                path: "$".into(),
                reason: format!(
                    "{} bytes left over after the value; the data was encoded with another format",
                    bytes.len() - d.pos
                ),
            });
        }
        Ok(value)
    }
}

struct Decoder<'a> {
    format: &'a DataFormat,
    input: &'a [u8],
    pos: usize,
    budget: usize,
}

impl Decoder<'_> {
    fn err(&self, path: &str, reason: impl Into<String>) -> FormatError {
        FormatError::Mismatch {
            path: path.to_owned(),
            reason: reason.into(),
        }
    }

    fn take(&mut self, n: usize, path: &str) -> Result<&[u8], FormatError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.input.len());
        match end {
            Some(end) => {
                let s = &self.input[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(self.err(
                path,
                format!(
                    "needs {n} more bytes at offset {} but the data ends at {}",
                    self.pos,
                    self.input.len()
                ),
            )),
        }
    }

    fn byte(&mut self, path: &str) -> Result<u8, FormatError> {
        Ok(self.take(1, path)?[0])
    }

    fn varint(&mut self, max_bytes: usize, path: &str) -> Result<u128, FormatError> {
        let mut out: u128 = 0;
        for i in 0..max_bytes {
            let b = self.byte(path)?;
            out |= u128::from(b & 0x7f) << (7 * i);
            if b & 0x80 == 0 {
                return Ok(out);
            }
        }
        Err(self.err(path, "varint is too long for its type"))
    }

    fn length(&mut self, path: &str) -> Result<usize, FormatError> {
        let n = self.varint(10, path)?;
        usize::try_from(n).map_err(|_| self.err(path, "length does not fit in memory"))
    }

    fn spend(&mut self, path: &str) -> Result<(), FormatError> {
        if self.budget == 0 {
            return Err(self.err(path, format!("more than {MAX_VALUES} values")));
        }
        self.budget -= 1;
        Ok(())
    }

    fn shape(&mut self, index: ShapeIndex, depth: usize, path: &str) -> Result<Value, FormatError> {
        if depth > MAX_DEPTH {
            return Err(self.err(path, format!("nested deeper than {MAX_DEPTH} levels")));
        }
        self.spend(path)?;
        let shape = self.format.shape(index)?.clone();
        let unsigned = |d: &mut Self, bytes: usize| d.varint(bytes, path);
        let signed = |d: &mut Self, bytes: usize| -> Result<Value, FormatError> {
            let z = d.varint(bytes, path)?;
            // zig-zag decoding
            let v = ((z >> 1) as i128) ^ -((z & 1) as i128);
            Ok(Value::Int(v))
        };
        Ok(match shape {
            Shape::Unit => Value::Unit,
            Shape::Bool => match self.byte(path)? {
                0 => Value::Bool(false),
                1 => Value::Bool(true),
                b => return Err(self.err(path, format!("bool byte is {b}, not 0 or 1"))),
            },
            Shape::U8 => Value::UInt(u128::from(self.byte(path)?)),
            Shape::I8 => Value::Int(i128::from(self.byte(path)? as i8)),
            Shape::U16 => Value::UInt(unsigned(self, 3)?),
            Shape::U32 => Value::UInt(unsigned(self, 5)?),
            Shape::U64 => Value::UInt(unsigned(self, 10)?),
            Shape::U128 => Value::UInt(unsigned(self, 19)?),
            Shape::I16 => signed(self, 3)?,
            Shape::I32 => signed(self, 5)?,
            Shape::I64 => signed(self, 10)?,
            Shape::I128 => signed(self, 19)?,
            Shape::F32 => {
                let b = self.take(4, path)?;
                Value::Float(f32_as_decimal(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            }
            Shape::F64 => {
                let b = self.take(8, path)?;
                let mut a = [0u8; 8];
                a.copy_from_slice(b);
                Value::Float(f64::from_le_bytes(a))
            }
            Shape::Char => {
                let s = self.string(path)?;
                let mut chars = s.chars();
                match (chars.next(), chars.next()) {
                    (Some(c), None) => Value::Char(c),
                    _ => return Err(self.err(path, "a char must be one character")),
                }
            }
            Shape::Str => Value::Str(self.string(path)?),
            Shape::Bytes => {
                let n = self.length(path)?;
                Value::Bytes(self.take(n, path)?.to_vec())
            }
            Shape::Option(inner) => match self.byte(path)? {
                0 => Value::Option(None),
                1 => Value::Option(Some(Box::new(self.shape(inner, depth + 1, path)?))),
                b => return Err(self.err(path, format!("option tag is {b}, not 0 or 1"))),
            },
            Shape::Seq(inner) => {
                let n = self.length(path)?;
                let mut items = Vec::with_capacity(n.min(self.input.len() - self.pos));
                for i in 0..n {
                    items.push(self.shape(inner, depth + 1, &format!("{path}[{i}]"))?);
                }
                Value::Seq(items)
            }
            Shape::Map(k, v) => {
                let n = self.length(path)?;
                let mut items = Vec::with_capacity(n.min(self.input.len() - self.pos));
                for i in 0..n {
                    let key = self.shape(k, depth + 1, &format!("{path}{{{i}}}"))?;
                    let value = self.shape(v, depth + 1, &format!("{path}[{key}]"))?;
                    items.push((key, value));
                }
                Value::Map(items)
            }
            Shape::Tuple(items) => {
                let mut out = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    out.push(self.shape(*item, depth + 1, &format!("{path}.{i}"))?);
                }
                Value::Seq(out)
            }
            Shape::Array(item, n) => {
                let mut out = Vec::with_capacity((n as usize).min(self.input.len() - self.pos));
                for i in 0..n {
                    out.push(self.shape(item, depth + 1, &format!("{path}[{i}]"))?);
                }
                Value::Seq(out)
            }
            Shape::Named(name) => self.named(&name, depth + 1, path)?,
        })
    }

    fn string(&mut self, path: &str) -> Result<String, FormatError> {
        let n = self.length(path)?;
        let bytes = self.take(n, path)?;
        String::from_utf8(bytes.to_vec()).map_err(|_| self.err(path, "string is not UTF-8"))
    }

    fn named(&mut self, name: &str, depth: usize, path: &str) -> Result<Value, FormatError> {
        match self.format.named(name)?.clone() {
            Container::Struct(body) => {
                let fields = self.body(&body, depth, path)?;
                Ok(Value::Struct {
                    name: name.to_owned(),
                    fields,
                })
            }
            Container::Enum(variants) => {
                let tag = self.varint(5, path)?;
                let variant = usize::try_from(tag)
                    .ok()
                    .and_then(|t| variants.get(t))
                    .ok_or_else(|| {
                        self.err(
                            path,
                            format!("variant index {tag} out of range for enum {name}"),
                        )
                    })?;
                let vpath = format!("{path}::{}", variant.name);
                let fields = self.body(&variant.body, depth, &vpath)?;
                let body = match &variant.body {
                    Body::Unit => Value::Unit,
                    Body::NewType(_) => fields
                        .into_iter()
                        .next()
                        .map(|(_, v)| v)
                        .unwrap_or(Value::Unit),
                    _ => Value::Struct {
                        name: variant.name.clone(),
                        fields,
                    },
                };
                Ok(Value::Variant {
                    name: name.to_owned(),
                    variant: variant.name.clone(),
                    body: Box::new(body),
                })
            }
        }
    }

    fn body(
        &mut self,
        body: &Body,
        depth: usize,
        path: &str,
    ) -> Result<Vec<(String, Value)>, FormatError> {
        Ok(match body {
            Body::Unit => Vec::new(),
            Body::NewType(i) => vec![("0".into(), self.shape(*i, depth, path)?)],
            Body::Tuple(items) => {
                let mut out = Vec::with_capacity(items.len());
                for (n, i) in items.iter().enumerate() {
                    out.push((
                        n.to_string(),
                        self.shape(*i, depth, &format!("{path}.{n}"))?,
                    ));
                }
                out
            }
            Body::Struct(fields) => {
                let mut out = Vec::with_capacity(fields.len());
                for f in fields {
                    let v = self.shape(f.shape, depth, &format!("{path}.{}", f.name))?;
                    out.push((f.name.clone(), v));
                }
                out
            }
        })
    }
}

/// An `f32` as the `f64` nearest its shortest decimal form (`0.1f32` gives `0.1`, not
/// `0.10000000149011612`), so that JSON and text show the number the sender wrote. Converting
/// the result back to `f32` gives the same bits for every finite value; non-finite values
/// are kept as they are.
pub fn f32_as_decimal(x: f32) -> f64 {
    if !x.is_finite() {
        return f64::from(x);
    }
    let mut buffer = ryu::Buffer::new();
    buffer
        .format_finite(x)
        .parse::<f64>()
        .unwrap_or_else(|_| f64::from(x))
}

impl fmt::Display for Value {
    /// Compact, readable text: `LegMove { transition: true, waypoints: [..] }`.
    /// Byte strings longer than 16 bytes and sequences longer than 16 items are abbreviated.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SHOWN: usize = 16;
        match self {
            Value::Unit => f.write_str("()"),
            Value::Bool(b) => write!(f, "{b}"),
            Value::Int(i) => write!(f, "{i}"),
            Value::UInt(u) => write!(f, "{u}"),
            Value::Float(x) => write!(f, "{x}"),
            Value::Char(c) => write!(f, "{c:?}"),
            Value::Str(s) => write!(f, "{s:?}"),
            Value::Bytes(b) => {
                f.write_str("0x")?;
                for byte in b.iter().take(SHOWN) {
                    write!(f, "{byte:02x}")?;
                }
                if b.len() > SHOWN {
                    write!(f, "..({} bytes)", b.len())?;
                }
                Ok(())
            }
            Value::Option(None) => f.write_str("None"),
            Value::Option(Some(v)) => write!(f, "Some({v})"),
            Value::Seq(items) => {
                f.write_char('[')?;
                for (i, v) in items.iter().take(SHOWN).enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{v}")?;
                }
                if items.len() > SHOWN {
                    write!(f, ", ..({} items)", items.len())?;
                }
                f.write_char(']')
            }
            Value::Map(items) => {
                f.write_char('{')?;
                for (i, (k, v)) in items.iter().take(SHOWN).enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{k}: {v}")?;
                }
                if items.len() > SHOWN {
                    write!(f, ", ..({} entries)", items.len())?;
                }
                f.write_char('}')
            }
            Value::Struct { name, fields } => {
                f.write_str(name)?;
                if fields.is_empty() {
                    return Ok(());
                }
                let tuple = fields.first().is_some_and(|(n, _)| n == "0");
                if tuple {
                    f.write_char('(')?;
                } else {
                    f.write_str(" { ")?;
                }
                for (i, (n, v)) in fields.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    if tuple {
                        write!(f, "{v}")?;
                    } else {
                        write!(f, "{n}: {v}")?;
                    }
                }
                f.write_str(if tuple { ")" } else { " }" })
            }
            Value::Variant { variant, body, .. } => match body.as_ref() {
                Value::Unit => f.write_str(variant),
                Value::Struct { fields, .. } => {
                    let inner = Value::Struct {
                        name: variant.clone(),
                        fields: fields.clone(),
                    };
                    write!(f, "{inner}")
                }
                other => write!(f, "{variant}({other})"),
            },
        }
    }
}

impl Value {
    /// Converts to JSON: structs become objects, variants `{"Variant": body}` (unit variants a
    /// string), maps with string, character or integer keys objects (keys as text, as serde_json
    /// writes them) and others arrays of pairs, bytes arrays of numbers, non-finite floats
    /// strings.
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::Value as J;
        match self {
            Value::Unit => J::Null,
            Value::Bool(b) => J::Bool(*b),
            Value::Int(i) => i64::try_from(*i)
                .map(J::from)
                .unwrap_or_else(|_| J::String(i.to_string())),
            Value::UInt(u) => u64::try_from(*u)
                .map(J::from)
                .unwrap_or_else(|_| J::String(u.to_string())),
            Value::Float(x) => serde_json::Number::from_f64(*x)
                .map(J::Number)
                .unwrap_or_else(|| J::String(x.to_string())),
            Value::Char(c) => J::String(c.to_string()),
            Value::Str(s) => J::String(s.clone()),
            Value::Bytes(b) => J::Array(b.iter().map(|x| J::from(*x)).collect()),
            Value::Option(None) => J::Null,
            Value::Option(Some(v)) => v.to_json(),
            Value::Seq(items) => J::Array(items.iter().map(Value::to_json).collect()),
            Value::Map(items) => {
                let key_text = |k: &Value| match k {
                    Value::Str(s) => Some(s.clone()),
                    Value::Char(c) => Some(c.to_string()),
                    Value::Int(_) | Value::UInt(_) => Some(k.to_string()),
                    _ => None,
                };
                if items.iter().all(|(k, _)| key_text(k).is_some()) {
                    J::Object(
                        items
                            .iter()
                            .map(|(k, v)| (key_text(k).unwrap_or_default(), v.to_json()))
                            .collect(),
                    )
                } else {
                    J::Array(
                        items
                            .iter()
                            .map(|(k, v)| J::Array(vec![k.to_json(), v.to_json()]))
                            .collect(),
                    )
                }
            }
            Value::Struct { fields, .. } => {
                if fields.len() == 1 && fields[0].0 == "0" {
                    return fields[0].1.to_json();
                }
                if fields.first().is_some_and(|(n, _)| n == "0") {
                    return J::Array(fields.iter().map(|(_, v)| v.to_json()).collect());
                }
                J::Object(
                    fields
                        .iter()
                        .map(|(n, v)| (n.clone(), v.to_json()))
                        .collect(),
                )
            }
            Value::Variant { variant, body, .. } => match body.as_ref() {
                Value::Unit => J::String(variant.clone()),
                other => {
                    let mut m = serde_json::Map::new();
                    m.insert(variant.clone(), other.to_json());
                    J::Object(m)
                }
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use serde::{Deserialize, Serialize};
    use std::collections::BTreeMap;

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    enum Kind {
        Plain,
        Tagged(i32),
        Pair(u8, String),
        Named { x: f64, flag: bool },
    }

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    struct Sample {
        a: u64,
        b: i16,
        c: Option<f32>,
        d: Vec<Kind>,
        e: BTreeMap<String, u32>,
        f: (char, u128),
        g: [i64; 3],
        h: String,
    }

    fn kind() -> impl Strategy<Value = Kind> {
        prop_oneof![
            Just(Kind::Plain),
            any::<i32>().prop_map(Kind::Tagged),
            (any::<u8>(), ".{0,8}").prop_map(|(a, b)| Kind::Pair(a, b)),
            (
                any::<f64>().prop_filter("finite", |x| x.is_finite()),
                any::<bool>()
            )
                .prop_map(|(x, flag)| Kind::Named { x, flag }),
        ]
    }

    prop_compose! {
        fn sample()(a in any::<u64>(), b in any::<i16>(),
                    c in proptest::option::of(-1e6f32..1e6),
                    d in proptest::collection::vec(kind(), 0..6),
                    e in proptest::collection::btree_map(".{0,5}", any::<u32>(), 0..4),
                    f in (any::<char>(), any::<u64>().prop_map(u128::from)), g in any::<[i64; 3]>(),
                    h in ".{0,12}") -> Sample {
            Sample { a, b, c, d, e, f, g, h }
        }
    }

    proptest! {
        #[test]
        fn an_f32_shown_as_decimal_converts_back_to_the_same_bits(bits in any::<u32>()) {
            let x = f32::from_bits(bits);
            let shown = f32_as_decimal(x);
            if x.is_nan() {
                prop_assert!(shown.is_nan());
            } else {
                prop_assert_eq!((shown as f32).to_bits(), x.to_bits());
            }
        }

        #[test]
        fn dynamic_decoding_matches_the_typed_value(s in sample()) {
            let format = DataFormat::of::<Sample>().unwrap();
            let bytes = postcard::to_allocvec(&s).unwrap();
            let value = format.decode_value(&bytes).unwrap();
            let via_json: Sample = serde_json::from_value(value.to_json()).unwrap();
            prop_assert_eq!(via_json, s);
        }

        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            let format = DataFormat::of::<Sample>().unwrap();
            let _ = format.decode_value(&bytes);
        }
    }

    #[test]
    fn trailing_bytes_are_refused() {
        let format = DataFormat::of::<u32>().unwrap();
        let mut bytes = postcard::to_allocvec(&7u32).unwrap();
        bytes.push(0);
        let err = format.decode_value(&bytes).unwrap_err();
        assert!(err.to_string().contains("left over"), "{err}");
    }

    #[test]
    fn display_is_readable() {
        let format = DataFormat::of::<Kind>().unwrap();
        let bytes = postcard::to_allocvec(&Kind::Named { x: 1.5, flag: true }).unwrap();
        let v = format.decode_value(&bytes).unwrap();
        assert_eq!(v.to_string(), "Named { x: 1.5, flag: true }");
    }

    #[test]
    fn single_precision_floats_show_as_written() {
        let format = DataFormat::of::<Vec<f32>>().unwrap();
        let bytes = postcard::to_allocvec(&vec![0.1f32, -2.7, 1e-7, f32::NAN]).unwrap();
        let v = format.decode_value(&bytes).unwrap();
        assert_eq!(v.to_string(), "[0.1, -2.7, 0.0000001, NaN]");
        assert_eq!(
            serde_json::to_string(&v.to_json()).unwrap(),
            r#"[0.1,-2.7,1e-7,"NaN"]"#
        );
    }

    #[test]
    fn huge_lengths_do_not_allocate() {
        let format = DataFormat::of::<Vec<()>>().unwrap();
        // length 2^60 of zero-sized items: must stop at the value budget, not allocate or spin.
        let mut bytes = Vec::new();
        let mut n: u64 = 1 << 60;
        while n >= 0x80 {
            bytes.push((n as u8) | 0x80);
            n >>= 7;
        }
        bytes.push(n as u8);
        assert!(format.decode_value(&bytes).is_err());
    }
}
