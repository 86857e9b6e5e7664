//! JSON schemas derived from registered data formats.
//!
//! The schema describes exactly the JSON that [`tca_messages::Value::to_json`] writes for
//! data of that format (the JSON `tca echo --json` prints): structs are objects, newtype
//! structs their inner value, tuple structs and tuples arrays, unit enum variants strings and
//! other variants `{"Variant": body}`, maps with text or integer keys objects (others arrays
//! of `[key, value]` pairs), byte strings arrays of numbers, and floats numbers (or strings
//! for values that are not finite). Named types are inlined; a type that contains itself is
//! described as any value past its first appearance.

use serde_json::{Map, Value as J, json};
use tca_messages::format::{Body, Container, Shape, ShapeIndex};
use tca_messages::{Class, DataFormat, Failure, RouteError};

/// The JSON schema (draft 2020-12) of data in `format`, as `Value::to_json` writes it.
pub fn data_schema(format: &DataFormat) -> J {
    let mut walker = Walker {
        format,
        stack: Vec::new(),
    };
    walker.shape(format.root_index())
}

/// The schema of one message on a traffic channel: the envelope's header fields and the data
/// (see [`crate::traffic::TrafficMessage::to_json`]). `data` is the data's schema.
pub fn envelope_schema(title: &str, data: J) -> J {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
        "properties": {
            "class": {"type": "string", "description": "query, goal, command, inform, exception, reply, success, failure or error"},
            "sender": {"type": "string", "description": "the module that sent it"},
            "id": {"type": "string", "description": "the message's id"},
            "node": {"type": ["integer", "null"], "description": "its task-tree node"},
            "context": {"type": ["integer", "null"], "description": "the node it was sent from"},
            "correlation": {"type": ["string", "null"], "description": "the message it answers"},
            "timestamp_ns": {"type": "integer", "description": "the sender's stamp (simulated time when the modules ran on it), nanoseconds"},
            "redelivery": {"type": "integer"},
            "data": data,
        },
        "required": ["class", "sender", "id", "timestamp_ns", "data"],
    })
}

/// The data schema of a message of `class` whose name registered `registered` (data format)
/// and `reply` (reply format): replies use the reply format, successes carry nothing,
/// failures a [`Failure`] and central's errors a [`RouteError`]. `None` when the format to
/// use is not known.
pub fn class_data_schema(
    class: Class,
    registered: Option<&DataFormat>,
    reply: Option<&DataFormat>,
) -> Option<J> {
    match class {
        Class::Reply => reply.map(data_schema),
        Class::Success => DataFormat::of::<()>().ok().map(|f| data_schema(&f)),
        Class::Failure | Class::Error => {
            let failure = DataFormat::of::<Failure>().ok()?;
            let error = DataFormat::of::<RouteError>().ok()?;
            Some(json!({"anyOf": [data_schema(&failure), data_schema(&error)]}))
        }
        _ => registered.map(data_schema),
    }
}

struct Walker<'a> {
    format: &'a DataFormat,
    /// Named types being expanded (to stop at a type that contains itself).
    stack: Vec<String>,
}

fn number() -> J {
    json!({"type": ["number", "string"], "description": "a number; a value that is not finite is written as a string (NaN, inf, -inf)"})
}

