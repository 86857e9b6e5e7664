//! Statistics of a log: the per-module breakdown of Figure 18 (computing, waiting on others,
//! idle), message counts and query latencies.
//!
//! A module is *busy* from the delivery of a query, goal, command or exception to it until its
//! answer (reply, success or failure); within that, it is *waiting* while a query it sent is
//! unanswered; busy but not waiting is *computing*; the rest of the log's span is *idle*.
//! Times come from the envelopes' timestamps (the senders' clocks: simulated time when the
//! modules run on it, so the breakdown is in simulated seconds) or from central's clock.

use std::collections::{BTreeMap, HashMap};

use serde::Serialize;
use tca_messages::{Class, MessageId};

use crate::reader::LogFile;
use crate::record::{Direction, RecordKind};

/// Which clock the statistics use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeBase {
    /// The envelopes' own timestamps (simulated time for simulations).
    Envelope,
    /// Central's clock when it handled each frame.
    Central,
}

/// An interval, seconds from the start of the log.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Span {
    /// Start.
    pub start_s: f64,
    /// End.
    pub end_s: f64,
}

/// One module's share of the time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModuleStats {
    /// Module name.
    pub module: String,
    /// Messages it handled (queries, goals, commands, exceptions).
    pub handled: usize,
    /// Seconds computing.
    pub computing_s: f64,
    /// Seconds waiting for answers while handling.
    pub waiting_s: f64,
    /// Seconds idle.
    pub idle_s: f64,
    /// Busy intervals (computing or waiting), merged.
    pub busy: Vec<Span>,
    /// Waiting intervals, merged.
    pub waiting: Vec<Span>,
}

/// Latency of one query name.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QueryStats {
    /// Query name.
    pub name: String,
    /// How many were answered.
    pub count: usize,
    /// Median latency, milliseconds (central's clock).
    pub p50_ms: f64,
    /// Slowest, milliseconds.
    pub max_ms: f64,
}

/// The statistics of a log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LogStats {
    /// Seconds from the first to the last timed event.
    pub span_s: f64,
    /// Messages delivered by central (frames out, control traffic excluded).
    pub messages: usize,
    /// Per module, sorted by name.
    pub modules: Vec<ModuleStats>,
    /// Per query name, sorted by name.
    pub queries: Vec<QueryStats>,
    /// Deliveries by message name.
    pub by_name: BTreeMap<String, usize>,
}

struct Open {
    module: String,
    start: u64,
}

