//! Message data from JSON, through a registered [`DataFormat`], without the Rust type.
//!
//! The inverse of [`Value::to_json`]: what a person types on the command line (`tca call`,
//! `tca send`) is read through the format a module registered and encoded as postcard, so a
//! tool sends messages it was not compiled with. Structs are objects (a missing `Option` field
//! is `None`), unit structs `{}` or `null`, newtypes their inner value, tuples and arrays
//! arrays, enums `"Variant"` or `{"Variant": body}`, maps objects (keys parsed for their
//! shape) or arrays of `[key, value]` pairs, non-finite floats `"NaN"`, `"inf"`, `"-inf"`,
//! integers past 64 bits decimal strings. Every refusal names the path of the field that was
//! wrong (`$.waypoints[1].shoulder_rad`) and what was expected there.

use serde_json::Value as J;

use crate::error::FormatError;
use crate::format::{Body, Container, DataFormat, Shape, ShapeIndex};
use crate::value::{MAX_DEPTH, MAX_VALUES, Value};

impl DataFormat {
    /// Reads JSON as a value of this format; the error names the field that does not fit.
    pub fn value_from_json(&self, json: &J) -> Result<Value, FormatError> {
        let mut reader = Reader {
            format: self,
            budget: MAX_VALUES,
        };
        reader.shape(self.root_index(), json, 0, "$")
    }

    /// Encodes a value of this format as postcard (what [`DataFormat::decode_value`] reads
    /// back); the error names the field that does not fit.
    pub fn encode_value(&self, value: &Value) -> Result<Vec<u8>, FormatError> {
        let mut writer = Writer {
            format: self,
            out: Vec::new(),
        };
        writer.shape(self.root_index(), value, 0, "$")?;
        Ok(writer.out)
    }

    /// Reads JSON through this format and encodes it as postcard: message data from JSON.
    pub fn encode_json(&self, json: &J) -> Result<Vec<u8>, FormatError> {
        self.encode_value(&self.value_from_json(json)?)
    }

    /// A JSON value of this format with every number zero, every string and sequence empty,
    /// every option `null` and every enum its first variant: a template to fill in.
    pub fn json_template(&self) -> J {
        self.template(self.root_index(), 0)
    }

    fn template(&self, index: ShapeIndex, depth: usize) -> J {
        if depth > MAX_DEPTH {
            return J::Null;
        }
        let Ok(shape) = self.shape(index) else {
            return J::Null;
        };
        match shape {
            Shape::Unit | Shape::Option(_) => J::Null,
            Shape::Bool => J::Bool(false),
            Shape::F32 | Shape::F64 => J::from(0.0),
            Shape::Char => J::String("a".into()),
            Shape::Str => J::String(String::new()),
            Shape::Bytes | Shape::Seq(_) => J::Array(Vec::new()),
            Shape::Map(_, _) => J::Object(Default::default()),
            Shape::Tuple(items) => {
                J::Array(items.iter().map(|i| self.template(*i, depth + 1)).collect())
            }
            Shape::Array(item, n) => {
                J::Array((0..*n).map(|_| self.template(*item, depth + 1)).collect())
            }
            Shape::Named(name) => match self.named(name) {
                Ok(Container::Struct(body)) => self.body_template(body, depth),
                Ok(Container::Enum(variants)) => match variants.first() {
                    None => J::Null,
                    Some(v) if v.body == Body::Unit => J::String(v.name.clone()),
                    Some(v) => {
                        let mut m = serde_json::Map::new();
                        m.insert(v.name.clone(), self.body_template(&v.body, depth));
                        J::Object(m)
                    }
                },
                Err(_) => J::Null,
            },
            _ => J::from(0),
        }
    }

    fn body_template(&self, body: &Body, depth: usize) -> J {
        match body {
            Body::Unit => J::Object(Default::default()),
            Body::NewType(i) => self.template(*i, depth + 1),
            Body::Tuple(items) => {
                J::Array(items.iter().map(|i| self.template(*i, depth + 1)).collect())
            }
            Body::Struct(fields) => J::Object(
                fields
                    .iter()
                    .map(|f| (f.name.clone(), self.template(f.shape, depth + 1)))
                    .collect(),
            ),
        }
    }
}

fn mismatch(path: &str, reason: impl Into<String>) -> FormatError {
    FormatError::Mismatch {
        path: path.to_owned(),
        reason: reason.into(),
    }
}

