//! Data formats: a description of a message's serde shape, registered with central.
//!
//! TCA registered a format string with every message so central could check and display data it
//! was not compiled with. Here the format is derived from the Rust type by tracing its serde
//! implementation (see the `trace` module) and stored in a flat, `Send` form ([`DataFormat`]): a table of shapes in which every shape
//! refers only to shapes before it, so decoding a format from the wire never recurses and a cycle
//! cannot be expressed except through a named type.

use std::collections::BTreeMap;
use std::fmt;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::error::FormatError;

/// Index of a [`Shape`] in a [`DataFormat`]'s shape table.
pub type ShapeIndex = u32;

/// Most shapes, named types, fields or variants a format may hold.
pub const MAX_FORMAT_ENTRIES: usize = 4096;

/// One node of a format: a primitive, a composite of earlier shapes, or a named type.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Shape {
    /// `()`.
    Unit,
    /// `bool`.
    Bool,
    /// `i8`.
    I8,
    /// `i16`.
    I16,
    /// `i32`.
    I32,
    /// `i64`.
    I64,
    /// `i128`.
    I128,
    /// `u8`.
    U8,
    /// `u16`.
    U16,
    /// `u32`.
    U32,
    /// `u64`.
    U64,
    /// `u128`.
    U128,
    /// `f32`.
    F32,
    /// `f64`.
    F64,
    /// `char`.
    Char,
    /// A string.
    Str,
    /// A byte string.
    Bytes,
    /// An optional value of the given shape.
    Option(ShapeIndex),
    /// A sequence of the given shape.
    Seq(ShapeIndex),
    /// A map from the first shape to the second.
    Map(ShapeIndex, ShapeIndex),
    /// A tuple of the given shapes.
    Tuple(Vec<ShapeIndex>),
    /// A fixed-size array: item shape and length.
    Array(ShapeIndex, u32),
    /// A named struct or enum, described in [`DataFormat::types`].
    Named(String),
}

/// A named field of a struct or struct variant.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Field {
    /// Field name.
    pub name: String,
    /// Field shape.
    pub shape: ShapeIndex,
}

/// The body of a struct or of an enum variant.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Body {
    /// No data.
    Unit,
    /// One unnamed value.
    NewType(ShapeIndex),
    /// Several unnamed values.
    Tuple(Vec<ShapeIndex>),
    /// Named fields.
    Struct(Vec<Field>),
}

/// A named type: a struct (with its body) or an enum (with its variants, in index order).
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Container {
    /// A struct.
    Struct(Body),
    /// An enum; variant `i` is `variants[i]`.
    Enum(Vec<Variant>),
}

/// One enum variant.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Variant {
    /// Variant name.
    pub name: String,
    /// Variant body.
    pub body: Body,
}

/// The complete data format of one message: the root shape plus every named type it uses.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct DataFormat {
    shapes: Vec<Shape>,
    root: ShapeIndex,
    types: BTreeMap<String, Container>,
}

impl DataFormat {
    /// Derives the format of `T` by tracing its serde implementation.
    ///
    /// Fails for types whose `Deserialize` refuses the tracer's sample values, or that use serde
    /// features postcard cannot carry (untagged enums, `deserialize_any`).
    pub fn of<T: DeserializeOwned>() -> Result<Self, FormatError> {
        crate::trace::trace::<T>().map_err(|e| FormatError::Trace {
            type_name: std::any::type_name::<T>(),
            reason: e.to_string(),
        })
    }

    /// Assembles and validates a format from its parts.
    pub fn from_parts(
        shapes: Vec<Shape>,
        root: ShapeIndex,
        types: BTreeMap<String, Container>,
    ) -> Result<Self, FormatError> {
        let format = DataFormat {
            shapes,
            root,
            types,
        };
        format.validate()?;
        Ok(format)
    }

    /// The format of a message with no data (`()`).
    pub fn unit() -> Self {
        DataFormat {
            shapes: vec![Shape::Unit],
            root: 0,
            types: BTreeMap::new(),
        }
    }

