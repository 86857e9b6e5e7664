//! Finding what the bridge forwards: each name or pattern of a way, looked up in the registry
//! of the side that handles it, waiting for exact names that are not there yet.

use std::collections::BTreeMap;
use std::time::Duration;

use tca_messages::control::{Registration, Registry, RegistryEntry};
use tca_messages::{Class, MessageName};
use tca_module::Module;

use crate::error::{BridgeError, Result};
use crate::file::{BridgeConfig, NamePattern};
use crate::side::{Direction, Side};

/// How often the registries are asked again while names are missing.
const POLL: Duration = Duration::from_millis(250);

/// How often the bridge says what it still waits for.
const SAY_EVERY: Duration = Duration::from_secs(5);

/// One message the bridge forwards.
#[derive(Clone, Debug, PartialEq)]
pub struct Forwarded {
    /// The way it crosses.
    pub direction: Direction,
    /// Its registration on the side that handles it (the far side), which the bridge makes
    /// on the side it leaves.
    pub entry: RegistryEntry,
}

impl Forwarded {
    /// Its name.
    pub fn name(&self) -> &MessageName {
        &self.entry.name
    }

    /// Its class.
    pub fn class(&self) -> Class {
        self.entry.class
    }

    /// The registration the bridge makes for it on the side it leaves.
    pub fn registration(&self) -> Registration {
        Registration {
            name: self.entry.name.clone(),
            class: self.entry.class,
            format: self.entry.format.clone(),
            reply: self.entry.reply.clone(),
            replace: false,
        }
    }
}

/// Exact names not registered yet on the side that handles them, with the way they cross.
pub(crate) type Missing = Vec<(Direction, MessageName)>;

/// What each way's names and patterns select in `registries` (robot's, ground's): the
/// forwarded messages, and the exact names not there yet, with their way.
pub(crate) fn select(
    config: &BridgeConfig,
    registries: [&Registry; 2],
) -> Result<(Vec<Forwarded>, Missing)> {
    let mut found: BTreeMap<MessageName, Forwarded> = BTreeMap::new();
    let mut missing = Vec::new();
    for d in Direction::BOTH {
        let registry = registries[d.to().index()];
        let way = config.way(d);
        let required = way.messages.iter().map(|p| (p, true));
        for (pattern, required) in required.chain(way.optional.iter().map(|p| (p, false))) {
            let matching: Vec<&RegistryEntry> = registry
                .entries
                .iter()
                // What the bridge registered itself (an earlier run's) is not a handler.
                .filter(|e| e.handler.as_str() != config.name && pattern.matches(e.name.as_str()))
                .filter(|e| e.class.is_handled())
                .collect();
            if matching.is_empty()
                && required
                && let NamePattern::Exact(name) = pattern
            {
                missing.push((d, name.clone()));
            }
            for e in matching {
                if let Some(other) = found.get(&e.name)
                    && other.direction != d
                {
                    return Err(BridgeError::Config(format!(
                        "{} is selected both [up] and [down] (by {}); a message crosses one way: \
                         narrow the patterns",
                        e.name, pattern
                    )));
                }
                found.insert(
                    e.name.clone(),
                    Forwarded {
                        direction: d,
                        entry: e.clone(),
                    },
                );
            }
        }
    }
    for d in Direction::BOTH {
        for name in config.way(d).query_timeouts.keys() {
            if let Some(f) = found.get(name)
                && f.class() != Class::Query
            {
                return Err(BridgeError::Config(format!(
                    "[{d}] query_timeout_s names {name}, a {}: only queries have timeouts",
                    f.class()
                )));
            }
        }
    }
    Ok((found.into_values().collect(), missing))
}

/// Asks both sides' registries (through `probes`, robot's then ground's) until every exact
/// name is registered on the side that handles it, at most `config.wait`; then returns what
/// is forwarded.
pub(crate) async fn wait_for(
    config: &BridgeConfig,
    probes: [&Module; 2],
) -> Result<Vec<Forwarded>> {
    let started = tokio::time::Instant::now();
    let mut said = started;
    loop {
        let mut registries = Vec::with_capacity(2);
        for (side, probe) in Side::BOTH.into_iter().zip(probes) {
            let r = probe.registry().await.map_err(|e| {
                BridgeError::Connect(format!(
                    "the {side} side's central did not give its registry: {e}"
                ))
            })?;
            registries.push(r);
        }
        let (found, missing) = select(config, [&registries[0], &registries[1]])?;
        if missing.is_empty() {
            return Ok(found);
        }
        let waited = started.elapsed();
        if waited >= config.wait {
            return Err(BridgeError::Missing(describe_missing(&missing, waited)));
        }
        if said.elapsed() >= SAY_EVERY {
            said = tokio::time::Instant::now();
            tracing::warn!("the bridge waits: {}", describe_missing(&missing, waited));
        }
        tokio::time::sleep(POLL).await;
    }
}