/// A few words for what a JSON value is, for errors.
fn found(json: &J) -> String {
    match json {
        J::Null => "null".into(),
        J::Bool(b) => format!("the boolean {b}"),
        J::Number(n) => format!("the number {n}"),
        J::String(s) if s.len() <= 40 => format!("the string {s:?}"),
        J::String(_) => "a string".into(),
        J::Array(a) => format!("an array of {}", a.len()),
        J::Object(_) => "an object".into(),
    }
}

/// The closest of `candidates` to `name`, when it is close enough to be a slip.
fn closest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let name = name.to_ascii_lowercase();
    candidates
        .map(|c| {
            (
                crate::spelling::edit_distance(&name, &c.to_ascii_lowercase()),
                c,
            )
        })
        .filter(|(d, c)| *d <= 2.max(c.len() / 3))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

struct Reader<'a> {
    format: &'a DataFormat,
    budget: usize,
}

impl Reader<'_> {
    fn shape(
        &mut self,
        index: ShapeIndex,
        json: &J,
        depth: usize,
        path: &str,
    ) -> Result<Value, FormatError> {
        if depth > MAX_DEPTH {
            return Err(mismatch(
                path,
                format!("nested deeper than {MAX_DEPTH} levels"),
            ));
        }
        if self.budget == 0 {
            return Err(mismatch(path, format!("more than {MAX_VALUES} values")));
        }
        self.budget -= 1;
        let shape = self.format.shape(index)?;
        let expected =
            |what: &str| mismatch(path, format!("expected {what}, found {}", found(json)));
        Ok(match shape {
            Shape::Unit => match json {
                J::Null => Value::Unit,
                J::Object(m) if m.is_empty() => Value::Unit,
                _ => return Err(expected("null (no data)")),
            },
            Shape::Bool => Value::Bool(json.as_bool().ok_or_else(|| expected("true or false"))?),
            Shape::U8 => unsigned(json, u128::from(u8::MAX), "u8", path)?,
            Shape::U16 => unsigned(json, u128::from(u16::MAX), "u16", path)?,
            Shape::U32 => unsigned(json, u128::from(u32::MAX), "u32", path)?,
            Shape::U64 => unsigned(json, u128::from(u64::MAX), "u64", path)?,
            Shape::U128 => unsigned(json, u128::MAX, "u128", path)?,
            Shape::I8 => signed(json, i128::from(i8::MIN), i128::from(i8::MAX), "i8", path)?,
            Shape::I16 => signed(
                json,
                i128::from(i16::MIN),
                i128::from(i16::MAX),
                "i16",
                path,
            )?,
            Shape::I32 => signed(
                json,
                i128::from(i32::MIN),
                i128::from(i32::MAX),
                "i32",
                path,
            )?,
            Shape::I64 => signed(
                json,
                i128::from(i64::MIN),
                i128::from(i64::MAX),
                "i64",
                path,
            )?,
            Shape::I128 => signed(json, i128::MIN, i128::MAX, "i128", path)?,
            Shape::F32 => {
                let x = float(json, "f32", path)?;
                if x.is_finite() && (x as f32).is_infinite() {
                    return Err(mismatch(path, format!("{x} does not fit in an f32")));
                }
                // As the wire's f32 decodes: the single-precision value, shown as written.
                Value::Float(crate::value::f32_as_decimal(x as f32))
            }
            Shape::F64 => Value::Float(float(json, "f64", path)?),
            Shape::Char => match json.as_str().map(|s| {
                let mut c = s.chars();
                (c.next(), c.next())
            }) {
                Some((Some(c), None)) => Value::Char(c),
                _ => return Err(expected("a string of one character")),
            },
            Shape::Str => Value::Str(
                json.as_str()
                    .ok_or_else(|| expected("a string"))?
                    .to_owned(),
            ),
            Shape::Bytes => {
                let items = json
                    .as_array()
                    .ok_or_else(|| expected("an array of bytes (numbers 0 to 255)"))?;
                let mut bytes = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    let byte = item
                        .as_u64()
                        .and_then(|b| u8::try_from(b).ok())
                        .ok_or_else(|| {
                            mismatch(
                                &format!("{path}[{i}]"),
                                format!("expected a byte (0 to 255), found {}", found(item)),
                            )
                        })?;
                    bytes.push(byte);
                }
                Value::Bytes(bytes)
            }
            Shape::Option(inner) => match json {
                J::Null => Value::Option(None),
                other => Value::Option(Some(Box::new(self.shape(
                    *inner,
                    other,
                    depth + 1,
                    path,
                )?))),
            },
            Shape::Seq(inner) => {
                let items = json.as_array().ok_or_else(|| expected("an array"))?;
                let mut out = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    out.push(self.shape(*inner, item, depth + 1, &format!("{path}[{i}]"))?);
                }
                Value::Seq(out)
            }
            Shape::Map(k, v) => self.map(*k, *v, json, depth, path)?,
            Shape::Tuple(items) => {
                let items = items.clone();
                let array = json
                    .as_array()
                    .filter(|a| a.len() == items.len())
                    .ok_or_else(|| expected(&format!("an array of {}", items.len())))?;
                let mut out = Vec::with_capacity(items.len());
                for (i, (shape, item)) in items.iter().zip(array).enumerate() {
                    out.push(self.shape(*shape, item, depth + 1, &format!("{path}.{i}"))?);
                }
                Value::Seq(out)
            }
            Shape::Array(item, n) => {
                let (item, n) = (*item, *n as usize);
                let array = json
                    .as_array()
                    .filter(|a| a.len() == n)
                    .ok_or_else(|| expected(&format!("an array of {n}")))?;
                let mut out = Vec::with_capacity(n);
                for (i, x) in array.iter().enumerate() {
                    out.push(self.shape(item, x, depth + 1, &format!("{path}[{i}]"))?);
                }
                Value::Seq(out)
            }
            Shape::Named(name) => {
                let name = name.clone();
                self.named(&name, json, depth + 1, path)?
            }
        })
    }

    fn map(
        &mut self,
        k: ShapeIndex,
        v: ShapeIndex,
        json: &J,
        depth: usize,
        path: &str,
    ) -> Result<Value, FormatError> {
        let mut items = Vec::new();
        match json {
            J::Object(m) => {
                let textual = matches!(self.format.shape(k)?, Shape::Str | Shape::Char);
                for (key, value) in m {
                    let key_json = if textual {
                        J::String(key.clone())
                    } else {
                        serde_json::from_str(key).unwrap_or_else(|_| J::String(key.clone()))
                    };
                    let key = self.shape(k, &key_json, depth + 1, &format!("{path}{{{key}}}"))?;
                    let value = self.shape(v, value, depth + 1, &format!("{path}[{key}]"))?;
                    items.push((key, value));
                }
            }
            J::Array(pairs) => {
                for (i, pair) in pairs.iter().enumerate() {
                    let at = format!("{path}[{i}]");
                    let Some([key, value]) = pair.as_array().map(Vec::as_slice) else {
                        return Err(mismatch(
                            &at,
                            format!("expected a [key, value] pair, found {}", found(pair)),
                        ));
                    };
                    let key = self.shape(k, key, depth + 1, &format!("{at}.0"))?;
                    let value = self.shape(v, value, depth + 1, &format!("{at}.1"))?;
                    items.push((key, value));
                }
            }
            other => {
                return Err(mismatch(
                    path,
                    format!(
                        "expected an object or an array of [key, value] pairs, found {}",
                        found(other)
                    ),
                ));
            }
        }
        Ok(Value::Map(items))
    }

    fn named(
        &mut self,
        name: &str,
        json: &J,
        depth: usize,
        path: &str,
    ) -> Result<Value, FormatError> {
        match self.format.named(name)?.clone() {
            Container::Struct(body) => Ok(Value::Struct {
                name: name.to_owned(),
                fields: self.body(name, &body, json, depth, path)?,
            }),
            Container::Enum(variants) => {
                let names = || {
                    variants
                        .iter()
                        .map(|v| format!("{:?}", v.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                let (tag, body_json) = match json {
                    J::String(s) => (s.as_str(), &J::Null),
                    J::Object(m) if m.len() == 1 => {
                        let Some((k, v)) = m.iter().next() else {
                            unreachable!("one entry")
                        };
                        (k.as_str(), v)
                    }
                    other => {
                        return Err(mismatch(
                            path,
                            format!(
                                "expected a variant of {name}: a string for a variant without \
                                 data or {{\"Variant\": data}}, one of {}; found {}",
                                names(),
                                found(other)
                            ),
                        ));
                    }
                };
                let Some(variant) = variants.iter().find(|v| v.name == tag) else {
                    let hint = closest(tag, variants.iter().map(|v| v.name.as_str()))
                        .map(|c| format!("did you mean {c:?}? "))
                        .unwrap_or_default();
                    return Err(mismatch(
                        path,
                        format!(
                            "{name} has no variant {tag:?}; {hint}its variants are {}",
                            names()
                        ),
                    ));
                };
                let vpath = format!("{path}::{}", variant.name);
                let body = match &variant.body {
                    Body::Unit => match body_json {
                        J::Null => Value::Unit,
                        J::Object(m) if m.is_empty() => Value::Unit,
                        other => {
                            return Err(mismatch(
                                &vpath,
                                format!("variant {tag} carries no data; found {}", found(other)),
                            ));
                        }
                    },
                    Body::NewType(i) => self.shape(*i, body_json, depth + 1, &vpath)?,
                    other => Value::Struct {
                        name: variant.name.clone(),
                        fields: self.body(&variant.name, other, body_json, depth, &vpath)?,
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
        name: &str,
        body: &Body,
        json: &J,
        depth: usize,
        path: &str,
    ) -> Result<Vec<(String, Value)>, FormatError> {
        Ok(match body {
            Body::Unit => match json {
                J::Null => Vec::new(),
                J::Object(m) if m.is_empty() => Vec::new(),
                other => {
                    return Err(mismatch(
                        path,
                        format!("{name} carries no data: give {{}}; found {}", found(other)),
                    ));
                }
            },
            Body::NewType(i) => vec![("0".into(), self.shape(*i, json, depth, path)?)],
            Body::Tuple(items) => {
                let array = json
                    .as_array()
                    .filter(|a| a.len() == items.len())
                    .ok_or_else(|| {
                        mismatch(
                            path,
                            format!(
                                "{name} is a tuple of {}: give an array of {}; found {}",
                                items.len(),
                                items.len(),
                                found(json)
                            ),
                        )
                    })?;
                let mut out = Vec::with_capacity(items.len());
                for (n, (i, item)) in items.iter().zip(array).enumerate() {
                    out.push((
                        n.to_string(),
                        self.shape(*i, item, depth, &format!("{path}.{n}"))?,
                    ));
                }
                out
            }
            Body::Struct(fields) => {
                let listed = || {
                    fields
                        .iter()
                        .map(|f| format!("{}: {}", f.name, self.format.shape_name(f.shape)))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                let J::Object(object) = json else {
                    return Err(mismatch(
                        path,
                        format!(
                            "expected an object with the fields of {name} ({}), found {}",
                            listed(),
                            found(json)
                        ),
                    ));
                };
                for key in object.keys() {
                    if !fields.iter().any(|f| &f.name == key) {
                        let hint = closest(key, fields.iter().map(|f| f.name.as_str()))
                            .map(|c| format!("did you mean {c:?}? "))
                            .unwrap_or_default();
                        return Err(mismatch(
                            &format!("{path}.{key}"),
                            format!(
                                "{name} has no field {key:?}; {hint}its fields are {}",
                                listed()
                            ),
                        ));
                    }
                }
                let mut out = Vec::with_capacity(fields.len());
                for f in fields {
                    let fpath = format!("{path}.{}", f.name);
                    let value = match object.get(&f.name) {
                        Some(v) => self.shape(f.shape, v, depth, &fpath)?,
                        None if matches!(self.format.shape(f.shape)?, Shape::Option(_)) => {
                            Value::Option(None)
                        }
                        None => {
                            return Err(mismatch(
                                &fpath,
                                format!(
                                    "missing field {:?} ({}) of {name}",
                                    f.name,
                                    self.format.shape_name(f.shape)
                                ),
                            ));
                        }
                    };
                    out.push((f.name.clone(), value));
                }
                out
            }
        })
    }
}

fn unsigned(json: &J, max: u128, what: &str, path: &str) -> Result<Value, FormatError> {
    let n = match json {
        J::Number(n) => n.as_u64().map(u128::from),
        J::String(s) => s.trim().parse::<u128>().ok(),
        _ => None,
    };
    match n {
        Some(n) if n <= max => Ok(Value::UInt(n)),
        Some(n) => Err(mismatch(path, format!("{n} does not fit in a {what}"))),
        None => Err(mismatch(
            path,
            format!(
                "expected a whole number {what} (0 to {max}), found {}",
                found(json)
            ),
        )),
    }
}

fn signed(json: &J, min: i128, max: i128, what: &str, path: &str) -> Result<Value, FormatError> {
    let n = match json {
        J::Number(n) => n
            .as_i64()
            .map(i128::from)
            .or_else(|| n.as_u64().map(i128::from)),
        J::String(s) => s.trim().parse::<i128>().ok(),
        _ => None,
    };
    match n {
        Some(n) if (min..=max).contains(&n) => Ok(Value::Int(n)),
        Some(n) => Err(mismatch(path, format!("{n} does not fit in an {what}"))),
        None => Err(mismatch(
            path,
            format!(
                "expected a whole number {what} ({min} to {max}), found {}",
                found(json)
            ),
        )),
    }
}

fn float(json: &J, what: &str, path: &str) -> Result<f64, FormatError> {
    let x = match json {
        J::Number(n) => n.as_f64(),
        J::String(s) => match s.trim() {
            "NaN" | "nan" => Some(f64::NAN),
            "inf" | "+inf" | "Infinity" => Some(f64::INFINITY),
            "-inf" | "-Infinity" => Some(f64::NEG_INFINITY),
            _ => None,
        },
        _ => None,
    };
    x.ok_or_else(|| {
        mismatch(
            path,
            format!("expected a number ({what}), found {}", found(json)),
        )
    })
}

struct Writer<'a> {
    format: &'a DataFormat,
    out: Vec<u8>,
}

impl Writer<'_> {
    fn varint(&mut self, mut n: u128) {
        loop {
            let byte = (n & 0x7f) as u8;
            n >>= 7;
            if n == 0 {
                self.out.push(byte);
                return;
            }
            self.out.push(byte | 0x80);
        }
    }

    fn length(&mut self, n: usize) {
        self.varint(n as u128);
    }

    fn shape(
        &mut self,
        index: ShapeIndex,
        value: &Value,
        depth: usize,
        path: &str,
    ) -> Result<(), FormatError> {
        if depth > MAX_DEPTH {
            return Err(mismatch(
                path,
                format!("nested deeper than {MAX_DEPTH} levels"),
            ));
        }
        let shape = self.format.shape(index)?;
        let wrong = || {
            mismatch(
                path,
                format!(
                    "a {} does not fit here; expected {}",
                    kind(value),
                    self.format.shape_name(index)
                ),
            )
        };
        let uint = |max: u128| match value {
            Value::UInt(u) if *u <= max => Ok(*u),
            Value::Int(i) if *i >= 0 && (*i as u128) <= max => Ok(*i as u128),
            _ => Err(wrong()),
        };
        let int = |min: i128, max: i128| match value {
            Value::Int(i) if (min..=max).contains(i) => Ok(*i),
            Value::UInt(u) if i128::try_from(*u).is_ok_and(|i| i <= max) => Ok(*u as i128),
            _ => Err(wrong()),
        };
        match shape {
            Shape::Unit => match value {
                Value::Unit => {}
                Value::Struct { fields, .. } if fields.is_empty() => {}
                _ => return Err(wrong()),
            },
            Shape::Bool => match value {
                Value::Bool(b) => self.out.push(u8::from(*b)),
                _ => return Err(wrong()),
            },
            Shape::U8 => {
                let u = uint(u128::from(u8::MAX))?;
                self.out.push(u as u8);
            }
            Shape::U16 => {
                let u = uint(u128::from(u16::MAX))?;
                self.varint(u);
            }
            Shape::U32 => {
                let u = uint(u128::from(u32::MAX))?;
                self.varint(u);
            }
            Shape::U64 => {
                let u = uint(u128::from(u64::MAX))?;
                self.varint(u);
            }
            Shape::U128 => {
                let u = uint(u128::MAX)?;
                self.varint(u);
            }
            Shape::I8 => {
                let i = int(i128::from(i8::MIN), i128::from(i8::MAX))?;
                self.out.push(i as i8 as u8);
            }
            Shape::I16 => {
                let i = int(i128::from(i16::MIN), i128::from(i16::MAX))?;
                self.zigzag(i);
            }
            Shape::I32 => {
                let i = int(i128::from(i32::MIN), i128::from(i32::MAX))?;
                self.zigzag(i);
            }
            Shape::I64 => {
                let i = int(i128::from(i64::MIN), i128::from(i64::MAX))?;
                self.zigzag(i);
            }
            Shape::I128 => {
                let i = int(i128::MIN, i128::MAX)?;
                self.zigzag(i);
            }
            Shape::F32 => {
                let x = number(value).ok_or_else(wrong)?;
                self.out.extend_from_slice(&(x as f32).to_le_bytes());
            }
            Shape::F64 => {
                let x = number(value).ok_or_else(wrong)?;
                self.out.extend_from_slice(&x.to_le_bytes());
            }
            Shape::Char => match value {
                Value::Char(c) => self.string(c.encode_utf8(&mut [0u8; 4])),
                _ => return Err(wrong()),
            },
            Shape::Str => match value {
                Value::Str(s) => self.string(s),
                _ => return Err(wrong()),
            },
            Shape::Bytes => match value {
                Value::Bytes(b) => {
                    self.length(b.len());
                    self.out.extend_from_slice(b);
                }
                _ => return Err(wrong()),
            },
            Shape::Option(inner) => {
                let inner = *inner;
                match value {
                    Value::Option(None) => self.out.push(0),
                    Value::Option(Some(v)) => {
                        self.out.push(1);
                        self.shape(inner, v, depth + 1, path)?;
                    }
                    _ => return Err(wrong()),
                }
            }
            Shape::Seq(inner) => {
                let inner = *inner;
                let Value::Seq(items) = value else {
                    return Err(wrong());
                };
                self.length(items.len());
                for (i, item) in items.iter().enumerate() {
                    self.shape(inner, item, depth + 1, &format!("{path}[{i}]"))?;
                }
            }
            Shape::Map(k, v) => {
                let (k, v) = (*k, *v);
                let Value::Map(items) = value else {
                    return Err(wrong());
                };
                self.length(items.len());
                for (i, (key, val)) in items.iter().enumerate() {
                    self.shape(k, key, depth + 1, &format!("{path}{{{i}}}"))?;
                    self.shape(v, val, depth + 1, &format!("{path}[{key}]"))?;
                }
            }
            Shape::Tuple(shapes) => {
                let shapes = shapes.clone();
                let items = seq_of(value, shapes.len()).ok_or_else(wrong)?;
                for (i, (s, item)) in shapes.iter().zip(items).enumerate() {
                    self.shape(*s, item, depth + 1, &format!("{path}.{i}"))?;
                }
            }
            Shape::Array(item, n) => {
                let (item, n) = (*item, *n as usize);
                let items = seq_of(value, n).ok_or_else(wrong)?;
                for (i, x) in items.iter().enumerate() {
                    self.shape(item, x, depth + 1, &format!("{path}[{i}]"))?;
                }
            }
            Shape::Named(name) => {
                let name = name.clone();
                self.named(&name, value, depth + 1, path)?;
            }
        }
        Ok(())
    }

    fn zigzag(&mut self, i: i128) {
        self.varint(((i << 1) ^ (i >> 127)) as u128);
    }

    fn string(&mut self, s: &str) {
        self.length(s.len());
        self.out.extend_from_slice(s.as_bytes());
    }

    fn named(
        &mut self,
        name: &str,
        value: &Value,
        depth: usize,
        path: &str,
    ) -> Result<(), FormatError> {
        match self.format.named(name)?.clone() {
            Container::Struct(body) => {
                let Value::Struct { fields, .. } = value else {
                    return Err(mismatch(
                        path,
                        format!("a {} does not fit here; expected {name}", kind(value)),
                    ));
                };
                self.body(name, &body, fields, depth, path)
            }
            Container::Enum(variants) => {
                let Value::Variant { variant, body, .. } = value else {
                    return Err(mismatch(
                        path,
                        format!("a {} does not fit here; expected enum {name}", kind(value)),
                    ));
                };
                let Some((tag, v)) = variants
                    .iter()
                    .enumerate()
                    .find(|(_, v)| &v.name == variant)
                else {
                    return Err(mismatch(path, format!("{name} has no variant {variant:?}")));
                };
                self.varint(tag as u128);
                let vpath = format!("{path}::{variant}");
                match (&v.body, body.as_ref()) {
                    (Body::Unit, Value::Unit) => Ok(()),
                    (Body::NewType(i), inner) => self.shape(*i, inner, depth, &vpath),
                    (b, Value::Struct { fields, .. }) => {
                        self.body(variant, b, fields, depth, &vpath)
                    }
                    (_, other) => Err(mismatch(
                        &vpath,
                        format!("a {} does not fit variant {variant}", kind(other)),
                    )),
                }
            }
        }
    }

    fn body(
        &mut self,
        name: &str,
        body: &Body,
        fields: &[(String, Value)],
        depth: usize,
        path: &str,
    ) -> Result<(), FormatError> {
        let count = |n: usize| {
            if fields.len() == n {
                Ok(())
            } else {
                Err(mismatch(
                    path,
                    format!("{name} has {n} fields; the value has {}", fields.len()),
                ))
            }
        };
        match body {
            Body::Unit => count(0),
            Body::NewType(i) => {
                count(1)?;
                self.shape(*i, &fields[0].1, depth, path)
            }
            Body::Tuple(items) => {
                count(items.len())?;
                for (n, (i, (_, v))) in items.iter().zip(fields).enumerate() {
                    self.shape(*i, v, depth, &format!("{path}.{n}"))?;
                }
                Ok(())
            }
            Body::Struct(described) => {
                count(described.len())?;
                for (f, (given, v)) in described.iter().zip(fields) {
                    let fpath = format!("{path}.{}", f.name);
                    if &f.name != given {
                        return Err(mismatch(
                            &fpath,
                            format!("the value has field {given:?} here, not {:?}", f.name),
                        ));
                    }
                    self.shape(f.shape, v, depth, &fpath)?;
                }
                Ok(())
            }
        }
    }
}

fn number(value: &Value) -> Option<f64> {
    match value {
        Value::Float(x) => Some(*x),
        Value::Int(i) => Some(*i as f64),
        Value::UInt(u) => Some(*u as f64),
        _ => None,
    }
}

fn seq_of(value: &Value, n: usize) -> Option<&[Value]> {
    match value {
        Value::Seq(items) if items.len() == n => Some(items),
        _ => None,
    }
}

/// What kind of value it is, for errors.
fn kind(value: &Value) -> &'static str {
    match value {
        Value::Unit => "unit",
        Value::Bool(_) => "boolean",
        Value::Int(_) | Value::UInt(_) => "integer",
        Value::Float(_) => "float",
        Value::Char(_) => "char",
        Value::Str(_) => "string",
        Value::Bytes(_) => "byte string",
        Value::Option(_) => "option",
        Value::Seq(_) => "sequence",
        Value::Map(_) => "map",
        Value::Struct { .. } => "struct",
        Value::Variant { .. } => "enum variant",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use serde::{Deserialize, Serialize};
    use std::collections::BTreeMap;

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    struct BodyMove {
        target_y_m: f64,
    }

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    struct BodyPosition;

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    enum Mode {
        Sequential,
        Concurrent,
    }

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    struct Joints {
        shoulder_rad: f64,
        elbow_rad: f64,
    }

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    struct LegMove {
        waypoints: Vec<Joints>,
        transition: bool,
        note: Option<String>,
    }

    #[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
    struct Id(u32);

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
        f: (char, u64),
        g: [i64; 3],
        h: String,
        i: Id,
        j: BTreeMap<u16, bool>,
        k: Mode,
    }

    fn encode<T: serde::de::DeserializeOwned>(json: serde_json::Value) -> Result<Vec<u8>, String> {
        DataFormat::of::<T>()
            .unwrap()
            .encode_json(&json)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn a_body_move_from_json_is_the_typed_encoding() {
        let bytes = encode::<BodyMove>(serde_json::json!({"target_y_m": 2.0})).unwrap();
        assert_eq!(
            bytes,
            postcard::to_allocvec(&BodyMove { target_y_m: 2.0 }).unwrap()
        );
        // Whole numbers are numbers too.
        let bytes = encode::<BodyMove>(serde_json::json!({"target_y_m": 2})).unwrap();
        assert_eq!(
            postcard::from_bytes::<BodyMove>(&bytes).unwrap().target_y_m,
            2.0
        );
    }

    #[test]
    fn a_unit_struct_takes_an_empty_object_or_null() {
        for json in [serde_json::json!({}), serde_json::Value::Null] {
            assert_eq!(encode::<BodyPosition>(json).unwrap(), Vec::<u8>::new());
        }
        let err = encode::<BodyPosition>(serde_json::json!({"x": 1})).unwrap_err();
        assert!(err.contains("carries no data"), "{err}");
    }

    #[test]
    fn refusals_name_the_field() {
        let err = encode::<BodyMove>(serde_json::json!({"target_y": 2.0})).unwrap_err();
        assert!(err.contains("$.target_y"), "{err}");
        assert!(err.contains("did you mean \"target_y_m\""), "{err}");
        let err = encode::<BodyMove>(serde_json::json!({})).unwrap_err();
        assert!(err.contains("$.target_y_m"), "{err}");
        assert!(err.contains("missing field"), "{err}");
        let err = encode::<BodyMove>(serde_json::json!({"target_y_m": "two"})).unwrap_err();
        assert!(err.contains("$.target_y_m"), "{err}");
        assert!(err.contains("expected a number (f64)"), "{err}");
        let err = encode::<BodyMove>(serde_json::json!([2.0])).unwrap_err();
        assert!(err.contains("target_y_m: f64"), "{err}");
        let err = encode::<LegMove>(serde_json::json!({
            "waypoints": [{"shoulder_rad": 0.1, "elbow_rad": 0.2}, {"shoulder_rad": 0.1, "elbow_deg": 2}],
            "transition": true
        }))
        .unwrap_err();
        assert!(err.contains("$.waypoints[1].elbow_deg"), "{err}");
        assert!(err.contains("elbow_rad"), "{err}");
        let err = encode::<Mode>(serde_json::json!("Concurent")).unwrap_err();
        assert!(err.contains("did you mean \"Concurrent\""), "{err}");
        let err = encode::<u8>(serde_json::json!(300)).unwrap_err();
        assert!(err.contains("300 does not fit in a u8"), "{err}");
        let err = encode::<i8>(serde_json::json!(1.5)).unwrap_err();
        assert!(err.contains("whole number i8"), "{err}");
    }

    #[test]
    fn a_missing_option_is_none() {
        let bytes =
            encode::<LegMove>(serde_json::json!({"waypoints": [], "transition": false})).unwrap();
        let m: LegMove = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(m.note, None);
    }

    #[test]
    fn a_template_is_accepted_by_its_format() {
        let format = DataFormat::of::<Sample>().unwrap();
        let template = format.json_template();
        format.encode_json(&template).unwrap();
        assert_eq!(
            DataFormat::of::<BodyMove>().unwrap().json_template(),
            serde_json::json!({"target_y_m": 0.0})
        );
    }

    #[test]
    fn values_that_do_not_fit_are_refused_by_the_encoder() {
        let format = DataFormat::of::<BodyMove>().unwrap();
        let err = format.encode_value(&Value::Bool(true)).unwrap_err();
        assert!(err.to_string().contains("expected BodyMove"), "{err}");
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
                    f in (any::<char>(), any::<u64>()), g in any::<[i64; 3]>(),
                    h in ".{0,12}", i in any::<u32>(),
                    j in proptest::collection::btree_map(any::<u16>(), any::<bool>(), 0..4),
                    k in prop_oneof![Just(Mode::Sequential), Just(Mode::Concurrent)]) -> Sample {
            Sample { a, b, c, d, e, f, g, h, i: Id(i), j, k }
        }
    }

    proptest! {
        #[test]
        fn json_through_the_format_encodes_as_the_typed_value(s in sample()) {
            let format = DataFormat::of::<Sample>().unwrap();
            let json = serde_json::to_value(&s).unwrap();
            let value = format.value_from_json(&json).unwrap();
            let bytes = format.encode_value(&value).unwrap();
            // JSON objects keep their keys sorted as text, so a map with integer keys may
            // come in another order than the typed encoding's: compare what the bytes hold.
            let typed: Sample = postcard::from_bytes(&bytes).unwrap();
            prop_assert_eq!(&typed, &s);
            if s.j.len() < 2 {
                prop_assert_eq!(&bytes, &postcard::to_allocvec(&s).unwrap());
            }
            // And the decoder reads back the same value, whose JSON is the typed value's.
            let back = format.decode_value(&bytes).unwrap();
            prop_assert_eq!(&back, &value);
            let typed: Sample = serde_json::from_value(back.to_json()).unwrap();
            prop_assert_eq!(typed, s);
        }

        #[test]
        fn arbitrary_json_never_panics(text in "[\\[\\]{}\",:0-9a-z ]{0,64}") {
            let format = DataFormat::of::<Sample>().unwrap();
            if let Ok(json) = serde_json::from_str::<serde_json::Value>(&text) {
                let _ = format.encode_json(&json);
            }
        }
    }
}
