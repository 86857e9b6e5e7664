//! Comparing what modules sent in two runs (`tca log replay`): message by message, per
//! (sender, message name, kind) in order, field by field through the registered formats.
//!
//! **What is compared.** Every query, goal, command, inform and exception a compared module
//! sent, and every answer (reply, success, failure) it gave, inside each log's window (the
//! replayed part of the run). The *n*-th message of a stream in the record is paired with the
//! *n*-th of the same stream in the live run; a stream is (sender, message name, kind), where
//! the kind is the class for messages a module sends on its own and "answer to the asker" for
//! replies, successes and failures (so an answer that turned from success into failure is one
//! difference, not two). Answers are paired per asker and in the order they were asked for:
//! requests from different askers, and the answers to concurrent requests, may interleave
//! differently from run to run.
//!
//! **What is not compared**, by rule rather than by accident:
//!
//! - the envelope header: message ids, task-node ids, link numbers and timestamps. Ids name
//!   messages and nodes and depend on the order of connection; stamps carry computing time,
//!   which modules on simulated time may charge from the wall clock;
//! - the data fields the [`Rules`] name as `ignored` (measurements of the wall clock, say);
//! - the data fields the [`Rules`] name as `message_ids` are message ids: they are compared
//!   through the pairing (the recorded id must name the message paired with the one the live
//!   id names), not as numbers.
//!
//! The rules belong to the vocabulary being compared: whoever knows the messages gives them.
//!
//! Floats are compared exactly (NaN equals NaN): a module that is deterministic given identical
//! inputs sends identical data, so any change is a divergence.

use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::ops::Range;

use serde::Serialize;
use tca_messages::{Class, Envelope, Value};

use crate::reader::LogFile;
use crate::record::{Direction, RecordKind};

/// A data field excluded from, or specially treated by, the comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FieldRule {
    /// Message name.
    pub message: &'static str,
    /// Which data: the message's own ([`Class::Query`] etc.) or its reply ([`Class::Reply`]).
    pub class: Class,
    /// Field path, as printed in divergences (`target.x_m`).
    pub path: &'static str,
    /// Why.
    pub why: &'static str,
}

/// Which stream a message belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum StreamKind {
    /// A message the module sent on its own, by class.
    Sent(ClassKey),
    /// A reply, success or failure.
    Answer,
}

/// A class usable as a key (queries, goals, commands, informs, exceptions, control).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ClassKey {
    /// Query.
    Query,
    /// Goal.
    Goal,
    /// Command.
    Command,
    /// Inform.
    Inform,
    /// Exception.
    Exception,
}

impl StreamKind {
    fn of(class: Class) -> Option<Self> {
        Some(match class {
            Class::Query => StreamKind::Sent(ClassKey::Query),
            Class::Goal => StreamKind::Sent(ClassKey::Goal),
            Class::Command => StreamKind::Sent(ClassKey::Command),
            Class::Inform => StreamKind::Sent(ClassKey::Inform),
            Class::Exception => StreamKind::Sent(ClassKey::Exception),
            Class::Reply | Class::Success | Class::Failure => StreamKind::Answer,
            _ => return None,
        })
    }
}

/// One message a module sent, as found in a log.
#[derive(Clone, Debug)]
pub struct SentMessage {
    /// Position in the log's records.
    pub position: usize,
    /// The envelope.
    pub envelope: Envelope,
}

/// Which stream a message belongs to.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct StreamKey {
    /// The module that sent it.
    pub sender: String,
    /// Message name.
    pub name: String,
    /// Sent on its own, or an answer.
    pub kind: StreamKind,
    /// For answers: the module that asked (answers to different askers interleave as the
    /// askers' requests do, so each asker's answers are a stream of their own).
    pub asker: Option<String>,
}