impl Walker<'_> {
    fn shape(&mut self, index: ShapeIndex) -> J {
        let Ok(shape) = self.format.shape(index) else {
            return json!({});
        };
        match shape.clone() {
            Shape::Unit => json!({"type": "null"}),
            Shape::Bool => json!({"type": "boolean"}),
            Shape::I8 | Shape::I16 | Shape::I32 | Shape::I64 => json!({"type": "integer"}),
            Shape::U8 | Shape::U16 | Shape::U32 | Shape::U64 => {
                json!({"type": "integer", "minimum": 0})
            }
            Shape::I128 | Shape::U128 => json!({
                "type": ["integer", "string"],
                "description": "an integer; one beyond 64 bits is written as a string"
            }),
            Shape::F32 | Shape::F64 => number(),
            Shape::Char => json!({"type": "string", "minLength": 1, "maxLength": 1}),
            Shape::Str => json!({"type": "string"}),
            Shape::Bytes => {
                json!({"type": "array", "items": {"type": "integer", "minimum": 0, "maximum": 255}})
            }
            Shape::Option(inner) => {
                let inner = self.shape(inner);
                json!({"anyOf": [{"type": "null"}, inner]})
            }
            Shape::Seq(item) => json!({"type": "array", "items": self.shape(item)}),
            Shape::Array(item, n) => json!({
                "type": "array",
                "items": self.shape(item),
                "minItems": n,
                "maxItems": n,
            }),
            Shape::Tuple(items) => self.tuple(&items),
            Shape::Map(key, value) => self.map(key, value),
            Shape::Named(name) => self.named(&name),
        }
    }

    fn tuple(&mut self, items: &[ShapeIndex]) -> J {
        let prefix: Vec<J> = items.iter().map(|i| self.shape(*i)).collect();
        json!({
            "type": "array",
            "prefixItems": prefix,
            "minItems": items.len(),
            "maxItems": items.len(),
        })
    }

    fn map(&mut self, key: ShapeIndex, value: ShapeIndex) -> J {
        let text_key = matches!(
            self.format.shape(key),
            Ok(Shape::Str
                | Shape::Char
                | Shape::I8
                | Shape::I16
                | Shape::I32
                | Shape::I64
                | Shape::I128
                | Shape::U8
                | Shape::U16
                | Shape::U32
                | Shape::U64
                | Shape::U128)
        );
        let value_schema = self.shape(value);
        if text_key {
            json!({"type": "object", "additionalProperties": value_schema})
        } else {
            let key_schema = self.shape(key);
            json!({"anyOf": [
                {"type": "array", "items": {
                    "type": "array",
                    "prefixItems": [key_schema, value_schema],
                    "minItems": 2,
                    "maxItems": 2,
                }},
                {"type": "object", "maxProperties": 0},
            ]})
        }
    }

    fn named(&mut self, name: &str) -> J {
        if self.stack.iter().any(|n| n == name) {
            return json!({"description": format!("a {name} (contains itself: any value here)")});
        }
        let Ok(container) = self.format.named(name) else {
            return json!({});
        };
        let container = container.clone();
        self.stack.push(name.to_owned());
        let mut schema = match &container {
            Container::Struct(body) => self.struct_body(body),
            Container::Enum(variants) => {
                let options: Vec<J> = variants
                    .iter()
                    .map(|v| match &v.body {
                        Body::Unit => json!({"const": v.name}),
                        body => {
                            let inner = self.variant_body(body);
                            let mut props = Map::new();
                            props.insert(v.name.clone(), inner);
                            json!({
                                "type": "object",
                                "properties": props,
                                "required": [v.name],
                                "additionalProperties": false,
                            })
                        }
                    })
                    .collect();
                json!({"oneOf": options})
            }
        };
        self.stack.pop();
        if let J::Object(m) = &mut schema {
            m.insert("title".into(), J::String(name.to_owned()));
        }
        schema
    }

    /// A struct's JSON: `{}` for a unit struct, the inner value for a newtype, an array for
    /// a tuple struct, an object for named fields.
    fn struct_body(&mut self, body: &Body) -> J {
        match body {
            Body::Unit => json!({"type": "object", "maxProperties": 0}),
            Body::NewType(i) => self.shape(*i),
            Body::Tuple(items) => self.tuple_struct(items),
            Body::Struct(fields) => self.fields(fields),
        }
    }

    /// A variant's body (never a unit).
    fn variant_body(&mut self, body: &Body) -> J {
        match body {
            Body::Unit => json!({"type": "null"}),
            Body::NewType(i) => self.shape(*i),
            Body::Tuple(items) => self.tuple_struct(items),
            Body::Struct(fields) => self.fields(fields),
        }
    }

    fn tuple_struct(&mut self, items: &[ShapeIndex]) -> J {
        // `Value::to_json` writes a one-field tuple as its field.
        if let [only] = items {
            return self.shape(*only);
        }
        self.tuple(items)
    }

    fn fields(&mut self, fields: &[tca_messages::format::Field]) -> J {
        if fields.is_empty() {
            return json!({"type": "object", "maxProperties": 0});
        }
        let mut props = Map::new();
        let mut required = Vec::new();
        for f in fields {
            props.insert(f.name.clone(), self.shape(f.shape));
            required.push(J::String(f.name.clone()));
        }
        json!({
            "type": "object",
            "properties": props,
            "required": required,
            "additionalProperties": false,
        })
    }
}
