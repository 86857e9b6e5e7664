//! Driving a running system by hand, the way the `ros2` command line does: list what is
//! registered, echo a name's traffic, call a query, send a goal, command or inform, kill a
//! task, stop everything. Each command is a short-lived module that connects to central.
//!
//! - [`list`]: `tca list [NAME]`: modules, their messages, formats and JSON templates.
//! - [`echo`]: `tca echo NAME...`: a name's traffic as it happens, decoded.
//! - [`call`]: `tca call NAME JSON`: a query; its reply as JSON.
//! - [`send`]: `tca send NAME JSON`: a goal, command or inform; a task's outcome.
//! - [`kill`]: `tca kill NODE|MESSAGE-ID`: a task and its subtree.
//! - [`stop`]: `tca stop`: every task tree killed, then the halt sent.
//!
//! Data is given as JSON and encoded through the format the handling module registered, so
//! these commands work for any message, including ones this binary was not compiled with.

pub(crate) mod call;
pub(crate) mod echo;
pub(crate) mod kill;
pub(crate) mod list;
pub(crate) mod send;
pub(crate) mod stop;

use anyhow::Context as _;
use tca_messages::DataFormat;
use tca_messages::control::{Registry, RegistryEntry};
use tca_module::{Connector, Module};

use super::ConnectArgs;

/// Connects a short-lived tool module named `tool-PID` to central.
pub(crate) async fn connect(args: &ConnectArgs, tool: &str) -> anyhow::Result<Module> {
    let endpoint = args.endpoint_or_default();
    let connector = Connector::zenoh(endpoint.clone());
    Module::builder(format!("{tool}-{}", std::process::id()))
        .connect(&connector)
        .await
        .with_context(|| format!("cannot reach central at {endpoint}"))
}

/// The registry entry of `name`, or an error naming the closest registered name.
pub(crate) fn find<'a>(registry: &'a Registry, name: &str) -> anyhow::Result<&'a RegistryEntry> {
    if let Some(e) = registry.entries.iter().find(|e| e.name.as_str() == name) {
        return Ok(e);
    }
    let hint = closest(name, registry.entries.iter().map(|e| e.name.as_str()))
        .map(|c| format!("did you mean {c}? "))
        .unwrap_or_default();
    anyhow::bail!(
        "no module registers a message named {name:?}; {hint}`tca list` shows what is registered"
    )
}

/// Reads the data argument: JSON text, `null` when absent.
pub(crate) fn parse_json(name: &str, text: Option<&str>) -> anyhow::Result<serde_json::Value> {
    let Some(text) = text else {
        return Ok(serde_json::Value::Null);
    };
    serde_json::from_str(text).map_err(|e| {
        anyhow::anyhow!(
            "the data for {name} is not valid JSON ({e}); give it as one argument in single \
             quotes, e.g. '{{\"target_y_m\": 2.0}}' (`tca list {name}` shows a template)"
        )
    })
}

/// Encodes JSON data through the format `entry` registered; the error names the field.
pub(crate) fn encode(entry: &RegistryEntry, json: &serde_json::Value) -> anyhow::Result<Vec<u8>> {
    entry.format.encode_json(json).map_err(|e| {
        anyhow::anyhow!(
            "the data does not fit the format {} registered for {}: {e}\n  format: {}\n  \
             template: {}",
            entry.handler,
            entry.name,
            entry.format,
            entry.format.json_template()
        )
    })
}

/// Postcard data decoded through `format` as JSON; what cannot be decoded is shown as such.
pub(crate) fn decode(format: &DataFormat, data: &[u8]) -> serde_json::Value {
    match format.decode_value(data) {
        Ok(v) => v.to_json(),
        Err(e) => serde_json::json!({ "undecodable": e.to_string(), "bytes": data.len() }),
    }
}

/// The closest of `candidates` to `name`, when it is close enough to be a slip.
fn closest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    candidates
        .map(|c| {
            let c_lower = c.to_ascii_lowercase();
            // A prefix of a name counts as a slip, however short.
            let d = if c_lower.starts_with(&lower) && lower.len() >= 3 {
                1
            } else {
                tca_messages::spelling::edit_distance(&lower, &c_lower)
            };
            (d, c)
        })
        .filter(|(d, c)| *d <= 2.max(c.len() / 3))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}
