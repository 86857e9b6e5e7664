//! What one module did in a recorded run, as a script to play it back (`tca log replay`).
//!
//! Each message central delivered to the module is a [`Handling`]: who asked, what, and what
//! the module did about it, in order: the messages it sent while handling (queries, goals,
//! commands, informs, exceptions and the task-tree control of `tca.onException`/`tca.kill`) and
//! how it ended (reply, success, failure, or never). A stand-in serves the handlings of each
//! (asker, message name) in recorded order.
//!
//! **Which handling a sent message belongs to.** Answers name the message they answer. A
//! message sent in the context of a node the module is handling belongs to that handling
//! (the most recent, if the node is being handled twice, e.g. a goal and an exception
//! attached to it); any other message belongs to the most recently delivered handling still
//! open (a query handler's queries have no node; a step's next step is sent in its parent's
//! context). Informs are never open (nothing answers them, so nothing would close them).
//! Messages sent with no handling open are counted as unprompted and not played.
//!
//! **Simulated time.** A module on simulated time starts a handler at the message's stamp (a
//! goal, command or exception: no earlier than the end of its previous one; the rule of
//! [`HandlingClock`]), follows the stamps of the answers it receives and advances by what it
//! spends. Each action's and each
//! answer's `spend` is the recorded own time before it: its stamp minus the latest of the
//! handler's start, its previous action's stamp and the replies it received since.

use std::collections::HashMap;
use std::time::Duration;

use tca_messages::control::{
    ControlKind, ControlNotice, ControlRequest, Registration, TaskOutcome,
};
use tca_messages::{Class, Envelope, Failure, HandlingClock, MessageId, ModuleName, decode_data};

use crate::reader::LogFile;
use crate::record::{Direction, LinkEvent, RecordKind};

pub use tca_messages::SIMULATED_TIME_BELOW_NS;

/// One module's recorded behaviour.
#[derive(Clone, Debug)]
pub struct ModuleScript {
    /// The module.
    pub module: ModuleName,
    /// Goals/commands it took at once (from its hello).
    pub capacity: u32,
    /// Its envelopes carried simulated time (stamps below [`SIMULATED_TIME_BELOW_NS`]).
    pub simulated_time: bool,
    /// What it registered, in order.
    pub registrations: Vec<Registration>,
    /// Every delivery to it, in delivery order.
    pub handlings: Vec<Handling>,
    /// Messages it sent with no handling open (not played back).
    pub unprompted: usize,
}

/// One message delivered to the module and what the module did about it.
#[derive(Clone, Debug)]
pub struct Handling {
    /// Position of the delivery in the log's records.
    pub position: usize,
    /// The envelope as delivered (sender = the asker; `node`, `context` as central set them).
    pub delivery: Envelope,
    /// What the handler sent, in order.
    pub actions: Vec<ScriptAction>,
    /// How it ended; `None` if it never did (killed, or the log ends first).
    pub answer: Option<Answer>,
}

impl Handling {
    /// Goals, commands and exceptions: handled one after another on simulated time
    /// ([`Class::runs_in_turn`]).
    pub fn runs_in_turn(&self) -> bool {
        self.delivery.class.runs_in_turn()
    }
}

/// A message the handler sent.
#[derive(Clone, Debug)]
pub struct ScriptAction {
    /// Own (simulated) time spent before sending it.
    pub spend: Duration,
    /// The envelope as the module sent it.
    pub envelope: Envelope,
}

/// How a handler ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Answer {
    /// Own (simulated) time spent before answering.
    pub spend: Duration,
    /// The answer.
    pub outcome: AnswerOutcome,
}

/// The end of a handler.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AnswerOutcome {
    /// A query's reply: postcard data in the reply format.
    Reply(Vec<u8>),
    /// A goal, command or exception succeeded.
    Success,
    /// Failed, with the reason.
    Failure(String),
}

/// A goal or command sent with no context (a root of a task tree) and how it ended.
#[derive(Clone, Debug)]
pub struct RootTask {
    /// Position of the sent frame in the log's records.
    pub position: usize,
    /// The envelope as sent.
    pub envelope: Envelope,
    /// How central said it ended, and where (position of that notice).
    pub outcome: Option<(TaskOutcome, usize)>,
}

