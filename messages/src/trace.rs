//! Deriving a [`DataFormat`] from a Rust type by driving its `Deserialize` impl.
//!
//! The tracer is a serde `Deserializer` that answers every request with a sample value and
//! records what was asked for: a struct's field names and shapes, a sequence's item shape, an
//! enum's variants. An enum yields one variant per visit, so the type is traced in passes until
//! every variant of every enum reached (at any depth: inside vectors, options, other enums) has
//! been seen. Recursive types are followed to [`CUT_DEPTH`], where options become `None` and
//! sequences empty; a type that cannot stop there is refused.

use std::collections::{BTreeMap, HashMap};

use serde::de::{
    self, DeserializeOwned, DeserializeSeed, EnumAccess, MapAccess, SeqAccess, VariantAccess,
    Visitor,
};

use crate::format::{
    Body, Container, DataFormat, Field, MAX_FORMAT_ENTRIES, Shape, ShapeIndex, Variant,
};

/// Depth past which optional and repeated content is no longer explored.
const CUT_DEPTH: usize = 24;
/// Depth at which tracing gives up (a recursive type with no way to stop).
const MAX_DEPTH: usize = 64;
/// Most passes over the type.
const MAX_PASSES: usize = 4096;

/// Why tracing failed (turned into [`crate::FormatError::Trace`]).
#[derive(Debug)]
pub(crate) struct TraceError(pub(crate) String);

impl std::fmt::Display for TraceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for TraceError {}

impl de::Error for TraceError {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        TraceError(format!("the type refused a sample value: {msg}"))
    }
}

type Result<T> = std::result::Result<T, TraceError>;

/// What the tracer has learned of one enum.
struct EnumInfo {
    names: &'static [&'static str],
    bodies: Vec<Option<Body>>,
    visits: usize,
}

#[derive(Default)]
struct Tracer {
    shapes: Vec<Shape>,
    index: HashMap<Shape, ShapeIndex>,
    structs: BTreeMap<String, Body>,
    enums: BTreeMap<String, EnumInfo>,
}

impl Tracer {
    fn intern(&mut self, shape: Shape) -> Result<ShapeIndex> {
        if let Some(&i) = self.index.get(&shape) {
            return Ok(i);
        }
        if self.shapes.len() >= MAX_FORMAT_ENTRIES {
            return Err(TraceError("the type is too large to describe".into()));
        }
        let i = self.shapes.len() as ShapeIndex;
        self.shapes.push(shape.clone());
        self.index.insert(shape, i);
        Ok(i)
    }

    /// The next variant to visit: the first not yet seen, else the variants in turn (so enums
    /// reachable only through one variant of another keep being reached).
    fn pick_variant(&mut self, name: &'static str, names: &'static [&'static str]) -> u32 {
        let info = self
            .enums
            .entry(name.to_owned())
            .or_insert_with(|| EnumInfo {
                names,
                bodies: vec![None; names.len()],
                visits: 0,
            });
        info.visits += 1;
        let n = info.bodies.len().max(1);
        info.bodies
            .iter()
            .position(Option::is_none)
            .unwrap_or(info.visits % n) as u32
    }

    fn incomplete(&self) -> bool {
        self.enums
            .values()
            .any(|e| e.bodies.iter().any(Option::is_none))
    }
}

/// Traces `T` into a data format.
pub(crate) fn trace<T: DeserializeOwned>() -> Result<DataFormat> {
    let mut tracer = Tracer::default();
    let mut root = None;
    for _ in 0..MAX_PASSES {
        let mut out = None;
        T::deserialize(De {
            t: &mut tracer,
            out: &mut out,
            depth: 0,
        })?;
        root = out;
        if !tracer.incomplete() {
            break;
        }
    }
    if tracer.incomplete() {
        return Err(TraceError(
            "an enum's variants could not all be reached".into(),
        ));
    }
    let root = root.ok_or_else(|| TraceError("the type produced no format".into()))?;
    let mut types = BTreeMap::new();
    for (name, body) in tracer.structs {
        types.insert(name, Container::Struct(body));
    }
    for (name, info) in tracer.enums {
        let variants = info
            .names
            .iter()
            .zip(info.bodies)
            .map(|(n, b)| Variant {
                name: (*n).to_owned(),
                body: b.unwrap_or(Body::Unit),
            })
            .collect();
        if types
            .insert(name.clone(), Container::Enum(variants))
            .is_some()
        {
            return Err(TraceError(format!(
                "two different types are both named {name}; rename one (serde(rename))"
            )));
        }
    }
    DataFormat::from_parts(tracer.shapes, root, types).map_err(|e| TraceError(e.to_string()))
}

/// One request: answers with a sample and stores the shape it saw in `out`.
struct De<'t> {
    t: &'t mut Tracer,
    out: &'t mut Option<ShapeIndex>,
    depth: usize,
}