/// Every message sent inside `window` (positions in `log.records`), by stream, in order.
/// Control traffic and central's own messages are left out.
pub fn streams(log: &LogFile, window: Range<usize>) -> BTreeMap<StreamKey, Vec<SentMessage>> {
    let mut out: BTreeMap<StreamKey, Vec<SentMessage>> = BTreeMap::new();
    let end = window.end.min(log.records.len());
    let start = window.start.min(end);
    // Who sent each message that can be answered (from the log's start: the asker of an
    // answer in the window may have asked before it).
    let mut askers: HashMap<u64, (String, usize)> = HashMap::new();
    let mut asked_at: HashMap<usize, usize> = HashMap::new();
    for (position, record) in log.records[..end].iter().enumerate() {
        let RecordKind::Frame(f) = &record.kind else {
            continue;
        };
        if f.direction != Direction::In {
            continue;
        }
        let Ok(env) = LogFile::envelope(f) else {
            continue;
        };
        if env.name.is_control() {
            continue;
        }
        let Some(kind) = StreamKind::of(env.class) else {
            continue;
        };
        let sender = f
            .peer
            .as_ref()
            .map_or_else(|| env.sender.to_string(), |p| p.to_string());
        let asker = match kind {
            StreamKind::Answer => match env.correlation.and_then(|c| askers.get(&c.0)) {
                Some((asker, asked)) => {
                    asked_at.insert(position, *asked);
                    Some(asker.clone())
                }
                None => Some("?".into()),
            },
            StreamKind::Sent(_) => {
                askers.insert(env.id.0, (sender.clone(), position));
                None
            }
        };
        if position < start {
            continue;
        }
        let key = StreamKey {
            sender,
            name: env.name.to_string(),
            kind,
            asker,
        };
        out.entry(key).or_default().push(SentMessage {
            position,
            envelope: env,
        });
    }
    // Answers in the order they were asked for: a module answering concurrent requests may
    // finish them in any order.
    for (key, list) in out.iter_mut() {
        if key.kind == StreamKind::Answer {
            list.sort_by_key(|m| asked_at.get(&m.position).copied().unwrap_or(m.position));
        }
    }
    out
}

/// What differs.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Difference {
    /// A field's value.
    Field {
        /// Field path (`target.x_m`, `cells[12]`; empty for the whole data).
        path: String,
        /// Recorded value.
        recorded: String,
        /// Live value.
        live: String,
    },
    /// The answer's class (success, failure, reply).
    Answer {
        /// Recorded answer.
        recorded: String,
        /// Live answer.
        live: String,
    },
    /// Recorded, but not sent in the live run.
    Missing,
    /// Sent in the live run, but not in the record.
    Extra,
    /// The data could not be decoded through its format.
    Undecodable {
        /// Why.
        reason: String,
    },
}

/// One message that differs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Divergence {
    /// Sender.
    pub sender: String,
    /// Message name.
    pub name: String,
    /// Stream kind.
    pub stream: StreamKind,
    /// For answers: the module that asked.
    pub asker: Option<String>,
    /// 1-based index in its stream.
    pub index: usize,
    /// What differs.
    pub difference: Difference,
    /// Ordering: position in the live log (or after every live message, for missing ones).
    #[serde(skip)]
    order: (u8, usize),
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match (self.stream, &self.asker) {
            (StreamKind::Sent(_), _) => String::new(),
            (StreamKind::Answer, Some(asker)) => format!(" answer to {asker}"),
            (StreamKind::Answer, None) => " answer".into(),
        };
        write!(f, "{} -> {}{what} #{}", self.sender, self.name, self.index)?;
        match &self.difference {
            Difference::Field {
                path,
                recorded,
                live,
            } if path.is_empty() => {
                write!(f, ", data: recorded {recorded}, live {live}")
            }
            Difference::Field {
                path,
                recorded,
                live,
            } => {
                write!(f, ", field {path}: recorded {recorded}, live {live}")
            }
            Difference::Answer { recorded, live } => {
                write!(f, ": recorded {recorded}, live {live}")
            }
            Difference::Missing => f.write_str(": recorded, but never sent in the replay"),
            Difference::Extra => f.write_str(": sent in the replay, but not in the record"),
            Difference::Undecodable { reason } => write!(f, ": data not decodable: {reason}"),
        }
    }
}

/// The result of a comparison.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Comparison {
    /// Messages paired and compared.
    pub compared: usize,
    /// Every divergence, first first.
    pub divergences: Vec<Divergence>,
}