/// Modules in the order they connected (first connection of each name).
pub fn connection_order(log: &LogFile) -> Vec<ModuleName> {
    let mut order: Vec<ModuleName> = Vec::new();
    for record in &log.records {
        if let RecordKind::Link(l) = &record.kind
            && l.event == LinkEvent::Connected
            && let Some(m) = &l.module
            && !order.contains(m)
        {
            order.push(m.clone());
        }
    }
    order
}

/// Root goals and commands (sent with no context) by `sender`, with their outcomes.
pub fn root_tasks(log: &LogFile, sender: &str) -> Vec<RootTask> {
    let mut roots: Vec<RootTask> = Vec::new();
    let mut by_id: HashMap<MessageId, usize> = HashMap::new();
    for (position, record) in log.records.iter().enumerate() {
        let RecordKind::Frame(f) = &record.kind else {
            continue;
        };
        if f.peer.as_ref().map(ModuleName::as_str) != Some(sender) {
            continue;
        }
        let Ok(env) = LogFile::envelope(f) else {
            continue;
        };
        match f.direction {
            Direction::In if env.class.is_task() && env.context.is_none() => {
                by_id.insert(env.id, roots.len());
                roots.push(RootTask {
                    position,
                    envelope: env,
                    outcome: None,
                });
            }
            Direction::Out if env.class == Class::Control => {
                if let Some(ControlNotice::TaskEnded(ended)) =
                    ControlNotice::decode(env.name.as_str(), &env.data)
                    && let Some(&i) = env.correlation.as_ref().and_then(|c| by_id.get(c))
                    && let Some(root) = roots.get_mut(i)
                    && root.outcome.is_none()
                {
                    root.outcome = Some((ended.outcome, position));
                }
            }
            _ => {}
        }
    }
    roots
}

/// An action waiting for the stamps that decide its `spend`.
struct Pending {
    stamp: u64,
    reply_stamp: Option<u64>,
}

struct Building {
    handling: Handling,
    start: u64,
    stamps: Vec<Pending>,
    answer_stamp: Option<u64>,
}