impl<'t> De<'t> {
    fn set(&mut self, shape: Shape) -> Result<()> {
        *self.out = Some(self.t.intern(shape)?);
        Ok(())
    }

    fn child<'a>(&'a mut self, out: &'a mut Option<ShapeIndex>) -> Result<De<'a>> {
        if self.depth >= MAX_DEPTH {
            return Err(TraceError(format!(
                "the type nests deeper than {MAX_DEPTH} levels (a recursive type must be able to \
                 stop at an Option, a Vec or an enum variant)"
            )));
        }
        Ok(De {
            t: self.t,
            out,
            depth: self.depth + 1,
        })
    }

    fn cut(&self) -> bool {
        self.depth >= CUT_DEPTH
    }

    fn record_struct(&mut self, name: &'static str, body: Body) -> Result<()> {
        self.t.structs.insert(name.to_owned(), body);
        self.set(Shape::Named(name.to_owned()))
    }
}

macro_rules! primitive {
    ($method:ident, $shape:ident, $visit:ident, $value:expr) => {
        fn $method<V: Visitor<'de>>(mut self, visitor: V) -> Result<V::Value> {
            self.set(Shape::$shape)?;
            visitor.$visit($value)
        }
    };
}

impl<'de> de::Deserializer<'de> for De<'_> {
    type Error = TraceError;

    fn deserialize_any<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        Err(TraceError(
            "the type needs a self-describing format (untagged or flattened serde attributes); \
             postcard cannot carry it"
                .into(),
        ))
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        self.deserialize_any(visitor)
    }

    primitive!(deserialize_bool, Bool, visit_bool, false);
    primitive!(deserialize_i8, I8, visit_i8, 0);
    primitive!(deserialize_i16, I16, visit_i16, 0);
    primitive!(deserialize_i32, I32, visit_i32, 0);
    primitive!(deserialize_i64, I64, visit_i64, 0);
    primitive!(deserialize_i128, I128, visit_i128, 0);
    primitive!(deserialize_u8, U8, visit_u8, 0);
    primitive!(deserialize_u16, U16, visit_u16, 0);
    primitive!(deserialize_u32, U32, visit_u32, 0);
    primitive!(deserialize_u64, U64, visit_u64, 0);
    primitive!(deserialize_u128, U128, visit_u128, 0);
    primitive!(deserialize_f32, F32, visit_f32, 0.0);
    primitive!(deserialize_f64, F64, visit_f64, 0.0);
    primitive!(deserialize_char, Char, visit_char, 'x');
    primitive!(deserialize_str, Str, visit_borrowed_str, "x");
    primitive!(deserialize_string, Str, visit_string, "x".to_owned());
    primitive!(deserialize_bytes, Bytes, visit_borrowed_bytes, b"");
    primitive!(deserialize_byte_buf, Bytes, visit_byte_buf, Vec::new());
    fn deserialize_unit<V: Visitor<'de>>(mut self, visitor: V) -> Result<V::Value> {
        self.set(Shape::Unit)?;
        visitor.visit_unit()
    }

    fn deserialize_option<V: Visitor<'de>>(mut self, visitor: V) -> Result<V::Value> {
        if self.cut() {
            // Content unexplored at this depth: a shallower visit describes it.
            let unit = self.t.intern(Shape::Unit)?;
            self.set(Shape::Option(unit))?;
            return visitor.visit_none();
        }
        let mut inner = None;
        let value = visitor.visit_some(self.child(&mut inner)?)?;
        let inner = inner.ok_or_else(|| TraceError("option content has no format".into()))?;
        self.set(Shape::Option(inner))?;
        Ok(value)
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(
        mut self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value> {
        self.record_struct(name, Body::Unit)?;
        visitor.visit_unit()
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        mut self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value> {
        let mut inner = None;
        let value = visitor.visit_newtype_struct(self.child(&mut inner)?)?;
        let inner = inner.ok_or_else(|| TraceError(format!("{name} has no format")))?;
        self.record_struct(name, Body::NewType(inner))?;
        Ok(value)
    }

    fn deserialize_seq<V: Visitor<'de>>(mut self, visitor: V) -> Result<V::Value> {
        let explore = !self.cut();
        let mut item = None;
        let value = visitor.visit_seq(Items {
            de: &mut self,
            outs: vec![None],
            remaining: usize::from(explore),
            got: &mut item,
        })?;
        let item = match item {
            Some(i) => i,
            None => self.t.intern(Shape::Unit)?,
        };
        self.set(Shape::Seq(item))?;
        Ok(value)
    }

    fn deserialize_tuple<V: Visitor<'de>>(mut self, len: usize, visitor: V) -> Result<V::Value> {
        let (value, items) = visit_fixed(&mut self, len, visitor)?;
        if items.len() == len && len > 1 && items.iter().all(|i| *i == items[0]) {
            // Arrays [T; N] arrive as tuples; describe them as arrays.
            self.set(Shape::Array(items[0], len as u32))?;
        } else {
            self.set(Shape::Tuple(items))?;
        }
        Ok(value)
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        mut self,
        name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value> {
        let (value, items) = visit_fixed(&mut self, len, visitor)?;
        self.record_struct(name, Body::Tuple(items))?;
        Ok(value)
    }

    fn deserialize_map<V: Visitor<'de>>(mut self, visitor: V) -> Result<V::Value> {
        let explore = !self.cut();
        let mut key = None;
        let mut val = None;
        let value = visitor.visit_map(Entries {
            de: &mut self,
            remaining: usize::from(explore),
            key: &mut key,
            value: &mut val,
        })?;
        let key = match key {
            Some(k) => k,
            None => self.t.intern(Shape::Unit)?,
        };
        let val = match val {
            Some(v) => v,
            None => self.t.intern(Shape::Unit)?,
        };
        self.set(Shape::Map(key, val))?;
        Ok(value)
    }

    fn deserialize_struct<V: Visitor<'de>>(
        mut self,
        name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value> {
        let (value, items) = visit_fixed(&mut self, fields.len(), visitor)?;
        let fields = fields
            .iter()
            .zip(items)
            .map(|(n, shape)| Field {
                name: (*n).to_owned(),
                shape,
            })
            .collect();
        self.record_struct(name, Body::Struct(fields))?;
        Ok(value)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        mut self,
        name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value> {
        if variants.is_empty() {
            return Err(TraceError(format!("enum {name} has no variants")));
        }
        let index = self.t.pick_variant(name, variants);
        let mut body = None;
        let value = visitor.visit_enum(Choice {
            de: &mut self,
            index,
            body: &mut body,
        })?;
        let body = body.ok_or_else(|| TraceError(format!("variant of {name} has no format")))?;
        if let Some(slot) = self
            .t
            .enums
            .get_mut(name)
            .and_then(|info| info.bodies.get_mut(index as usize))
        {
            *slot = Some(body);
        }
        self.set(Shape::Named(name.to_owned()))?;
        Ok(value)
    }

    fn deserialize_identifier<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        Err(TraceError(
            "identifiers are only expected inside enums; the type needs a self-describing format"
                .into(),
        ))
    }

    fn is_human_readable(&self) -> bool {
        false
    }
}

