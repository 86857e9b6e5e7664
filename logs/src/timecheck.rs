//! Proving from a log that a run kept time: every temporal constraint held in the time the
//! task tree saw (simulated time, when central kept it), no module handled more goals,
//! commands and exceptions at once than its capacity, and every answer is stamped no earlier
//! than the message it answers.
//!
//! - **Constraints.** The task-tree operations the log recorded are replayed into a fresh
//!   tree; each point (handling start and end, achievement start and end) occurs at the time of
//!   the operation that made it occur. Every constraint given with a node or added later must
//!   have its `before` point no later than its `after` point. A `before` point that never
//!   occurred (its node was killed or retired first) is not a violation: the tree counts it as
//!   satisfied.
//! - **Capacity.** Each goal, command and exception delivered to a module is handled from the
//!   stamp it was delivered with to the stamp of the module's answer (or, if cancelled, of the
//!   cancel). At no time may more of them overlap on one module than the capacity its hello
//!   gave. A delivery never answered because the module went away ends when its link closed.
//! - **Answers.** A reply, success or failure is stamped no earlier than the delivery it
//!   answers.

use std::collections::{BTreeMap, HashMap};

use serde::Serialize;
use tca_messages::control::{ControlNotice, ControlRequest};
use tca_messages::{Class, MessageId, ModuleName};
use tca_task_tree::{Endpoint, NewConstraint, Point, TaskTree, TreeEvent, TreeOp};

use crate::reader::LogFile;
use crate::record::{Direction, LinkEvent, RecordKind};

/// What the time check found.
#[derive(Clone, Debug, Default, Serialize)]
pub struct TimeCheck {
    /// Temporal constraints checked (both points occurred).
    pub constraints: usize,
    /// Deliveries of goals, commands and exceptions whose handling was checked against
    /// their module's capacity.
    pub handlings: usize,
    /// Answers checked against what they answer.
    pub answers: usize,
    /// Everything that did not hold, as sentences.
    pub violations: Vec<String>,
}

impl TimeCheck {
    /// Whether everything held.
    pub fn holds(&self) -> bool {
        self.violations.is_empty()
    }

    /// A readable summary.
    pub fn text(&self) -> String {
        let mut s = format!(
            "time: {} constraints held in the tree's time, {} handlings within their modules' \
             capacity, {} answers no earlier than their questions\n",
            self.constraints, self.handlings, self.answers
        );
        if self.holds() {
            s.push_str("time kept\n");
        }
        for v in &self.violations {
            s.push_str(&format!("TIME: {v}\n"));
        }
        s
    }
}

/// Checks a log (see the module documentation).
pub fn time_check(log: &LogFile) -> TimeCheck {
    let mut check = TimeCheck::default();
    check_constraints(log, &mut check);
    check_handlings(log, &mut check);
    check
}

fn point_of(event: &TreeEvent) -> Option<(tca_task_tree::NodeId, Point)> {
    Some(match event {
        TreeEvent::HandlingStarted(n) => (*n, Point::HandlingStart),
        TreeEvent::HandlingEnded(n) => (*n, Point::HandlingEnd),
        TreeEvent::AchievementStarted(n) => (*n, Point::AchievementStart),
        TreeEvent::Achieved(n) => (*n, Point::AchievementEnd),
        _ => return None,
    })
}

fn check_constraints(log: &LogFile, check: &mut TimeCheck) {
    let mut tree = TaskTree::new();
    let mut times: HashMap<Endpoint, u64> = HashMap::new();
    let mut constraints: Vec<(Endpoint, Endpoint)> = Vec::new();
    for record in &log.records {
        let RecordKind::Tree(t) = &record.kind else {
            continue;
        };
        let op = &t.op;
        match op {
            TreeOp::AddNode { id, spec, .. } => {
                for c in &spec.constraints {
                    match c {
                        NewConstraint::After { before, point } => {
                            constraints.push((*before, Endpoint::new(*id, *point)))
                        }
                        NewConstraint::Before { point, after } => {
                            constraints.push((Endpoint::new(*id, *point), *after))
                        }
                        NewConstraint::PlanFirst => {}
                    }
                }
            }
            TreeOp::AddConstraint { constraint, .. } => {
                constraints.push((constraint.before, constraint.after));
            }
            _ => {}
        }
        let now = op.now();
        match tree.apply(op) {
            Ok(events) => {
                for e in &events {
                    if let Some((node, point)) = point_of(e) {
                        times.entry(Endpoint::new(node, point)).or_insert(now);
                    }
                }
            }
            Err(e) => check.violations.push(format!(
                "the recorded tree operation {op:?} does not replay: {e}"
            )),
        }
    }
    for (before, after) in constraints {
        let (Some(&tb), Some(&ta)) = (times.get(&before), times.get(&after)) else {
            continue;
        };
        check.constraints += 1;
        if tb > ta {
            check.violations.push(format!(
                "constraint {before} <= {after} broken: {before} at {:.3} s, {after} at {:.3} s",
                tb as f64 / 1e9,
                ta as f64 / 1e9
            ));
        }
    }
}

