//! The bridge file (TOML): which centrals, which messages each way, the delays, the log.
//!
//! ```toml
//! name = "bridge"                  # the bridge's module name on both centrals (default)
//! robot = "tcp/127.0.0.1:7447"     # the robot's central: Controller and sensors
//! ground = "tcp/127.0.0.1:7448"    # the operators' central: their tools and planners
//! log = "out/bridge/bridge.mcap"   # every crossing (optional)
//! query_timeout_s = 30             # a forwarded query's own timeout, on the far side (default)
//! wait_s = 60                      # how long to wait at the start for the messages named
//!
//! [up]                             # sent on the ground side, handled on the robot side
//! delay_s = 1.3
//! messages = ["legged.legMove", "legged.bodyPose", "legged.halt"]
//! query_timeout_s = { "legged.robotModel" = 60 }   # per query (optional)
//!
//! [down]                           # sent on the robot side, handled on the ground side
//! delay_s = 1.3
//! messages = ["legged.telemetry"]
//! optional = ["legged.moveFailed"]
//! ```
//!
//! A message is named by its exact name, which the bridge waits for (until `wait_s`), or by
//! a pattern (`*` any run of characters, `?` one), which takes whatever the handling side has
//! registered when the bridge starts; `optional = [...]` beside `messages` names what is
//! taken if it is there when the bridge starts, and not waited for (exceptions that only
//! some ground tools handle, for example). Every class crosses: queries (their replies come back),
//! goals and commands (their success or failure comes back), informs, and exceptions raised
//! inside a forwarded goal or command.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Deserialize;
use tca_messages::MessageName;
use tca_module::Connector;

use crate::error::{BridgeError, Result};
use crate::side::Direction;

/// The bridge's module name unless the file says otherwise.
pub const DEFAULT_NAME: &str = "bridge";

/// How long the bridge waits at the start for the messages it names, unless told.
pub const DEFAULT_WAIT: Duration = Duration::from_secs(60);

/// Longest delay accepted (a day): anything longer is a typing mistake.
const MAX_DELAY_S: f64 = 86_400.0;

/// A bridge file as written.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BridgeFile {
    /// The bridge's module name on both centrals.
    pub name: Option<String>,
    /// The robot-side central's endpoint.
    pub robot: Option<String>,
    /// The ground-side central's endpoint.
    pub ground: Option<String>,
    /// Where to log every crossing (MCAP).
    pub log: Option<PathBuf>,
    /// A forwarded query's own timeout on the far side, seconds.
    pub query_timeout_s: Option<f64>,
    /// How long to wait at the start for the messages named, seconds.
    pub wait_s: Option<f64>,
    /// Ground to robot.
    #[serde(default)]
    pub up: Way,
    /// Robot to ground.
    #[serde(default)]
    pub down: Way,
}

/// `[up]` or `[down]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Way {
    /// The delay this way, seconds (default 0).
    pub delay_s: Option<f64>,
    /// Message names or patterns.
    #[serde(default)]
    pub messages: Vec<String>,
    /// Names or patterns taken when the handling side has them as the bridge starts, not
    /// waited for.
    #[serde(default)]
    pub optional: Vec<String>,
    /// Own timeouts of some queries, seconds.
    #[serde(default)]
    pub query_timeout_s: BTreeMap<String, f64>,
}

/// A message name or a pattern of a bridge file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NamePattern {
    /// An exact name: the bridge waits for it.
    Exact(MessageName),
    /// A pattern (`*`, `?`): what matches when the bridge starts.
    Glob(String),
}