/// Visits `len` items in order (tuples, tuple structs, structs) and returns their shapes.
fn visit_fixed<'de, V: Visitor<'de>>(
    de: &mut De<'_>,
    len: usize,
    visitor: V,
) -> Result<(V::Value, Vec<ShapeIndex>)> {
    let mut unused = None;
    let mut items = Items {
        de,
        outs: vec![None; len],
        remaining: len,
        got: &mut unused,
    };
    let value = visitor.visit_seq(&mut items)?;
    let shapes = items
        .outs
        .into_iter()
        .map(|o| o.ok_or_else(|| TraceError("a field was not visited".into())))
        .collect::<Result<Vec<_>>>()?;
    Ok((value, shapes))
}

/// Sequence access for seqs (one explored item, shape in `got`) and fixed-size visits
/// (`outs[i]` per item).
struct Items<'a, 'b> {
    de: &'a mut De<'b>,
    outs: Vec<Option<ShapeIndex>>,
    remaining: usize,
    got: &'a mut Option<ShapeIndex>,
}

impl<'de> SeqAccess<'de> for Items<'_, '_> {
    type Error = TraceError;

    fn next_element_seed<S: DeserializeSeed<'de>>(&mut self, seed: S) -> Result<Option<S::Value>> {
        if self.remaining == 0 {
            return Ok(None);
        }
        let at = self.outs.len() - self.remaining;
        self.remaining -= 1;
        let mut out = None;
        let value = seed.deserialize(self.de.child(&mut out)?)?;
        if let Some(slot) = self.outs.get_mut(at) {
            *slot = out;
        }
        if self.got.is_none() {
            *self.got = out;
        }
        Ok(Some(value))
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.remaining)
    }
}

