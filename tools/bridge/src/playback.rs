//! Playing a recorded session back to a ground side, as the robot side and the bridge gave it
//! then, with the recorded timing.
//!
//! The player joins the ground central under the bridge's name and registers what the bridge
//! registered there. Then:
//!
//! - what came down on its own (telemetry and other informs, and queries, goals and commands
//!   the robot side sent) is sent again at the recorded time after the start (the first
//!   crossing of the log is the start), faster or slower with a speed factor;
//! - a query, goal or command the ground side sends is matched with the next recorded one of
//!   that name, and answered as it was then: the recorded reply, success or failure, the
//!   recorded exceptions raised in its context on the way, each after the time it took in the
//!   recorded session. One sent more often than recorded fails, saying so; one whose data
//!   differs from the recording is answered all the same and counted. After the timeline the
//!   player stays (at most a set time) until every recorded request was sent again.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde::Serialize;
use tca_messages::{Class, Failure, MessageName, decode_data};
use tca_module::{Connector, Context, HandlerError, Module};
use tokio::time::Instant;

use crate::bridge::lock;
use crate::error::{BridgeError, Result};
use crate::recorded::{Recorded, RecordedCrossing};
use crate::side::{Direction, Side};

/// How to play a session back.
#[derive(Clone, Debug)]
pub struct PlaybackOptions {
    /// The ground central to play to.
    pub ground: Connector,
    /// Times faster than recorded (1: as recorded).
    pub speed: f64,
    /// The module name to play under (default: the recorded bridge's name).
    pub name: Option<String>,
    /// After the timeline, how long to stay for requests of the recording the ground side
    /// has not sent yet (the player leaves as soon as every recorded request was asked).
    pub linger: Duration,
}

/// What a playback did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PlaybackReport {
    /// Messages sent again on the recorded timeline (informs, and the robot side's own
    /// requests).
    pub sent: usize,
    /// Of those, informs.
    pub informs: usize,
    /// Requests from the ground side answered as recorded.
    pub answered: usize,
    /// Of those, requests whose data differed from the recorded one.
    pub differing: usize,
    /// Requests the recording had no more of.
    pub unmatched: usize,
    /// How late the latest timeline message went out against its recorded time, milliseconds.
    pub max_late_ms: f64,
    /// The timeline's length, seconds of the recording.
    pub recorded_s: f64,
}

/// A request the ground sent in the recorded session, with what answered it.
#[derive(Clone, Debug)]
struct Script {
    data: Vec<u8>,
    /// Exceptions raised in its context: (after how long, name, data).
    exceptions: Vec<(u64, MessageName, Vec<u8>)>,
    /// Its answer: (after how long, class, data).
    answer: Option<(u64, Class, Vec<u8>)>,
}