    /// The shape table.
    pub fn shapes(&self) -> &[Shape] {
        &self.shapes
    }

    /// The root shape.
    pub fn root(&self) -> &Shape {
        // `validate` guarantees the index is in range; fall back to Unit defensively.
        self.shapes.get(self.root as usize).unwrap_or(&Shape::Unit)
    }

    /// Index of the root shape in [`DataFormat::shapes`].
    pub fn root_index(&self) -> ShapeIndex {
        self.root
    }

    /// The named types, by name.
    pub fn types(&self) -> &BTreeMap<String, Container> {
        &self.types
    }

    /// Looks up a shape by index.
    pub fn shape(&self, index: ShapeIndex) -> Result<&Shape, FormatError> {
        self.shapes
            .get(index as usize)
            .ok_or_else(|| FormatError::Invalid(format!("shape index {index} out of range")))
    }

    /// Looks up a named type.
    pub fn named(&self, name: &str) -> Result<&Container, FormatError> {
        self.types
            .get(name)
            .ok_or_else(|| FormatError::Invalid(format!("named type {name:?} is not described")))
    }

    /// Checks that the format is self-consistent: indices in range and pointing backwards, named
    /// types described, sizes bounded. Every format received from the wire must pass this.
    pub fn validate(&self) -> Result<(), FormatError> {
        let entries = self.shapes.len()
            + self.types.len()
            + self
                .types
                .values()
                .map(|c| match c {
                    Container::Struct(b) => body_len(b),
                    Container::Enum(vs) => vs.iter().map(|v| 1 + body_len(&v.body)).sum(),
                })
                .sum::<usize>();
        if entries > MAX_FORMAT_ENTRIES {
            return Err(FormatError::Invalid(format!(
                "format has {entries} entries; at most {MAX_FORMAT_ENTRIES} are accepted"
            )));
        }
        if self.root as usize >= self.shapes.len() {
            return Err(FormatError::Invalid("root shape index out of range".into()));
        }
        let n = self.shapes.len();
        let check_any = |i: ShapeIndex| -> Result<(), FormatError> {
            if (i as usize) < n {
                Ok(())
            } else {
                Err(FormatError::Invalid(format!(
                    "shape index {i} out of range"
                )))
            }
        };
        for (at, shape) in self.shapes.iter().enumerate() {
            let back = |i: ShapeIndex| -> Result<(), FormatError> {
                if (i as usize) < at {
                    Ok(())
                } else {
                    Err(FormatError::Invalid(format!(
                        "shape {at} refers to shape {i}, which does not come before it"
                    )))
                }
            };
            match shape {
                Shape::Option(i) | Shape::Seq(i) | Shape::Array(i, _) => back(*i)?,
                Shape::Map(k, v) => {
                    back(*k)?;
                    back(*v)?;
                }
                Shape::Tuple(items) => items.iter().try_for_each(|i| back(*i))?,
                Shape::Named(name) => {
                    self.named(name)?;
                }
                _ => {}
            }
        }
        for container in self.types.values() {
            let bodies: Vec<&Body> = match container {
                Container::Struct(b) => vec![b],
                Container::Enum(vs) => vs.iter().map(|v| &v.body).collect(),
            };
            for body in bodies {
                match body {
                    Body::Unit => {}
                    Body::NewType(i) => check_any(*i)?,
                    Body::Tuple(items) => items.iter().try_for_each(|i| check_any(*i))?,
                    Body::Struct(fields) => fields.iter().try_for_each(|f| check_any(f.shape))?,
                }
            }
        }
        Ok(())
    }

    /// Lists the differences between `self` (the format already known) and `other` (the one
    /// offered), as readable lines naming the path of each differing field. Empty when equal.
    pub fn differences(&self, other: &DataFormat) -> Vec<String> {
        let mut diff = Differ {
            a: self,
            b: other,
            out: Vec::new(),
            seen: Default::default(),
        };
        diff.shapes("$", self.root, other.root);
        diff.out
    }

