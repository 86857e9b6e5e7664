//! Delays measured from outside the bridge: from the two centrals' own traffic logs, the time
//! between a message reaching the central on the side it left and the forwarded copy
//! reaching the other side's central. (Both logs stamp with their machine's clock: on two
//! machines, keep the clocks synchronised.)
//!
//! Measured for informs, goals, commands and exceptions, and for the outcome of a forwarded
//! goal or command; a query's reply is not (the bridge does not know its id on the far
//! side), nor are kills.

use std::collections::HashMap;

use tca_logs::{Direction as Way, LogFile, RecordKind};
use tca_messages::{Class, MessageId};

use crate::recorded::{Recorded, RecordedCrossing};
use crate::side::Side;
use crate::stats::DelayStats;
use crate::worst::{LateCrossing, worst};

/// When each message reached one central: by its id, and (for answers) by the id it answers.
struct Arrivals {
    by_id: HashMap<MessageId, u64>,
    answers: HashMap<MessageId, u64>,
}

impl Arrivals {
    fn of(log: &LogFile) -> Self {
        let mut by_id = HashMap::new();
        let mut answers = HashMap::new();
        for r in &log.records {
            let RecordKind::Frame(f) = &r.kind else {
                continue;
            };
            if f.direction != Way::In {
                continue;
            }
            let Ok(env) = LogFile::envelope(f) else {
                continue;
            };
            match env.class {
                Class::Success | Class::Failure | Class::Reply => {
                    if let Some(c) = env.correlation {
                        answers.entry(c).or_insert(r.at_ns);
                    }
                }
                _ => {
                    by_id.entry(env.id).or_insert(r.at_ns);
                }
            }
        }
        Arrivals { by_id, answers }
    }

    /// When a crossing's message (`cause`, its id on this side) reached this central.
    fn at(&self, class: Class, cause: MessageId) -> Option<u64> {
        match class {
            Class::Success | Class::Failure | Class::Reply => self.answers.get(&cause).copied(),
            _ => self.by_id.get(&cause).copied(),
        }
    }
}

/// The end-to-end delays of one crossing, seconds, if both centrals logged it.
fn delay(c: &RecordedCrossing, logs: &[Arrivals; 2]) -> Option<f64> {
    if matches!(c.class, Class::Control | Class::Query) {
        return None;
    }
    let from = &logs[c.direction.from().index()];
    let to = &logs[c.direction.to().index()];
    let left = from.at(c.class, c.in_cause?)?;
    let reached = to.at(c.class, c.out_cause?)?;
    Some(reached.saturating_sub(left) as f64 / 1e9)
}

/// The delays each way (up, down) between the two centrals, from their logs (`robot`,
/// `ground`), against the bridge's settings.
pub fn end_to_end(recorded: &Recorded, robot: &LogFile, ground: &LogFile) -> Vec<DelayStats> {
    let logs = [Arrivals::of(robot), Arrivals::of(ground)];
    debug_assert_eq!(Side::Robot.index(), 0);
    DelayStats::both_ways(recorded.delays_s.unwrap_or((0.0, 0.0)), |d| {
        recorded
            .crossings
            .values()
            .filter(|c| c.direction == d)
            .filter_map(|c| delay(c, &logs))
            .collect()
    })
}

/// The `n` crossings that took longest past the setting between the two centrals (from
/// their logs, `robot` and `ground`), worst first.
pub fn worst_between(
    recorded: &Recorded,
    robot: &LogFile,
    ground: &LogFile,
    n: usize,
) -> Vec<LateCrossing> {
    let logs = [Arrivals::of(robot), Arrivals::of(ground)];
    worst(
        recorded.crossings.values(),
        recorded.delays_s.unwrap_or((0.0, 0.0)),
        n,
        |c| delay(c, &logs),
    )
}