impl NamePattern {
    /// Reads a name or pattern; a wrong one is refused saying why.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        if text.contains(['*', '?']) {
            let bad = text
                .chars()
                .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '*' | '?')));
            return match bad {
                Some(c) => Err(format!(
                    "the pattern {text:?} has {c:?}: names have letters, digits, '_', '-' and \
                     '.', patterns also '*' and '?'"
                )),
                None => Ok(NamePattern::Glob(text.to_owned())),
            };
        }
        let name = MessageName::new(text).map_err(|e| e.to_string())?;
        if name
            .as_str()
            .starts_with(tca_messages::control::CONTROL_PREFIX)
        {
            return Err(format!(
                "{text} is one of central's own control messages; each central keeps its own"
            ));
        }
        Ok(NamePattern::Exact(name))
    }

    /// Whether `name` is this name or matches this pattern.
    pub fn matches(&self, name: &str) -> bool {
        match self {
            NamePattern::Exact(n) => n.as_str() == name,
            NamePattern::Glob(p) => tca_central::policy::glob_match(p, name),
        }
    }
}

impl std::fmt::Display for NamePattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NamePattern::Exact(n) => write!(f, "{n}"),
            NamePattern::Glob(p) => f.write_str(p),
        }
    }
}

/// What a bridge does, checked: the file's settings with the command line's over them.
#[derive(Clone, Debug)]
pub struct BridgeConfig {
    /// The bridge's module name on both centrals.
    pub name: String,
    /// How to reach the robot-side central.
    pub robot: Connector,
    /// How to reach the ground-side central.
    pub ground: Connector,
    /// Ground-to-robot traffic.
    pub up: WayConfig,
    /// Robot-to-ground traffic.
    pub down: WayConfig,
    /// A forwarded query's own timeout on the far side, unless its way names one.
    pub query_timeout: Duration,
    /// How long to wait at the start for the exact names.
    pub wait: Duration,
    /// Where to log every crossing.
    pub log: Option<PathBuf>,
}

/// One way's settings.
#[derive(Clone, Debug, Default)]
pub struct WayConfig {
    /// Added to everything crossing this way.
    pub delay: Duration,
    /// What crosses (exact names are waited for).
    pub messages: Vec<NamePattern>,
    /// What crosses if the handling side has it when the bridge starts.
    pub optional: Vec<NamePattern>,
    /// Own timeouts of some queries.
    pub query_timeouts: BTreeMap<MessageName, Duration>,
}

impl BridgeConfig {
    /// A bridge between `robot` and `ground` forwarding nothing yet, with no delay.
    pub fn new(robot: Connector, ground: Connector) -> Self {
        BridgeConfig {
            name: DEFAULT_NAME.to_owned(),
            robot,
            ground,
            up: WayConfig::default(),
            down: WayConfig::default(),
            query_timeout: tca_module::DEFAULT_QUERY_TIMEOUT,
            wait: DEFAULT_WAIT,
            log: None,
        }
    }

    /// One way's settings.
    pub fn way(&self, direction: Direction) -> &WayConfig {
        match direction {
            Direction::Up => &self.up,
            Direction::Down => &self.down,
        }
    }

    /// One way's settings, to change.
    pub fn way_mut(&mut self, direction: Direction) -> &mut WayConfig {
        match direction {
            Direction::Up => &mut self.up,
            Direction::Down => &mut self.down,
        }
    }

    /// The delay one way.
    pub fn delay(&self, direction: Direction) -> Duration {
        self.way(direction).delay
    }

    /// A forwarded query's own timeout on the far side.
    pub fn query_timeout(&self, direction: Direction, name: &MessageName) -> Duration {
        self.way(direction)
            .query_timeouts
            .get(name)
            .copied()
            .unwrap_or(self.query_timeout)
    }

    /// How long the near side waits for a forwarded query's answer: the delay up and down
    /// plus the query's own timeout on the far side (and a second for the answer's own
    /// journey through both centrals).
    pub fn answer_within(&self, direction: Direction, name: &MessageName) -> Duration {
        self.delay(direction)
            + self.delay(direction.reverse())
            + self.query_timeout(direction, name)
            + Duration::from_secs(1)
    }