impl Comparison {
    /// Whether every message matched.
    pub fn all_match(&self) -> bool {
        self.divergences.is_empty()
    }
}

/// Which field rules apply. The default has none: every data field is compared as a value.
#[derive(Clone, Debug, Default)]
pub struct Rules {
    /// Fields never compared.
    pub ignored: Vec<FieldRule>,
    /// Fields holding message ids.
    pub message_ids: Vec<FieldRule>,
}

/// One side of a comparison: a log and its window.
#[derive(Clone, Copy, Debug)]
pub struct Side<'a> {
    /// The log.
    pub log: &'a LogFile,
    /// Positions of its records to consider.
    pub window: &'a Range<usize>,
}

/// Compares the messages the modules in `senders` sent in `recorded` and `live`. Messages of
/// every sender are paired (the pairing maps recorded message ids to live ones), but only
/// those of `senders` are compared.
pub fn compare(
    recorded: Side<'_>,
    live: Side<'_>,
    senders: &[String],
    rules: &Rules,
) -> Comparison {
    let rec = streams(recorded.log, recorded.window.clone());
    let liv = streams(live.log, live.window.clone());
    // Pair every stream, so ids in data can be mapped.
    let mut ids: HashMap<u64, u64> = HashMap::new();
    for (key, r) in &rec {
        if let Some(l) = liv.get(key) {
            for (a, b) in r.iter().zip(l) {
                ids.insert(a.envelope.id.0, b.envelope.id.0);
            }
        }
    }
    let mut result = Comparison::default();
    let mut keys: Vec<&StreamKey> = rec.keys().chain(liv.keys()).collect();
    keys.sort();
    keys.dedup();
    for key in keys {
        if !senders.iter().any(|s| s == &key.sender) {
            continue;
        }
        let empty = Vec::new();
        let r = rec.get(key).unwrap_or(&empty);
        let l = liv.get(key).unwrap_or(&empty);
        let divergence = |index: usize, difference: Difference, order: (u8, usize)| Divergence {
            sender: key.sender.clone(),
            name: key.name.clone(),
            stream: key.kind,
            asker: key.asker.clone(),
            index: index + 1,
            difference,
            order,
        };
        for i in 0..r.len().max(l.len()) {
            match (r.get(i), l.get(i)) {
                (Some(a), Some(b)) => {
                    result.compared += 1;
                    if let Some(d) = compare_one(recorded.log, a, live.log, b, rules, &ids) {
                        result.divergences.push(divergence(i, d, (0, b.position)));
                    }
                }
                (Some(a), None) => {
                    result
                        .divergences
                        .push(divergence(i, Difference::Missing, (1, a.position)));
                }
                (None, Some(b)) => {
                    result
                        .divergences
                        .push(divergence(i, Difference::Extra, (0, b.position)));
                }
                (None, None) => {}
            }
        }
    }
    result.divergences.sort_by_key(|d| d.order);
    result
}

fn answer_word(class: Class) -> &'static str {
    match class {
        Class::Reply => "reply",
        Class::Success => "success",
        Class::Failure => "failure",
        _ => "other",
    }
}

/// Compares one pair of messages of the same stream.
fn compare_one(
    rlog: &LogFile,
    a: &SentMessage,
    llog: &LogFile,
    b: &SentMessage,
    rules: &Rules,
    ids: &HashMap<u64, u64>,
) -> Option<Difference> {
    let (ra, lb) = (&a.envelope, &b.envelope);
    if ra.class != lb.class {
        let describe = |log: &LogFile, e: &Envelope| match (e.class, log.data_value(e)) {
            (Class::Failure, Ok(v)) => format!("failure ({})", short(&v)),
            (c, _) => answer_word(c).to_owned(),
        };
        return Some(Difference::Answer {
            recorded: describe(rlog, ra),
            live: describe(llog, lb),
        });
    }
    let data_class = ra.class;
    let applies = |list: &[FieldRule]| -> Vec<&'static str> {
        list.iter()
            .filter(|r| r.message == ra.name.as_str() && r.class == data_class)
            .map(|r| r.path)
            .collect()
    };
    let id_paths = applies(&rules.message_ids);
    let ignored = applies(&rules.ignored);
    if ra.data == lb.data && id_paths.is_empty() {
        return None;
    }
    let rv = match rlog.data_value(ra) {
        Ok(v) => v,
        Err(reason) => {
            return (ra.data != lb.data).then(|| Difference::Undecodable {
                reason: format!("recorded: {reason}"),
            });
        }
    };
    let lv = match llog.data_value(lb) {
        Ok(v) => v,
        Err(reason) => {
            return Some(Difference::Undecodable {
                reason: format!("live: {reason}"),
            });
        }
    };
    let rules = DiffRules {
        ignored: &ignored,
        ids: &id_paths,
        id_map: ids,
    };
    first_difference(&rv, &lv, &rules).map(|(path, recorded, live)| Difference::Field {
        path,
        recorded,
        live,
    })
}