/// Plays `recorded` back to a ground central. Returns when the timeline has been played and
/// every request taken meanwhile answered.
pub async fn play(recorded: &Recorded, options: PlaybackOptions) -> Result<PlaybackReport> {
    if !(options.speed.is_finite() && options.speed > 0.0) {
        return Err(BridgeError::Config(format!(
            "speed {} is not valid: give a positive factor (1 plays as recorded)",
            options.speed
        )));
    }
    let name = options
        .name
        .clone()
        .or_else(|| recorded.bridge.clone())
        .unwrap_or_else(|| crate::file::DEFAULT_NAME.to_owned());
    let scripts = Arc::new(Mutex::new(scripts(recorded)));
    let stats = Arc::new(Mutex::new(PlaybackReport::default()));
    let mut builder = Module::builder(name.clone()).capacity(crate::bridge::CAPACITY);
    for (side, registration) in &recorded.registrations {
        if *side != Side::Ground {
            continue;
        }
        let class = registration.class;
        let rname = registration.name.clone();
        let scripts = scripts.clone();
        let stats = stats.clone();
        let speed = options.speed;
        builder = builder.handle_raw(registration.clone(), move |ctx, data| {
            answer(
                ctx,
                class,
                rname.clone(),
                data,
                scripts.clone(),
                stats.clone(),
                speed,
            )
        });
    }
    let module = builder.connect(&options.ground).await.map_err(|e| {
        BridgeError::Connect(format!(
            "cannot play back to the ground side's {}: {e}",
            options.ground.describe()
        ))
    })?;
    let timeline = timeline(recorded);
    let start = Instant::now();
    let mut report_late: f64 = 0.0;
    let (mut sent, mut informs) = (0, 0);
    let recorded_s = timeline.last().map_or(0.0, |(t, _)| *t as f64 / 1e9);
    for (offset_ns, c) in &timeline {
        let due = start + Duration::from_secs_f64(*offset_ns as f64 / 1e9 / options.speed);
        tokio::time::sleep_until(due).await;
        report_late = report_late.max(due.elapsed().as_secs_f64() * 1e3);
        let result = match c.class {
            Class::Query => {
                let m = module.clone();
                let (qname, data) = (c.name.clone(), c.data.clone());
                tokio::spawn(async move {
                    if let Err(e) = m.query_raw(qname.as_str(), data, None).await {
                        tracing::debug!(name = %qname, error = %e, "a played-back query was not answered");
                    }
                });
                Ok(())
            }
            class => module
                .send_raw(class, c.name.as_str(), c.data.clone(), [])
                .map(|_| ()),
        };
        match result {
            Ok(()) => {
                sent += 1;
                if c.class == Class::Inform {
                    informs += 1;
                }
            }
            Err(e) => {
                tracing::warn!(name = %c.name, error = %e, "a recorded message could not be played back")
            }
        }
    }
    // The ground side may still send what the recording has; requests taken finish before
    // the player leaves.
    let lingering = Instant::now() + options.linger;
    loop {
        let finished = {
            let s = lock(&stats);
            s.answered + s.unmatched
        };
        let (taken, left) = {
            let s = lock(&scripts);
            (
                s.taken,
                s.by_name.values().map(VecDeque::len).sum::<usize>(),
            )
        };
        if finished >= taken && (left == 0 || Instant::now() >= lingering) {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    module.close().await;
    let mut report = lock(&stats).clone();
    report.sent = sent;
    report.informs = informs;
    report.max_late_ms = report_late;
    report.recorded_s = recorded_s;
    Ok(report)
}

/// Recorded requests by name, in order.
#[derive(Debug, Default)]
struct Scripts {
    by_name: HashMap<MessageName, VecDeque<Script>>,
    /// Requests taken during the playback.
    taken: usize,
}

fn scripts(recorded: &Recorded) -> Scripts {
    let mut by_name: HashMap<MessageName, VecDeque<Script>> = HashMap::new();
    let mut refer: BTreeMap<u32, Vec<&RecordedCrossing>> = BTreeMap::new();
    for c in recorded.crossings.values() {
        if let Some(r) = c.refers_to {
            refer.entry(r).or_default().push(c);
        }
    }
    for c in recorded.crossings.values() {
        if c.direction != Direction::Up
            || !matches!(c.class, Class::Query | Class::Goal | Class::Command)
        {
            continue;
        }
        let Some(asked_ns) = c.in_ns else { continue };
        let mut script = Script {
            data: c.data.clone(),
            exceptions: Vec::new(),
            answer: None,
        };
        for r in refer.get(&c.id).into_iter().flatten() {
            let Some(out) = r.out_ns else { continue };
            let after = out.saturating_sub(asked_ns);
            match r.class {
                Class::Exception => script
                    .exceptions
                    .push((after, r.name.clone(), r.data.clone())),
                Class::Reply | Class::Success | Class::Failure => {
                    script.answer = Some((after, r.class, r.data.clone()));
                }
                _ => {}
            }
        }
        by_name.entry(c.name.clone()).or_default().push_back(script);
    }
    Scripts { by_name, taken: 0 }
}

/// What came down on its own, in order: (offset from the session's start, crossing).
fn timeline(recorded: &Recorded) -> Vec<(u64, &RecordedCrossing)> {
    let start = recorded
        .crossings
        .values()
        .filter_map(|c| c.in_ns)
        .min()
        .unwrap_or(0);
    let mut items: Vec<(u64, &RecordedCrossing)> = recorded
        .crossings
        .values()
        .filter(|c| {
            c.direction == Direction::Down
                && c.refers_to.is_none()
                && matches!(
                    c.class,
                    Class::Inform | Class::Query | Class::Goal | Class::Command
                )
        })
        .filter_map(|c| c.out_ns.map(|t| (t.saturating_sub(start), c)))
        .collect();
    items.sort_by_key(|(t, c)| (*t, c.id));
    items
}

/// Answers a ground request as the recording answered it.
async fn answer(
    ctx: Context,
    class: Class,
    name: MessageName,
    data: Vec<u8>,
    scripts: Arc<Mutex<Scripts>>,
    stats: Arc<Mutex<PlaybackReport>>,
    speed: f64,
) -> Result<Vec<u8>, HandlerError> {
    if !matches!(class, Class::Query | Class::Goal | Class::Command) {
        // Informs and exceptions the ground sends up go nowhere in a playback.
        return Ok(Vec::new());
    }
    let script = {
        let mut s = lock(&scripts);
        s.taken += 1;
        s.by_name.get_mut(&name).and_then(VecDeque::pop_front)
    };
    let Some(script) = script else {
        lock(&stats).unmatched += 1;
        return Err(HandlerError::new(format!(
            "the recorded session has no more {name} to answer with (played back, not live)"
        )));
    };
    let started = Instant::now();
    let at = |after_ns: u64| started + Duration::from_secs_f64(after_ns as f64 / 1e9 / speed);
    if script.data != data {
        lock(&stats).differing += 1;
        tracing::warn!(%name, "the request differs from the recorded one; answered as recorded");
    }
    for (after, ename, edata) in &script.exceptions {
        tokio::time::sleep_until(at(*after)).await;
        if let Err(e) = ctx.send_raw(Class::Exception, ename.as_str(), edata.clone(), []) {
            tracing::warn!(exception = %ename, error = %e, "a recorded exception could not be raised");
        }
    }
    let result = match &script.answer {
        Some((after, aclass, adata)) => {
            tokio::time::sleep_until(at(*after)).await;
            match aclass {
                Class::Reply => Ok(adata.clone()),
                Class::Success => Ok(Vec::new()),
                _ => Err(HandlerError::new(
                    decode_data::<Failure>(adata)
                        .map(|f| f.reason)
                        .unwrap_or_else(|e| format!("a recorded failure that cannot be read: {e}")),
                )),
            }
        }
        None => Err(HandlerError::new(format!(
            "{name} was not answered in the recorded session"
        ))),
    };
    lock(&stats).answered += 1;
    result
}