/// One delivery of a task-like message to a module.
struct Handling {
    module: ModuleName,
    name: String,
    start: u64,
    end: Option<u64>,
}

fn check_handlings(log: &LogFile, check: &mut TimeCheck) {
    let mut capacity: HashMap<ModuleName, u32> = HashMap::new();
    let mut handlings: BTreeMap<MessageId, Handling> = BTreeMap::new();
    // Deliveries of any handled message, for the answer check: id -> (module, stamp).
    let mut delivered: HashMap<MessageId, (ModuleName, u64)> = HashMap::new();
    let mut link_module: HashMap<u32, ModuleName> = HashMap::new();
    for record in &log.records {
        match &record.kind {
            RecordKind::Link(l) => {
                if let Some(m) = &l.module {
                    link_module.insert(l.link, m.clone());
                }
                if l.event == LinkEvent::Closed
                    && let Some(m) = &l.module
                {
                    // What it was handling ends with it (no simulated end is known).
                    handlings.retain(|_, h| !(h.end.is_none() && &h.module == m));
                }
            }
            RecordKind::Frame(f) => {
                let Ok(env) = LogFile::envelope(f) else {
                    continue;
                };
                // A hello names its module itself: it comes before the link has one.
                if f.direction == Direction::In {
                    match ControlRequest::decode(env.name.as_str(), &env.data) {
                        Ok(ControlRequest::Hello(h)) => {
                            capacity.insert(h.module, h.capacity.max(1));
                        }
                        Ok(ControlRequest::HelloAuth(a)) => {
                            capacity.insert(a.hello.module, a.hello.capacity.max(1));
                        }
                        _ => {}
                    }
                }
                let Some(peer) = f.peer.clone().or_else(|| link_module.get(&f.link).cloned())
                else {
                    continue;
                };
                match f.direction {
                    Direction::In => {
                        if matches!(env.class, Class::Reply | Class::Success | Class::Failure)
                            && let Some(c) = env.correlation
                        {
                            if let Some((m, t)) = delivered.get(&c)
                                && m == &peer
                            {
                                check.answers += 1;
                                if env.timestamp_ns < *t {
                                    check.violations.push(format!(
                                        "{peer} answered {} {c} at {:.3} s, before it was \
                                         delivered at {:.3} s",
                                        env.name,
                                        env.timestamp_ns as f64 / 1e9,
                                        *t as f64 / 1e9
                                    ));
                                }
                            }
                            if let Some(h) = handlings.get_mut(&c)
                                && h.module == peer
                                && h.end.is_none()
                            {
                                h.end = Some(env.timestamp_ns);
                            }
                        }
                    }
                    Direction::Out => {
                        if env.class.is_handled() {
                            delivered.insert(env.id, (peer.clone(), env.timestamp_ns));
                        }
                        if env.class.runs_in_turn() {
                            handlings.insert(
                                env.id,
                                Handling {
                                    module: peer.clone(),
                                    name: env.name.to_string(),
                                    start: env.timestamp_ns,
                                    end: None,
                                },
                            );
                        }
                        if let Some(ControlNotice::Cancel(_)) =
                            ControlNotice::decode(env.name.as_str(), &env.data)
                            && let Some(c) = env.correlation
                            && let Some(h) = handlings.get_mut(&c)
                            && h.end.is_none()
                        {
                            h.end = Some(env.timestamp_ns);
                        }
                    }
                }
            }
            _ => {}
        }
    }
    // Per module, sweep the intervals: +1 at a start, -1 at an end (ends first at a tie, as
    // a task delivered at the instant another ended does not overlap it).
    let mut by_module: HashMap<&ModuleName, Vec<(u64, i32, &Handling)>> = HashMap::new();
    for h in handlings.values() {
        let Some(end) = h.end else { continue };
        check.handlings += 1;
        let v = by_module.entry(&h.module).or_default();
        v.push((h.start, 1, h));
        v.push((end, -1, h));
    }
    for (module, mut points) in by_module {
        points.sort_by_key(|(t, d, _)| (*t, *d));
        let cap = capacity.get(module).copied().unwrap_or(1) as i32;
        let mut level = 0;
        for (t, d, h) in points {
            level += d;
            if level > cap {
                check.violations.push(format!(
                    "{module} handled {level} tasks at once at {:.3} s (capacity {cap}), \
                     among them {}",
                    t as f64 / 1e9,
                    h.name
                ));
                break;
            }
        }
    }
}