/// Map access with at most one explored entry.
struct Entries<'a, 'b> {
    de: &'a mut De<'b>,
    remaining: usize,
    key: &'a mut Option<ShapeIndex>,
    value: &'a mut Option<ShapeIndex>,
}

impl<'de> MapAccess<'de> for Entries<'_, '_> {
    type Error = TraceError;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>> {
        if self.remaining == 0 {
            return Ok(None);
        }
        self.remaining -= 1;
        let mut out = None;
        let key = seed.deserialize(self.de.child(&mut out)?)?;
        *self.key = out;
        Ok(Some(key))
    }

    fn next_value_seed<S: DeserializeSeed<'de>>(&mut self, seed: S) -> Result<S::Value> {
        let mut out = None;
        let value = seed.deserialize(self.de.child(&mut out)?)?;
        *self.value = out;
        Ok(value)
    }
}

/// Enum access that selects variant `index` and records its body.
struct Choice<'a, 'b> {
    de: &'a mut De<'b>,
    index: u32,
    body: &'a mut Option<Body>,
}

impl<'de, 'a, 'b> EnumAccess<'de> for Choice<'a, 'b> {
    type Error = TraceError;
    type Variant = Self;

    fn variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<(S::Value, Self)> {
        let id = seed.deserialize(VariantIndex(self.index))?;
        Ok((id, self))
    }
}

impl<'de> VariantAccess<'de> for Choice<'_, '_> {
    type Error = TraceError;

    fn unit_variant(self) -> Result<()> {
        *self.body = Some(Body::Unit);
        Ok(())
    }

    fn newtype_variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<S::Value> {
        let mut out = None;
        let value = seed.deserialize(self.de.child(&mut out)?)?;
        let inner = out.ok_or_else(|| TraceError("variant content has no format".into()))?;
        *self.body = Some(Body::NewType(inner));
        Ok(value)
    }

    fn tuple_variant<V: Visitor<'de>>(self, len: usize, visitor: V) -> Result<V::Value> {
        let (value, items) = visit_fixed(self.de, len, visitor)?;
        *self.body = Some(Body::Tuple(items));
        Ok(value)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value> {
        let (value, items) = visit_fixed(self.de, fields.len(), visitor)?;
        *self.body = Some(Body::Struct(
            fields
                .iter()
                .zip(items)
                .map(|(n, shape)| Field {
                    name: (*n).to_owned(),
                    shape,
                })
                .collect(),
        ));
        Ok(value)
    }
}

/// Deserializes a variant identifier as its index.
struct VariantIndex(u32);

impl<'de> de::Deserializer<'de> for VariantIndex {
    type Error = TraceError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_u32(self.0)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf option unit unit_struct newtype_struct seq tuple
        tuple_struct map struct enum identifier ignored_any
    }
}