/// Extracts `module`'s script from the log. `None` if the module never connected.
pub fn module_script(log: &LogFile, module: &str) -> Option<ModuleScript> {
    let name = ModuleName::new(module).ok()?;
    if !connection_order(log).contains(&name) {
        return None;
    }
    let mut script = ModuleScript {
        module: name.clone(),
        capacity: 1,
        simulated_time: false,
        registrations: Vec::new(),
        handlings: Vec::new(),
        unprompted: 0,
    };
    let mut building: Vec<Building> = Vec::new();
    // Open handlings (indices into `building`), in delivery order.
    let mut open: Vec<usize> = Vec::new();
    // Handling by delivered message id.
    let mut by_delivery: HashMap<MessageId, usize> = HashMap::new();
    // Query sent by the module -> (handling, action).
    let mut queries: HashMap<MessageId, (usize, usize)> = HashMap::new();
    let clock = HandlingClock::new();
    let mut saw_stamp = None::<u64>;
    for (position, record) in log.records.iter().enumerate() {
        match &record.kind {
            RecordKind::Registered(r) if r.module == name => {
                script
                    .registrations
                    .retain(|x| x.name != r.registration.name);
                script.registrations.push(r.registration.clone());
            }
            RecordKind::Frame(f) if f.peer.as_ref() == Some(&name) => {
                let Ok(env) = LogFile::envelope(f) else {
                    continue;
                };
                match f.direction {
                    Direction::Out => {
                        if env.class.is_handled() {
                            let start = clock.start(env.class, env.timestamp_ns);
                            by_delivery.insert(env.id, building.len());
                            // Nothing answers an inform, so it would never close: what a
                            // module sends after one is not attributed to it.
                            if env.class != Class::Inform {
                                open.push(building.len());
                            }
                            building.push(Building {
                                handling: Handling {
                                    position,
                                    delivery: env,
                                    actions: Vec::new(),
                                    answer: None,
                                },
                                start,
                                stamps: Vec::new(),
                                answer_stamp: None,
                            });
                        } else if matches!(env.class, Class::Reply | Class::Failure | Class::Error)
                            && let Some((h, a)) =
                                env.correlation.as_ref().and_then(|c| queries.get(c))
                            && let Some(p) = building.get_mut(*h).and_then(|b| b.stamps.get_mut(*a))
                        {
                            p.reply_stamp = Some(env.timestamp_ns);
                        }
                    }
                    Direction::In => {
                        let is_hello = ControlKind::from_name(env.name.as_str())
                            .is_some_and(ControlKind::is_hello);
                        let hello = is_hello.then(|| {
                            // Credentials are redacted from the log; the hello is what counts.
                            match ControlRequest::decode(env.name.as_str(), &env.data) {
                                Ok(ControlRequest::Hello(h)) => Some(h),
                                Ok(ControlRequest::HelloAuth(a)) => Some(a.hello),
                                _ => None,
                            }
                        });
                        if let Some(hello) = hello {
                            if let Some(h) = hello {
                                script.capacity = h.capacity.max(1);
                            }
                            continue;
                        }
                        if !env.name.is_control() {
                            saw_stamp = Some(
                                saw_stamp
                                    .map_or(env.timestamp_ns, |s: u64| s.min(env.timestamp_ns)),
                            );
                        }
                        let answer = match env.class {
                            Class::Reply => Some(AnswerOutcome::Reply(env.data.clone())),
                            Class::Success => Some(AnswerOutcome::Success),
                            Class::Failure => Some(AnswerOutcome::Failure(
                                decode_data::<Failure>(&env.data)
                                    .map(|f| f.reason)
                                    .unwrap_or_else(|e| format!("(unreadable failure: {e})")),
                            )),
                            _ => None,
                        };
                        if let Some(outcome) = answer {
                            let Some(&h) =
                                env.correlation.as_ref().and_then(|c| by_delivery.get(c))
                            else {
                                continue;
                            };
                            open.retain(|&o| o != h);
                            if let Some(b) = building.get_mut(h)
                                && b.handling.answer.is_none()
                            {
                                b.handling.answer = Some(Answer {
                                    spend: Duration::ZERO,
                                    outcome,
                                });
                                b.answer_stamp = Some(env.timestamp_ns);
                                clock.ended(b.handling.delivery.class, env.timestamp_ns);
                            }
                            continue;
                        }
                        if env.class == Class::Control && !played_control(env.name.as_str()) {
                            continue;
                        }
                        let by_context = env.context.and_then(|c| {
                            open.iter().rev().copied().find(|&o| {
                                building
                                    .get(o)
                                    .is_some_and(|b| b.handling.delivery.node == Some(c))
                            })
                        });
                        let Some(h) = by_context.or_else(|| open.last().copied()) else {
                            script.unprompted += 1;
                            continue;
                        };
                        let Some(b) = building.get_mut(h) else {
                            continue;
                        };
                        if env.class == Class::Query {
                            queries.insert(env.id, (h, b.stamps.len()));
                        }
                        b.stamps.push(Pending {
                            stamp: env.timestamp_ns,
                            reply_stamp: None,
                        });
                        b.handling.actions.push(ScriptAction {
                            spend: Duration::ZERO,
                            envelope: env,
                        });
                    }
                }
            }
            _ => {}
        }
    }
    script.simulated_time = saw_stamp.is_some_and(tca_messages::is_simulated_stamp);
    script.handlings = building
        .into_iter()
        .map(|mut b| {
            let mut reference = b.start;
            for (action, pending) in b.handling.actions.iter_mut().zip(&b.stamps) {
                action.spend = Duration::from_nanos(pending.stamp.saturating_sub(reference));
                reference = reference.max(pending.stamp);
                if let Some(r) = pending.reply_stamp {
                    reference = reference.max(r);
                }
            }
            if let (Some(answer), Some(stamp)) = (b.handling.answer.as_mut(), b.answer_stamp) {
                answer.spend = Duration::from_nanos(stamp.saturating_sub(reference));
            }
            b.handling
        })
        .collect();
    Some(script)
}