    /// Checks what a file cannot check alone: a name crossing both ways, a module name.
    pub fn check(&self) -> Result<()> {
        tca_messages::ModuleName::new(self.name.clone())
            .map_err(|e| BridgeError::Config(format!("the bridge's name {:?}: {e}", self.name)))?;
        let all = |w: &WayConfig| -> Vec<NamePattern> {
            w.messages.iter().chain(&w.optional).cloned().collect()
        };
        let down = all(&self.down);
        for up in &all(&self.up) {
            if let NamePattern::Exact(n) = up
                && down.contains(up)
            {
                return Err(BridgeError::Config(format!(
                    "{n} is named both [up] and [down]; a message crosses one way (its answers \
                     come back by themselves)"
                )));
            }
        }
        for d in Direction::BOTH {
            for name in self.way(d).query_timeouts.keys() {
                if !self
                    .way(d)
                    .messages
                    .iter()
                    .any(|p| p.matches(name.as_str()))
                {
                    return Err(BridgeError::Config(format!(
                        "[{d}] query_timeout_s names {name}, which [{d}] messages does not \
                         forward; add it to messages or remove its timeout"
                    )));
                }
            }
        }
        Ok(())
    }
}

impl BridgeFile {
    /// Reads and parses a bridge file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| BridgeError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text)
            .map_err(|e| BridgeError::Config(format!("bridge file {}: {e}", path.display())))
    }

    /// Parses bridge-file text; the error says what is wrong where.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }

    /// The checked configuration, with `robot` and `ground` endpoints given on the command
    /// line taking the file's place.
    pub fn config(&self, robot: Option<&str>, ground: Option<&str>) -> Result<BridgeConfig> {
        let endpoint = |given: Option<&str>, file: &Option<String>, key: &str| {
            given
                .map(str::to_owned)
                .or_else(|| file.clone())
                .ok_or_else(|| {
                    BridgeError::Config(format!(
                        "no {key} central: give its endpoint as `{key} = \"tcp/HOST:PORT\"` in \
                         the bridge file or with --{key}"
                    ))
                })
        };
        let robot = endpoint(robot, &self.robot, "robot")?;
        let ground = endpoint(ground, &self.ground, "ground")?;
        if robot == ground {
            return Err(BridgeError::Config(format!(
                "the robot and ground sides are both {robot}: a bridge joins two different \
                 centrals"
            )));
        }
        let mut config = BridgeConfig::new(
            Connector::endpoint(robot.clone()),
            Connector::endpoint(ground.clone()),
        );
        if let Some(name) = &self.name {
            config.name = name.clone();
        }
        if let Some(t) = self.query_timeout_s {
            config.query_timeout = positive("query_timeout_s", t)?;
        }
        if let Some(w) = self.wait_s {
            config.wait = seconds("wait_s", w)?;
        }
        config.log = self.log.clone();
        for (d, way) in [(Direction::Up, &self.up), (Direction::Down, &self.down)] {
            let c = config.way_mut(d);
            c.delay = delay(d, way.delay_s.unwrap_or(0.0))?;
            for m in &way.messages {
                let p = NamePattern::parse(m)
                    .map_err(|e| BridgeError::Config(format!("[{d}] messages: {e}")))?;
                if !c.messages.contains(&p) {
                    c.messages.push(p);
                }
            }
            for m in &way.optional {
                let p = NamePattern::parse(m)
                    .map_err(|e| BridgeError::Config(format!("[{d}] optional: {e}")))?;
                if !c.optional.contains(&p) {
                    c.optional.push(p);
                }
            }
            for (name, t) in &way.query_timeout_s {
                let n = MessageName::new(name.clone()).map_err(|e| {
                    BridgeError::Config(format!("[{d}] query_timeout_s: {name:?}: {e}"))
                })?;
                let t = positive(&format!("[{d}] query_timeout_s.{name}"), *t)?;
                c.query_timeouts.insert(n, t);
            }
        }
        config.check()?;
        Ok(config)
    }
}

/// A delay: zero or more seconds, at most a day.
pub fn delay(direction: Direction, s: f64) -> Result<Duration> {
    if !(s.is_finite() && (0.0..=MAX_DELAY_S).contains(&s)) {
        return Err(BridgeError::Config(format!(
            "the {direction} delay {s} s is not valid: give a number of seconds from 0 to \
             {MAX_DELAY_S}"
        )));
    }
    Ok(Duration::from_secs_f64(s))
}