/// How [`first_difference`] treats special fields.
#[derive(Clone, Copy, Debug)]
pub struct DiffRules<'a> {
    /// Paths not compared.
    pub ignored: &'a [&'a str],
    /// Paths holding message ids, compared through `id_map` (recorded -> live).
    pub ids: &'a [&'a str],
    /// Recorded message id -> live message id.
    pub id_map: &'a HashMap<u64, u64>,
}

/// The first field where `recorded` and `live` differ, depth first in field order: its path
/// and both values, shortened for printing. `None` if they are equal.
pub fn first_difference(
    recorded: &Value,
    live: &Value,
    rules: &DiffRules<'_>,
) -> Option<(String, String, String)> {
    diff(recorded, live, rules, "")
}

fn join(path: &str, field: &str) -> String {
    if path.is_empty() {
        field.to_owned()
    } else {
        format!("{path}.{field}")
    }
}

fn diff(
    a: &Value,
    b: &Value,
    rules: &DiffRules<'_>,
    path: &str,
) -> Option<(String, String, String)> {
    if rules.ignored.contains(&path) {
        return None;
    }
    let here = || Some((path.to_owned(), short(a), short(b)));
    if rules.ids.contains(&path) {
        let mapped = map_ids(a, rules.id_map);
        return if same(&mapped, b) { None } else { here() };
    }
    match (a, b) {
        (Value::Struct { fields: fa, .. }, Value::Struct { fields: fb, .. }) => {
            for ((na, va), (nb, vb)) in fa.iter().zip(fb) {
                if na != nb {
                    return here();
                }
                if let Some(d) = diff(va, vb, rules, &join(path, na)) {
                    return Some(d);
                }
            }
            if fa.len() != fb.len() { here() } else { None }
        }
        (
            Value::Variant {
                variant: xa,
                body: ba,
                ..
            },
            Value::Variant {
                variant: xb,
                body: bb,
                ..
            },
        ) => {
            if xa != xb {
                return here();
            }
            diff(ba, bb, rules, path)
        }
        (Value::Option(Some(x)), Value::Option(Some(y))) => diff(x, y, rules, path),
        (Value::Seq(xs), Value::Seq(ys)) => {
            for (i, (x, y)) in xs.iter().zip(ys).enumerate() {
                if let Some(d) = diff(x, y, rules, &format!("{path}[{i}]")) {
                    return Some(d);
                }
            }
            (xs.len() != ys.len()).then(|| {
                (
                    path.to_owned(),
                    format!("{} items", xs.len()),
                    format!("{} items", ys.len()),
                )
            })
        }
        (Value::Map(xs), Value::Map(ys)) => {
            for ((kx, x), (ky, y)) in xs.iter().zip(ys) {
                if !same(kx, ky) {
                    return here();
                }
                if let Some(d) = diff(x, y, rules, &format!("{path}[{}]", short(kx))) {
                    return Some(d);
                }
            }
            (xs.len() != ys.len()).then(|| {
                (
                    path.to_owned(),
                    format!("{} entries", xs.len()),
                    format!("{} entries", ys.len()),
                )
            })
        }
        _ if same(a, b) => None,
        _ => here(),
    }
}