/// Control messages a handler's script plays back: those that act on the task tree and that
/// a handler sends (monitors are installed by their own requests, not played).
pub fn played_control(name: &str) -> bool {
    matches!(
        ControlKind::from_name(name),
        Some(
            ControlKind::OnException
                | ControlKind::Kill
                | ControlKind::Constrain
                | ControlKind::Retry
        )
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::{FrameRecord, LinkRecord, LogRecord, RegisteredRecord};
    use tca_messages::{DataFormat, MessageName, NodeId, SendOptions, encode_data};

    struct Builder {
        records: Vec<LogRecord>,
    }

    impl Builder {
        fn connected(&mut self, link: u32, module: &str) {
            self.records.push(LogRecord {
                at_ns: 0,
                kind: RecordKind::Link(LinkRecord {
                    link,
                    event: LinkEvent::Connected,
                    module: Some(ModuleName::new(module).unwrap()),
                    detail: String::new(),
                }),
            });
        }

        /// A frame between central and `peer`.
        #[allow(clippy::too_many_arguments)]
        fn frame(
            &mut self,
            direction: Direction,
            peer: &str,
            sender: &str,
            id: (u32, u32),
            class: Class,
            name: &str,
            t_ns: u64,
            node: Option<u64>,
            context: Option<u64>,
            correlation: Option<(u32, u32)>,
            data: Vec<u8>,
        ) -> MessageId {
            let env = Envelope {
                id: MessageId::new(id.0, id.1),
                class,
                name: MessageName::new(name).unwrap(),
                sender: ModuleName::new(sender).unwrap(),
                context: context.map(NodeId),
                node: node.map(NodeId),
                correlation: correlation.map(|(l, s)| MessageId::new(l, s)),
                cause: None,
                timestamp_ns: t_ns,
                options: SendOptions::default(),
                redelivery: 0,
                data,
            };
            self.records.push(LogRecord {
                at_ns: 0,
                kind: RecordKind::Frame(FrameRecord {
                    direction,
                    link: 1,
                    peer: Some(ModuleName::new(peer).unwrap()),
                    name: env.name.clone(),
                    class,
                    frame: tca_messages::encode(&env).unwrap().into(),
                }),
            });
            env.id
        }
    }

    const S: u64 = 1_000_000_000;

    /// The controller: a query answered at once, then a moveArm that spends 3 s, raises
    /// moveFailed in its context and fails; the ISM asks it nothing. Then a goal delivered
    /// while the controller is still busy starts when the moveArm ended.
    fn controller_log() -> LogFile {
        use Direction::{In, Out};
        let mut b = Builder {
            records: Vec::new(),
        };
        b.connected(1, "controller");
        b.records.push(LogRecord {
            at_ns: 0,
            kind: RecordKind::Registered(RegisteredRecord {
                module: ModuleName::new("controller").unwrap(),
                registration: Registration {
                    name: MessageName::new("moveArm").unwrap(),
                    class: Class::Command,
                    format: DataFormat::of::<u32>().unwrap(),
                    reply: None,
                    replace: false,
                },
            }),
        });
        let unit = encode_data(&()).unwrap();
        // bodyPosition from gait at t = 10 s, answered at once.
        b.frame(
            Out,
            "controller",
            "gait",
            (6, 5),
            Class::Query,
            "bodyPosition",
            10 * S,
            None,
            None,
            None,
            unit.clone(),
        );
        b.frame(
            In,
            "controller",
            "controller",
            (1, 2),
            Class::Reply,
            "bodyPosition",
            10 * S,
            None,
            None,
            Some((6, 5)),
            encode_data(&2.5f64).unwrap(),
        );
        // moveArm from lrp at t = 11 s as node 7.
        b.frame(
            Out,
            "controller",
            "lrp",
            (5, 9),
            Class::Command,
            "moveArm",
            11 * S,
            Some(7),
            Some(6),
            None,
            encode_data(&1u32).unwrap(),
        );
        // A query the controller sends while moving (no node), answered at 12.5 s.
        b.frame(
            In,
            "controller",
            "controller",
            (1, 3),
            Class::Query,
            "readForce",
            12 * S,
            None,
            None,
            None,
            unit.clone(),
        );
        b.frame(
            Out,
            "controller",
            "ism",
            (2, 4),
            Class::Reply,
            "readForce",
            12 * S + S / 2,
            None,
            None,
            Some((1, 3)),
            unit.clone(),
        );
        // moveFailed raised in node 7 at 14 s, failure at 14 s.
        b.frame(
            In,
            "controller",
            "controller",
            (1, 4),
            Class::Exception,
            "moveFailed",
            14 * S,
            None,
            Some(7),
            None,
            unit.clone(),
        );
        let failure = encode_data(&Failure {
            reason: "struck the terrain".into(),
        })
        .unwrap();
        b.frame(
            In,
            "controller",
            "controller",
            (1, 5),
            Class::Failure,
            "moveArm",
            14 * S,
            Some(7),
            Some(7),
            Some((5, 9)),
            failure,
        );
        // A moveBase sent at 13 s (before the moveArm ended), answered at 20 s.
        b.frame(
            Out,
            "controller",
            "gait",
            (6, 8),
            Class::Command,
            "moveBase",
            13 * S,
            Some(8),
            Some(2),
            None,
            unit.clone(),
        );
        b.frame(
            In,
            "controller",
            "controller",
            (1, 6),
            Class::Success,
            "moveBase",
            20 * S,
            Some(8),
            Some(8),
            Some((6, 8)),
            unit.clone(),
        );
        // Sent with nothing open.
        b.frame(
            In,
            "controller",
            "controller",
            (1, 7),
            Class::Inform,
            "note",
            21 * S,
            None,
            None,
            None,
            unit.clone(),
        );
        // A stepPlanned inform delivered (never answered) does not capture later sends.
        b.frame(
            Out,
            "controller",
            "gait",
            (6, 9),
            Class::Inform,
            "stepPlanned",
            22 * S,
            None,
            None,
            None,
            unit.clone(),
        );
        b.frame(
            In,
            "controller",
            "controller",
            (1, 8),
            Class::Inform,
            "note",
            23 * S,
            None,
            None,
            None,
            unit,
        );
        LogFile {
            path: "test.mcap".into(),
            records: b.records,
            formats: HashMap::new(),
            truncated: None,
        }
    }

    #[test]
    fn handlings_collect_what_the_module_sent_and_how_it_ended() {
        let log = controller_log();
        let script = module_script(&log, "controller").unwrap();
        assert!(script.simulated_time);
        assert_eq!(script.registrations.len(), 1);
        assert_eq!(
            script.unprompted, 2,
            "the two notes were sent with nothing open"
        );
        let h = &script.handlings;
        assert_eq!(h.len(), 4);
        assert_eq!(h[0].delivery.sender.as_str(), "gait");
        assert_eq!(h[0].answer.as_ref().unwrap().spend, Duration::ZERO);
        assert!(matches!(
            h[0].answer.as_ref().unwrap().outcome,
            AnswerOutcome::Reply(_)
        ));
        // moveArm: the query and the exception, then the failure.
        let names: Vec<&str> = h[1]
            .actions
            .iter()
            .map(|a| a.envelope.name.as_str())
            .collect();
        assert_eq!(names, ["readForce", "moveFailed"]);
        assert_eq!(
            h[1].actions[0].spend,
            Duration::from_secs(1),
            "11 s -> 12 s"
        );
        assert_eq!(
            h[1].actions[1].spend,
            Duration::from_millis(1500),
            "from the reply at 12.5 s to 14 s"
        );
        let answer = h[1].answer.as_ref().unwrap();
        assert_eq!(answer.spend, Duration::ZERO);
        assert_eq!(
            answer.outcome,
            AnswerOutcome::Failure("struck the terrain".into())
        );
        // moveBase, sent at 13 s, starts when the moveArm ended (14 s): 6 s of its own.
        assert_eq!(h[2].answer.as_ref().unwrap().spend, Duration::from_secs(6));
        assert_eq!(
            h[2].answer.as_ref().unwrap().outcome,
            AnswerOutcome::Success
        );
        // The inform: delivered, nothing attributed to it.
        assert_eq!(h[3].delivery.class, Class::Inform);
        assert!(h[3].actions.is_empty() && h[3].answer.is_none());
    }

    #[test]
    fn root_tasks_and_connection_order() {
        let log = controller_log();
        assert_eq!(
            connection_order(&log),
            [ModuleName::new("controller").unwrap()]
        );
        assert!(
            module_script(&log, "gait").is_none(),
            "gait never connected"
        );
        assert!(root_tasks(&log, "controller").is_empty());
    }
}