fn seconds(what: &str, s: f64) -> Result<Duration> {
    Duration::try_from_secs_f64(s).map_err(|_| {
        BridgeError::Config(format!(
            "{what} = {s} is not valid: give a number of seconds, 0 or more"
        ))
    })
}

fn positive(what: &str, s: f64) -> Result<Duration> {
    match seconds(what, s) {
        Ok(d) if !d.is_zero() => Ok(d),
        _ => Err(BridgeError::Config(format!(
            "{what} = {s} is not valid: give a positive number of seconds"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = r#"
        robot = "tcp/127.0.0.1:7447"
        ground = "tcp/127.0.0.1:7448"
        log = "out/bridge.mcap"
        [up]
        delay_s = 1.3
        messages = ["legMove", "pose", "legged.*"]
        query_timeout_s = { "pose" = 5 }
        [down]
        delay_s = 0.25
        messages = ["telemetry"]
    "#;

    #[test]
    fn a_file_gives_its_settings() {
        let c = BridgeFile::parse(FILE).unwrap().config(None, None).unwrap();
        assert_eq!(c.name, "bridge");
        assert_eq!(c.up.delay, Duration::from_millis(1300));
        assert_eq!(c.down.delay, Duration::from_millis(250));
        assert_eq!(c.up.messages.len(), 3);
        assert!(c.up.messages[2].matches("legged.halt"));
        assert!(!c.up.messages[2].matches("legMove2"));
        let pose = MessageName::new("pose").unwrap();
        assert_eq!(
            c.query_timeout(Direction::Up, &pose),
            Duration::from_secs(5)
        );
        let other = MessageName::new("legMove").unwrap();
        assert_eq!(
            c.query_timeout(Direction::Up, &other),
            tca_module::DEFAULT_QUERY_TIMEOUT
        );
        // Twice the delay plus its own timeout, and a second for the centrals.
        assert_eq!(
            c.answer_within(Direction::Up, &pose),
            Duration::from_millis(1300 + 250 + 5000 + 1000)
        );
        assert_eq!(c.log.as_deref(), Some(Path::new("out/bridge.mcap")));
    }

    #[test]
    fn the_command_line_endpoints_take_the_files_place() {
        let c = BridgeFile::parse(FILE)
            .unwrap()
            .config(Some("tcp/127.0.0.1:9000"), None)
            .unwrap();
        assert!(
            c.robot.describe().ends_with("at tcp/127.0.0.1:9000"),
            "{}",
            c.robot.describe()
        );
    }

    #[test]
    fn mistakes_are_refused_saying_what_to_change() {
        let cases = [
            ("[up]\ndelay = 1", "unknown field `delay`"),
            ("ground = \"tcp/a:1\"", "no robot central"),
            ("robot = \"tcp/a:1\"\nground = \"tcp/a:1\"", "two different"),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\n[up]\ndelay_s = -1",
                "up delay -1 s is not valid",
            ),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\n[down]\ndelay_s = inf",
                "down delay inf s",
            ),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\n[up]\nmessages = [\"a b\"]",
                "[up] messages",
            ),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\n[up]\nmessages = [\"tca.kill\"]",
                "control messages",
            ),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\n[up]\nmessages = [\"x\"]\n[down]\nmessages = [\"x\"]",
                "named both [up] and [down]",
            ),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\n[up]\nmessages = [\"x\"]\nquery_timeout_s = { y = 3 }",
                "does not forward",
            ),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\nquery_timeout_s = 0",
                "positive number",
            ),
            (
                "robot = \"tcp/a:1\"\nground = \"tcp/b:1\"\nname = \"my bridge\"",
                "the bridge's name",
            ),
        ];
        for (text, expected) in cases {
            let e = BridgeFile::parse(text)
                .map_err(BridgeError::Config)
                .and_then(|f| f.config(None, None))
                .unwrap_err()
                .to_string();
            assert!(e.contains(expected), "{text:?}: {e}");
        }
    }
}