/// Equality with NaN equal to NaN.
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Float(x), Value::Float(y)) => x == y || (x.is_nan() && y.is_nan()),
        (Value::Option(Some(x)), Value::Option(Some(y))) => same(x, y),
        (Value::Seq(xs), Value::Seq(ys)) => {
            xs.len() == ys.len() && xs.iter().zip(ys).all(|(x, y)| same(x, y))
        }
        (Value::Map(xs), Value::Map(ys)) => {
            xs.len() == ys.len()
                && xs
                    .iter()
                    .zip(ys)
                    .all(|((kx, x), (ky, y))| same(kx, ky) && same(x, y))
        }
        (
            Value::Struct {
                name: na,
                fields: fa,
            },
            Value::Struct {
                name: nb,
                fields: fb,
            },
        ) => {
            na == nb
                && fa.len() == fb.len()
                && fa
                    .iter()
                    .zip(fb)
                    .all(|((x, vx), (y, vy))| x == y && same(vx, vy))
        }
        (
            Value::Variant {
                name: na,
                variant: xa,
                body: ba,
            },
            Value::Variant {
                name: nb,
                variant: xb,
                body: bb,
            },
        ) => na == nb && xa == xb && same(ba, bb),
        _ => a == b,
    }
}

/// Replaces message ids (unsigned integers) by their live counterparts; unknown ids stay.
fn map_ids(v: &Value, map: &HashMap<u64, u64>) -> Value {
    match v {
        Value::UInt(u) => match u64::try_from(*u).ok().and_then(|k| map.get(&k)) {
            Some(&m) => Value::UInt(u128::from(m)),
            None => v.clone(),
        },
        Value::Option(Some(x)) => Value::Option(Some(Box::new(map_ids(x, map)))),
        Value::Struct { name, fields } => Value::Struct {
            name: name.clone(),
            fields: fields
                .iter()
                .map(|(n, x)| (n.clone(), map_ids(x, map)))
                .collect(),
        },
        other => other.clone(),
    }
}

