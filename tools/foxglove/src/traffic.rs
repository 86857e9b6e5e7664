//! The traffic channels: one per message name (and per answer kind), JSON-encoded with a
//! JSON schema derived from the registered format.
//!
//! A query, goal, command, inform or exception goes to the topic of its name; a query's reply
//! to `NAME/reply`; the success, failure or central's error that ends it to `NAME/outcome`.
//! Central's own control traffic (`tca.*`) is left out: `tca log export --json` keeps it.

use std::collections::HashMap;

use serde_json::{Value as J, json};
use tca_messages::{Class, DataFormat, Envelope, Failure, MessageName, RouteError};

use crate::schema::{class_data_schema, envelope_schema};

/// A message name's registered formats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Formats {
    /// The data format.
    pub format: DataFormat,
    /// The reply format (queries).
    pub reply: Option<DataFormat>,
}

/// The registered formats by message name.
pub type FormatTable = HashMap<MessageName, Formats>;

/// The topic a message of `class` named `name` goes to, or `None` for control traffic.
pub fn topic(name: &str, class: Class) -> Option<String> {
    match class {
        Class::Control => None,
        _ if name.starts_with("tca.") => None,
        Class::Reply => Some(format!("{name}/reply")),
        Class::Success | Class::Failure | Class::Error => Some(format!("{name}/outcome")),
        _ => Some(name.to_owned()),
    }
}

/// The JSON schema of `topic`'s messages (see [`topic`]), from the formats registered for
/// `name`; `None` when they are not known.
pub fn topic_schema(topic: &str, name: &str, class: Class, formats: &FormatTable) -> Option<J> {
    let known = MessageName::new(name).ok().and_then(|n| formats.get(&n));
    let data = class_data_schema(
        class,
        known.map(|k| &k.format),
        known.and_then(|k| k.reply.as_ref()),
    )?;
    Some(envelope_schema(topic, data))
}

/// The data of `envelope` decoded through its formats, as JSON (`Value::to_json`).
pub fn data_json(envelope: &Envelope, formats: &FormatTable) -> Result<J, String> {
    let fixed = |f: Result<DataFormat, tca_messages::FormatError>| {
        f.map_err(|e| e.to_string())
            .and_then(|f| f.decode_value(&envelope.data).map_err(|e| e.to_string()))
    };
    let value = match envelope.class {
        Class::Success => fixed(DataFormat::of::<()>())?,
        Class::Failure => fixed(DataFormat::of::<Failure>())?,
        Class::Error => fixed(DataFormat::of::<RouteError>())?,
        class => {
            let known = formats
                .get(&envelope.name)
                .ok_or_else(|| format!("{} is not registered", envelope.name))?;
            let format = if class == Class::Reply {
                known
                    .reply
                    .as_ref()
                    .ok_or_else(|| format!("{} has no reply format", envelope.name))?
            } else {
                &known.format
            };
            format
                .decode_value(&envelope.data)
                .map_err(|e| e.to_string())?
        }
    };
    Ok(value.to_json())
}

/// One traffic message as JSON: the envelope's header and the decoded data (the shape
/// [`crate::schema::envelope_schema`] describes).
pub fn message_json(envelope: &Envelope, data: J) -> J {
    json!({
        "class": envelope.class.as_str(),
        "sender": envelope.sender.as_str(),
        "id": envelope.id.to_string(),
        "node": envelope.node.map(|n| n.0),
        "context": envelope.context.map(|n| n.0),
        "correlation": envelope.correlation.map(|c| c.to_string()),
        "timestamp_ns": envelope.timestamp_ns,
        "redelivery": envelope.redelivery,
        "data": data,
    })
}