fn describe_missing(missing: &[(Direction, MessageName)], waited: Duration) -> String {
    let mut by_side: BTreeMap<Side, Vec<String>> = BTreeMap::new();
    for (d, name) in missing {
        by_side.entry(d.to()).or_default().push(name.to_string());
    }
    let parts: Vec<String> = by_side
        .into_iter()
        .map(|(side, names)| {
            format!(
                "the {side} side's central has no handler for {} (it must handle what crosses \
                 to it: start the modules that do)",
                names.join(", ")
            )
        })
        .collect();
    format!("after {:.1} s {}", waited.as_secs_f64(), parts.join("; "))
}

#[cfg(test)]
mod tests {
    use tca_messages::{DataFormat, ModuleName};

    use super::*;
    use crate::file::BridgeFile;

    fn entry(name: &str, class: Class, handler: &str) -> RegistryEntry {
        RegistryEntry {
            name: MessageName::new(name).unwrap(),
            class,
            handler: ModuleName::new(handler).unwrap(),
            connected: true,
            format: DataFormat::of::<u32>().unwrap(),
            reply: (class == Class::Query).then(|| DataFormat::of::<u32>().unwrap()),
            waiting: 0,
        }
    }

    fn registry(entries: Vec<RegistryEntry>) -> Registry {
        Registry {
            entries,
            modules: Vec::new(),
        }
    }

    fn config(text: &str) -> BridgeConfig {
        let text = format!("robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\n{text}");
        BridgeFile::parse(&text)
            .unwrap()
            .config(None, None)
            .unwrap()
    }

    #[test]
    fn names_are_looked_up_on_the_side_that_handles_them() {
        let c = config(
            "[up]\nmessages = [\"legged.*\", \"pose\"]\n[down]\nmessages = [\"telemetry\", \"missing\"]\noptional = [\"absent\", \"fault\"]",
        );
        let robot = registry(vec![
            entry("legged.legMove", Class::Command, "controller"),
            entry("legged.halt", Class::Command, "controller"),
            entry("pose", Class::Query, "controller"),
            // Registered on the robot side by the bridge itself (an earlier run): not taken.
            entry("legged.telemetry", Class::Inform, "bridge"),
        ]);
        let ground = registry(vec![
            entry("telemetry", Class::Inform, "monitor"),
            entry("fault", Class::Exception, "walker"),
            entry("legged.legMove", Class::Command, "bridge"),
        ]);
        let (found, missing) = select(&c, [&robot, &ground]).unwrap();
        let up: Vec<&str> = found
            .iter()
            .filter(|f| f.direction == Direction::Up)
            .map(|f| f.name().as_str())
            .collect();
        assert_eq!(up, ["legged.halt", "legged.legMove", "pose"]);
        let down: Vec<&str> = found
            .iter()
            .filter(|f| f.direction == Direction::Down)
            .map(|f| f.name().as_str())
            .collect();
        assert_eq!(down, ["fault", "telemetry"]);
        assert_eq!(
            missing,
            vec![(Direction::Down, MessageName::new("missing").unwrap())]
        );
        let text = describe_missing(&missing, Duration::from_secs(3));
        assert!(
            text.contains("the ground side's central has no handler for missing"),
            "{text}"
        );
    }

    #[test]
    fn a_name_selected_both_ways_or_a_timeout_on_a_command_is_refused() {
        let c = config("[up]\nmessages = [\"a*\"]\n[down]\nmessages = [\"*b\"]");
        let robot = registry(vec![entry("ab", Class::Command, "controller")]);
        let ground = registry(vec![entry("ab", Class::Command, "operator")]);
        let e = select(&c, [&robot, &ground]).unwrap_err().to_string();
        assert!(e.contains("both [up] and [down]"), "{e}");
        let c = config("[up]\nmessages = [\"move\"]\nquery_timeout_s = { move = 2 }");
        let robot = registry(vec![entry("move", Class::Command, "controller")]);
        let e = select(&c, [&robot, &registry(vec![])])
            .unwrap_err()
            .to_string();
        assert!(e.contains("only queries have timeouts"), "{e}");
    }
}