    /// Renders a shape in Rust-like notation.
    pub fn shape_name(&self, index: ShapeIndex) -> String {
        match self.shape(index) {
            Ok(shape) => self.describe(shape),
            Err(_) => "?".into(),
        }
    }

    fn describe(&self, shape: &Shape) -> String {
        match shape {
            Shape::Unit => "()".into(),
            Shape::Bool => "bool".into(),
            Shape::I8 => "i8".into(),
            Shape::I16 => "i16".into(),
            Shape::I32 => "i32".into(),
            Shape::I64 => "i64".into(),
            Shape::I128 => "i128".into(),
            Shape::U8 => "u8".into(),
            Shape::U16 => "u16".into(),
            Shape::U32 => "u32".into(),
            Shape::U64 => "u64".into(),
            Shape::U128 => "u128".into(),
            Shape::F32 => "f32".into(),
            Shape::F64 => "f64".into(),
            Shape::Char => "char".into(),
            Shape::Str => "String".into(),
            Shape::Bytes => "Bytes".into(),
            Shape::Option(i) => format!("Option<{}>", self.shape_name(*i)),
            Shape::Seq(i) => format!("Vec<{}>", self.shape_name(*i)),
            Shape::Map(k, v) => format!("Map<{}, {}>", self.shape_name(*k), self.shape_name(*v)),
            Shape::Tuple(items) => {
                let inner: Vec<String> = items.iter().map(|i| self.shape_name(*i)).collect();
                format!("({})", inner.join(", "))
            }
            Shape::Array(i, n) => format!("[{}; {n}]", self.shape_name(*i)),
            Shape::Named(name) => name.clone(),
        }
    }

    fn body_text(&self, body: &Body) -> String {
        match body {
            Body::Unit => String::new(),
            Body::NewType(i) => format!("({})", self.shape_name(*i)),
            Body::Tuple(items) => {
                let inner: Vec<String> = items.iter().map(|i| self.shape_name(*i)).collect();
                format!("({})", inner.join(", "))
            }
            Body::Struct(fields) => {
                let inner: Vec<String> = fields
                    .iter()
                    .map(|f| format!("{}: {}", f.name, self.shape_name(f.shape)))
                    .collect();
                format!(" {{ {} }}", inner.join(", "))
            }
        }
    }
}

fn body_len(body: &Body) -> usize {
    match body {
        Body::Unit => 0,
        Body::NewType(_) => 1,
        Body::Tuple(items) => items.len(),
        Body::Struct(fields) => fields.len(),
    }
}

impl fmt::Display for DataFormat {
    /// One line: the root shape, then each named type, e.g.
    /// `BodyMove; struct BodyMove { target_y_m: f64 }`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe(self.root()))?;
        for (name, container) in &self.types {
            match container {
                Container::Struct(body) => write!(f, "; struct {name}{}", self.body_text(body))?,
                Container::Enum(variants) => {
                    let vs: Vec<String> = variants
                        .iter()
                        .map(|v| format!("{}{}", v.name, self.body_text(&v.body)))
                        .collect();
                    write!(f, "; enum {name} {{ {} }}", vs.join(", "))?;
                }
            }
        }
        Ok(())
    }
}

/// Walks two formats side by side and records where they differ.
struct Differ<'a> {
    a: &'a DataFormat,
    b: &'a DataFormat,
    out: Vec<String>,
    seen: std::collections::HashSet<(String, String)>,
}