/// A value printed for a divergence line: at most 80 characters.
fn short(v: &Value) -> String {
    const MAX: usize = 80;
    let s = v.to_string();
    if s.chars().count() <= MAX {
        s
    } else {
        let cut: String = s.chars().take(MAX).collect();
        format!("{cut}...")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reader::KnownFormat;
    use crate::record::{FrameRecord, LogRecord};
    use serde::{Deserialize, Serialize};
    use tca_messages::{DataFormat, MessageId, MessageName, ModuleName, NodeId, SendOptions};

    #[derive(Serialize, Deserialize, Clone, Copy)]
    struct Point {
        x_m: f64,
        y_m: f64,
    }

    #[derive(Serialize, Deserialize, Clone, Copy)]
    struct Place {
        target: Point,
        base_m: f64,
    }

    #[derive(Serialize, Deserialize, Clone, Copy)]
    struct Step {
        step: u32,
        after_move: Option<MessageId>,
    }

    fn envelope(id: MessageId, class: Class, name: &str, sender: &str, data: Vec<u8>) -> Envelope {
        Envelope {
            id,
            class,
            name: MessageName::new(name).unwrap(),
            sender: ModuleName::new(sender).unwrap(),
            context: Some(NodeId(1)),
            node: None,
            correlation: None,
            cause: None,
            timestamp_ns: id.0,
            options: SendOptions::default(),
            redelivery: 0,
            data,
        }
    }

    /// A log of `planner` sending `placeTool` goals with these targets, then `planMove`s
    /// naming the previous message, on link `link`.
    fn log(link: u32, targets: &[(f64, f64)], steps: u32, answer_fails: bool) -> LogFile {
        let mut records = Vec::new();
        let mut push = |env: Envelope| {
            records.push(LogRecord {
                at_ns: 0,
                kind: RecordKind::Frame(FrameRecord {
                    direction: Direction::In,
                    link,
                    peer: Some(env.sender.clone()),
                    name: env.name.clone(),
                    class: env.class,
                    frame: tca_messages::encode(&env).unwrap().into(),
                }),
            });
        };
        let mut seq = 10;
        let mut next = || {
            seq += 1;
            MessageId::new(link, seq)
        };
        let walk = next();
        push(envelope(walk, Class::Goal, "job", "user", vec![]));
        let mut previous = None;
        for &(x, y) in targets {
            let data = postcard::to_allocvec(&Place {
                target: Point { x_m: x, y_m: y },
                base_m: 2.0,
            })
            .unwrap();
            let id = next();
            push(envelope(id, Class::Goal, "placeTool", "planner", data));
            previous = Some(id);
        }
        for step in 0..steps {
            let data = postcard::to_allocvec(&Step {
                step,
                after_move: previous,
            })
            .unwrap();
            push(envelope(next(), Class::Goal, "planMove", "planner", data));
        }
        let (class, data) = if answer_fails {
            let f = tca_messages::Failure {
                reason: "no target".into(),
            };
            (Class::Failure, postcard::to_allocvec(&f).unwrap())
        } else {
            (Class::Success, postcard::to_allocvec(&()).unwrap())
        };
        let mut answer = envelope(next(), class, "job", "planner", data);
        answer.correlation = Some(walk);
        push(answer);
        // Another module's message, not compared.
        push(envelope(next(), Class::Inform, "note", "camera", vec![7]));
        let mut formats = HashMap::new();
        let known = |format: DataFormat| KnownFormat {
            class: Class::Goal,
            format,
            reply: None,
        };
        formats.insert(
            MessageName::new("placeTool").unwrap(),
            known(DataFormat::of::<Place>().unwrap()),
        );
        formats.insert(
            MessageName::new("planMove").unwrap(),
            known(DataFormat::of::<Step>().unwrap()),
        );
        LogFile {
            path: "test.mcap".into(),
            records,
            formats,
            truncated: None,
        }
    }

    /// The test vocabulary's rule: `planMove.after_move` names a message.
    fn rules() -> Rules {
        Rules {
            ignored: Vec::new(),
            message_ids: vec![FieldRule {
                message: "planMove",
                class: Class::Goal,
                path: "after_move",
                why: "names the previous move",
            }],
        }
    }

    fn run(a: &LogFile, b: &LogFile) -> Comparison {
        let (wa, wb) = (0..a.records.len(), 0..b.records.len());
        compare(
            Side {
                log: a,
                window: &wa,
            },
            Side {
                log: b,
                window: &wb,
            },
            &["planner".to_owned()],
            &rules(),
        )
    }

    #[test]
    fn identical_runs_match_even_on_other_links() {
        let a = log(3, &[(1.0, 2.0), (1.5, 2.5)], 2, false);
        let b = log(7, &[(1.0, 2.0), (1.5, 2.5)], 2, false);
        let c = run(&a, &b);
        assert!(c.all_match(), "{:?}", c.divergences);
        // two placeTool, two planMove, one job answer; camera's inform is not compared
        assert_eq!(c.compared, 5);
    }

    #[test]
    fn a_changed_field_is_named_with_both_values() {
        let a = log(3, &[(1.0, 2.0), (1.55, 2.5)], 0, false);
        let b = log(3, &[(1.0, 2.0), (1.65, 2.5)], 0, false);
        let c = run(&a, &b);
        assert_eq!(c.divergences.len(), 1);
        assert_eq!(
            c.divergences[0].to_string(),
            "planner -> placeTool #2, field target.x_m: recorded 1.55, live 1.65"
        );
    }

    #[test]
    fn missing_and_extra_messages_are_divergences_and_live_ones_come_first() {
        let a = log(3, &[(1.0, 2.0), (1.5, 2.5)], 0, false);
        let b = log(3, &[(1.0, 2.0)], 1, false);
        let c = run(&a, &b);
        let lines: Vec<String> = c.divergences.iter().map(|d| d.to_string()).collect();
        assert_eq!(
            lines,
            [
                "planner -> planMove #1: sent in the replay, but not in the record",
                "planner -> placeTool #2: recorded, but never sent in the replay",
            ]
        );
    }

    #[test]
    fn an_answer_turned_failure_is_one_divergence() {
        let a = log(3, &[], 0, false);
        let b = log(3, &[], 0, true);
        let c = run(&a, &b);
        assert_eq!(c.divergences.len(), 1, "{:?}", c.divergences);
        let line = c.divergences[0].to_string();
        assert!(
            line.starts_with("planner -> job answer to user #1: recorded success, live failure"),
            "{line}"
        );
        assert!(line.contains("no target"), "{line}");
    }

    #[test]
    fn message_id_fields_are_compared_through_the_pairing() {
        // On another link the ids differ as numbers but name the paired message: a match.
        let a = log(3, &[(1.0, 2.0)], 1, false);
        let b = log(9, &[(1.0, 2.0)], 1, false);
        assert!(run(&a, &b).all_match());
        // The same number but naming another message: a divergence.
        let rules = Rules::default();
        let (wa, wb) = (0..a.records.len(), 0..b.records.len());
        let c = compare(
            Side {
                log: &a,
                window: &wa,
            },
            Side {
                log: &b,
                window: &wb,
            },
            &["planner".to_owned()],
            &rules,
        );
        assert_eq!(c.divergences.len(), 1);
        assert!(
            c.divergences[0].to_string().contains("field after_move"),
            "{:?}",
            c.divergences
        );
    }

    #[test]
    fn windows_limit_what_is_compared() {
        let a = log(3, &[(1.0, 2.0), (1.5, 2.5)], 0, false);
        let b = log(3, &[(1.0, 2.0), (9.0, 2.5)], 0, false);
        // The walk goal and the first placeTool.
        let (wa, wb) = (0..2, 0..2);
        let c = compare(
            Side {
                log: &a,
                window: &wa,
            },
            Side {
                log: &b,
                window: &wb,
            },
            &["planner".to_owned()],
            &rules(),
        );
        assert!(c.all_match());
        assert_eq!(c.compared, 1);
    }

    fn v_struct(fields: Vec<(&str, Value)>) -> Value {
        Value::Struct {
            name: "S".into(),
            fields: fields.into_iter().map(|(n, v)| (n.to_owned(), v)).collect(),
        }
    }

    #[test]
    fn paths_name_sequence_items_variants_and_lengths() {
        let none = HashMap::new();
        let rules = DiffRules {
            ignored: &[],
            ids: &[],
            id_map: &none,
        };
        let cell = |variant: &str, body: Value| Value::Variant {
            name: "MapCell".into(),
            variant: variant.into(),
            body: Box::new(body),
        };
        let a = v_struct(vec![(
            "cells",
            Value::Seq(vec![
                cell("Known", Value::Float(0.5)),
                cell("Unknown", Value::Unit),
            ]),
        )]);
        let b = v_struct(vec![(
            "cells",
            Value::Seq(vec![
                cell("Known", Value::Float(0.5)),
                cell("Known", Value::Float(0.25)),
            ]),
        )]);
        assert_eq!(
            first_difference(&a, &b, &rules),
            Some(("cells[1]".into(), "Unknown".into(), "Known(0.25)".into()))
        );
        let c = v_struct(vec![(
            "cells",
            Value::Seq(vec![cell("Known", Value::Float(0.5))]),
        )]);
        assert_eq!(
            first_difference(&a, &c, &rules),
            Some(("cells".into(), "2 items".into(), "1 items".into()))
        );
        assert_eq!(first_difference(&a, &a, &rules), None);
        // NaN equals NaN; ignored paths are skipped.
        let n = v_struct(vec![
            ("x", Value::Float(f64::NAN)),
            ("clock_s", Value::Float(1.0)),
        ]);
        let m = v_struct(vec![
            ("x", Value::Float(f64::NAN)),
            ("clock_s", Value::Float(2.0)),
        ]);
        assert!(first_difference(&n, &m, &rules).is_some());
        let ignoring = DiffRules {
            ignored: &["clock_s"],
            ..rules
        };
        assert_eq!(first_difference(&n, &m, &ignoring), None);
    }

    #[test]
    fn long_values_are_shortened() {
        let long = Value::Str("x".repeat(500));
        assert!(short(&long).len() < 100);
    }
}