/// Computes the statistics of `log` on the given clock.
pub fn stats(log: &LogFile, base: TimeBase) -> LogStats {
    let mut handled: HashMap<MessageId, Open> = HashMap::new();
    let mut asked: HashMap<MessageId, Open> = HashMap::new();
    let mut asked_central: HashMap<MessageId, (String, u64)> = HashMap::new();
    let mut busy: BTreeMap<String, Vec<(u64, u64)>> = BTreeMap::new();
    let mut waiting: BTreeMap<String, Vec<(u64, u64)>> = BTreeMap::new();
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut by_name: BTreeMap<String, usize> = BTreeMap::new();
    let mut latencies: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut messages = 0usize;
    let (mut first, mut last) = (u64::MAX, 0u64);
    for record in &log.records {
        let RecordKind::Frame(f) = &record.kind else {
            continue;
        };
        let Ok(env) = LogFile::envelope(f) else {
            continue;
        };
        let t = match base {
            TimeBase::Envelope => env.timestamp_ns,
            TimeBase::Central => record.at_ns,
        };
        let peer = f.peer.as_ref().map(|p| p.to_string()).unwrap_or_default();
        if env.class != Class::Control && !env.name.is_control() {
            first = first.min(t);
            last = last.max(t);
        }
        match (f.direction, env.class) {
            (Direction::Out, Class::Query | Class::Goal | Class::Command | Class::Exception) => {
                messages += 1;
                *by_name.entry(env.name.to_string()).or_default() += 1;
                handled.insert(
                    env.id,
                    Open {
                        module: peer.clone(),
                        start: t,
                    },
                );
                busy.entry(peer).or_default();
            }
            (Direction::Out, Class::Inform) => {
                messages += 1;
                *by_name.entry(env.name.to_string()).or_default() += 1;
            }
            (Direction::In, Class::Reply | Class::Success | Class::Failure) => {
                if let Some(id) = env.correlation
                    && let Some(open) = handled.remove(&id)
                    && open.module == peer
                {
                    *counts.entry(peer.clone()).or_default() += 1;
                    busy.entry(peer)
                        .or_default()
                        .push((open.start, t.max(open.start)));
                }
            }
            (Direction::In, Class::Query) => {
                asked.insert(
                    env.id,
                    Open {
                        module: peer.clone(),
                        start: t,
                    },
                );
                asked_central.insert(env.id, (env.name.to_string(), record.at_ns));
            }
            (Direction::Out, Class::Reply | Class::Failure | Class::Error) => {
                if let Some(id) = env.correlation {
                    if let Some(open) = asked.remove(&id) {
                        waiting
                            .entry(open.module)
                            .or_default()
                            .push((open.start, t.max(open.start)));
                    }
                    if let Some((name, sent)) = asked_central.remove(&id) {
                        latencies
                            .entry(name)
                            .or_default()
                            .push(record.at_ns.saturating_sub(sent));
                    }
                }
            }
            _ => {}
        }
    }
    if first > last {
        first = 0;
        last = 0;
    }
    let secs = |ns: u64| ns.saturating_sub(first) as f64 / 1e9;
    let span_s = secs(last);
    let mut modules = Vec::new();
    for (module, intervals) in busy {
        let busy_merged = merge(intervals);
        let wait_merged = intersect(
            &merge(waiting.remove(&module).unwrap_or_default()),
            &busy_merged,
        );
        let busy_total: u64 = busy_merged.iter().map(|(a, b)| b - a).sum();
        let wait_total: u64 = wait_merged.iter().map(|(a, b)| b - a).sum();
        let to_spans = |v: &[(u64, u64)]| {
            v.iter()
                .map(|(a, b)| Span {
                    start_s: secs(*a),
                    end_s: secs(*b),
                })
                .collect::<Vec<_>>()
        };
        modules.push(ModuleStats {
            handled: counts.get(&module).copied().unwrap_or(0),
            computing_s: (busy_total - wait_total) as f64 / 1e9,
            waiting_s: wait_total as f64 / 1e9,
            idle_s: (span_s - busy_total as f64 / 1e9).max(0.0),
            busy: to_spans(&busy_merged),
            waiting: to_spans(&wait_merged),
            module,
        });
    }
    let queries = latencies
        .into_iter()
        .map(|(name, mut v)| {
            v.sort_unstable();
            QueryStats {
                name,
                count: v.len(),
                p50_ms: v[v.len() / 2] as f64 / 1e6,
                max_ms: v[v.len() - 1] as f64 / 1e6,
            }
        })
        .collect();
    LogStats {
        span_s,
        messages,
        modules,
        queries,
        by_name,
    }
}

/// Sorts and merges overlapping intervals.
fn merge(mut v: Vec<(u64, u64)>) -> Vec<(u64, u64)> {
    v.sort_unstable();
    let mut out: Vec<(u64, u64)> = Vec::with_capacity(v.len());
    for (a, b) in v {
        match out.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => out.push((a, b)),
        }
    }
    out
}

/// The parts of `a` inside `b` (both merged and sorted).
fn intersect(a: &[(u64, u64)], b: &[(u64, u64)]) -> Vec<(u64, u64)> {
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let lo = a[i].0.max(b[j].0);
        let hi = a[i].1.min(b[j].1);
        if lo < hi {
            out.push((lo, hi));
        }
        if a[i].1 < b[j].1 {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_merge_and_intersect() {
        assert_eq!(merge(vec![(5, 7), (1, 3), (2, 4)]), vec![(1, 4), (5, 7)]);
        assert_eq!(
            intersect(&[(0, 10)], &[(2, 3), (5, 12)]),
            vec![(2, 3), (5, 10)]
        );
    }
}