impl Differ<'_> {
    const MAX_DIFFERENCES: usize = 32;

    fn note(&mut self, path: &str, what: String) {
        if self.out.len() < Self::MAX_DIFFERENCES {
            self.out.push(format!("{path}: {what}"));
        }
    }

    fn shapes(&mut self, path: &str, ia: ShapeIndex, ib: ShapeIndex) {
        let (Ok(sa), Ok(sb)) = (self.a.shape(ia), self.b.shape(ib)) else {
            self.note(path, "invalid shape index".into());
            return;
        };
        match (sa, sb) {
            (Shape::Option(x), Shape::Option(y)) | (Shape::Seq(x), Shape::Seq(y)) => {
                self.shapes(&format!("{path}[]"), *x, *y)
            }
            (Shape::Map(ka, va), Shape::Map(kb, vb)) => {
                self.shapes(&format!("{path}{{key}}"), *ka, *kb);
                self.shapes(&format!("{path}{{value}}"), *va, *vb);
            }
            (Shape::Array(x, n), Shape::Array(y, m)) => {
                if n != m {
                    self.note(path, format!("array of {n} vs array of {m}"));
                }
                self.shapes(&format!("{path}[]"), *x, *y);
            }
            (Shape::Tuple(xs), Shape::Tuple(ys)) => self.lists(path, xs, ys),
            (Shape::Named(na), Shape::Named(nb)) => self.named(path, na, nb),
            (x, y) if x == y => {}
            _ => {
                let (da, db) = (self.a.describe(sa), self.b.describe(sb));
                self.note(path, format!("{da} (registered) vs {db} (offered)"));
            }
        }
    }

    fn lists(&mut self, path: &str, xs: &[ShapeIndex], ys: &[ShapeIndex]) {
        if xs.len() != ys.len() {
            self.note(
                path,
                format!(
                    "{} elements (registered) vs {} (offered)",
                    xs.len(),
                    ys.len()
                ),
            );
        }
        for (i, (x, y)) in xs.iter().zip(ys).enumerate() {
            self.shapes(&format!("{path}.{i}"), *x, *y);
        }
    }

    fn named(&mut self, path: &str, na: &str, nb: &str) {
        if !self.seen.insert((na.to_owned(), nb.to_owned())) {
            return;
        }
        let (Ok(ca), Ok(cb)) = (self.a.named(na), self.b.named(nb)) else {
            self.note(path, format!("type {na} or {nb} is not described"));
            return;
        };
        match (ca, cb) {
            (Container::Struct(ba), Container::Struct(bb)) => self.bodies(path, ba, bb),
            (Container::Enum(va), Container::Enum(vb)) => {
                for (i, x) in va.iter().enumerate() {
                    match vb.get(i) {
                        None => self.note(path, format!("variant {} missing from offered", x.name)),
                        Some(y) if y.name != x.name => self.note(
                            path,
                            format!(
                                "variant {i} is {} (registered) vs {} (offered)",
                                x.name, y.name
                            ),
                        ),
                        Some(y) => self.bodies(&format!("{path}::{}", x.name), &x.body, &y.body),
                    }
                }
                for y in vb.iter().skip(va.len()) {
                    self.note(path, format!("variant {} not in registered", y.name));
                }
            }
            _ => self.note(path, format!("{na} and {nb} are not the same kind of type")),
        }
    }

    fn bodies(&mut self, path: &str, ba: &Body, bb: &Body) {
        match (ba, bb) {
            (Body::Unit, Body::Unit) => {}
            (Body::NewType(x), Body::NewType(y)) => self.shapes(path, *x, *y),
            (Body::Tuple(xs), Body::Tuple(ys)) => self.lists(path, xs, ys),
            (Body::Struct(fa), Body::Struct(fb)) => {
                for (i, x) in fa.iter().enumerate() {
                    match fb.get(i) {
                        None => self.note(
                            &format!("{path}.{}", x.name),
                            "field missing from offered format".into(),
                        ),
                        Some(y) if y.name != x.name => self.note(
                            &format!("{path}.{}", x.name),
                            format!("field {i} is named {:?} in the offered format", y.name),
                        ),
                        Some(y) => self.shapes(&format!("{path}.{}", x.name), x.shape, y.shape),
                    }
                }
                for y in fb.iter().skip(fa.len()) {
                    self.note(
                        &format!("{path}.{}", y.name),
                        "field not in registered format".into(),
                    );
                }
            }
            _ => self.note(path, "different kinds of body (unit, tuple, struct)".into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize, Deserialize)]
    struct LegMoveDeg {
        waypoints: Vec<JointsDeg>,
        transition: bool,
    }
    #[derive(Serialize, Deserialize)]
    #[serde(rename = "Joints")]
    struct JointsDeg {
        shoulder_deg: f64,
        elbow_deg: f64,
    }
    #[derive(Serialize, Deserialize)]
    #[serde(rename = "LegMoveDeg")]
    struct LegMoveRad {
        waypoints: Vec<JointsRad>,
        transition: bool,
    }
    #[derive(Serialize, Deserialize)]
    #[serde(rename = "Joints")]
    struct JointsRad {
        shoulder_rad: f64,
        elbow_rad: f32,
    }

    #[derive(Serialize, Deserialize)]
    enum Mode {
        Sequential,
        Concurrent { lookahead: u8 },
    }

    #[test]
    fn equal_types_have_equal_formats() {
        let a = DataFormat::of::<LegMoveDeg>().unwrap();
        let b = DataFormat::of::<LegMoveDeg>().unwrap();
        assert_eq!(a, b);
        assert!(a.differences(&b).is_empty());
        assert_eq!(
            a.to_string(),
            "LegMoveDeg; struct Joints { shoulder_deg: f64, elbow_deg: f64 }; \
             struct LegMoveDeg { waypoints: Vec<Joints>, transition: bool }"
        );
    }

    #[test]
    fn differences_name_the_fields() {
        let a = DataFormat::of::<LegMoveDeg>().unwrap();
        let b = DataFormat::of::<LegMoveRad>().unwrap();
        let diff = a.differences(&b);
        assert_eq!(diff.len(), 2, "{diff:?}");
        assert!(diff[0].contains("$.waypoints[].shoulder_deg"), "{diff:?}");
        assert!(diff[0].contains("shoulder_rad"), "{diff:?}");
        assert!(diff[1].contains("elbow_deg"), "{diff:?}");
    }

    #[test]
    fn enums_are_traced_completely() {
        let f = DataFormat::of::<Mode>().unwrap();
        assert_eq!(
            f.to_string(),
            "Mode; enum Mode { Sequential, Concurrent { lookahead: u8 } }"
        );
    }

    #[derive(Serialize, Deserialize)]
    struct Outer {
        modes: Vec<Mode>,
        inner: Option<Inner>,
    }
    #[derive(Serialize, Deserialize)]
    enum Inner {
        A(Mode),
        B { m: Vec<Mode>, z: Deep },
        C,
    }
    #[derive(Serialize, Deserialize)]
    enum Deep {
        P,
        Q,
        R(u8),
    }

    #[test]
    fn nested_enums_are_traced() {
        let f = DataFormat::of::<Outer>().unwrap();
        let text = f.to_string();
        assert!(text.contains("enum Deep { P, Q, R(u8) }"), "{text}");
        assert!(
            text.contains("enum Inner { A(Mode), B { m: Vec<Mode>, z: Deep }, C }"),
            "{text}"
        );
        assert!(
            text.contains("enum Mode { Sequential, Concurrent { lookahead: u8 } }"),
            "{text}"
        );
    }

    #[test]
    fn formats_survive_the_wire_and_validate() {
        let f = DataFormat::of::<LegMoveDeg>().unwrap();
        let bytes = postcard::to_allocvec(&f).unwrap();
        let back: DataFormat = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back, f);
        back.validate().unwrap();
    }

    #[test]
    fn forward_references_are_refused() {
        let bad = DataFormat {
            shapes: vec![Shape::Seq(0)],
            root: 0,
            types: BTreeMap::new(),
        };
        assert!(bad.validate().is_err());
        let dangling = DataFormat {
            shapes: vec![Shape::Named("Nope".into())],
            root: 0,
            types: BTreeMap::new(),
        };
        assert!(
            dangling
                .validate()
                .unwrap_err()
                .to_string()
                .contains("Nope")
        );
    }
}
