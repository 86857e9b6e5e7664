//! What crosses the bridge, and the delay line that holds it back.
//!
//! Every crossing has its own number. A forwarded query, goal or command, an inform, an
//! exception raised inside a forwarded task, the answer or outcome that goes back, and the
//! kill of a forwarded task when its origin is killed: each crosses once, one way, and waits
//! in that way's delay line until its time has come. A line releases in the order it took
//! (every crossing waits the same), so nothing overtakes.

use std::time::Duration;

use tca_messages::control::{KillTask, names};
use tca_messages::{
    Class, Envelope, Failure, MessageId, MessageName, ModuleName, SendOptions, encode_data,
};
use tokio::sync::{mpsc, watch};
use tokio::time::Instant;

use crate::side::Direction;

/// One crossing.
#[derive(Clone, Debug)]
pub(crate) struct Crossing {
    /// Its number, unique in this bridge's run.
    pub(crate) id: u32,
    /// The way it crosses.
    pub(crate) direction: Direction,
    /// The module that sent it on the side it leaves (for answers: the one that answered).
    pub(crate) sender: ModuleName,
    /// When the bridge got it (monotonic).
    pub(crate) received: Instant,
    /// When the bridge got it, nanoseconds since the UNIX epoch.
    pub(crate) received_ns: u64,
    /// What it is.
    pub(crate) payload: Payload,
}

/// What a crossing carries.
#[derive(Clone, Debug)]
pub(crate) enum Payload {
    /// A goal or command to carry out on the far side.
    Task {
        class: Class,
        name: MessageName,
        data: Vec<u8>,
    },
    /// A query to ask on the far side, with its own timeout there.
    Query {
        name: MessageName,
        data: Vec<u8>,
        timeout: Duration,
    },
    /// An inform.
    Inform { name: MessageName, data: Vec<u8> },
    /// An exception raised inside forwarded task `task`, to raise in that task's context on
    /// the side it came from.
    Exception {
        task: u32,
        name: MessageName,
        data: Vec<u8>,
    },
    /// The answer to query, or the outcome of task, `request`.
    Answer {
        request: u32,
        name: MessageName,
        answer: Answer,
    },
    /// Kill the far copy of task `task` (its origin was killed).
    Kill { task: u32, name: MessageName },
}

/// How a forwarded query or task ended on the far side.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Answer {
    /// A query's reply data.
    Reply(Vec<u8>),
    /// A task achieved.
    Done,
    /// A query or task failed, with the reason.
    Failed(String),
}

impl Payload {
    /// The message name it concerns.
    pub(crate) fn name(&self) -> &MessageName {
        match self {
            Payload::Task { name, .. }
            | Payload::Query { name, .. }
            | Payload::Inform { name, .. }
            | Payload::Exception { name, .. }
            | Payload::Answer { name, .. }
            | Payload::Kill { name, .. } => name,
        }
    }

    /// The class of its records in the bridge's log.
    pub(crate) fn class(&self) -> Class {
        match self {
            Payload::Task { class, .. } => *class,
            Payload::Query { .. } => Class::Query,
            Payload::Inform { .. } => Class::Inform,
            Payload::Exception { .. } => Class::Exception,
            Payload::Answer { answer, .. } => match answer {
                Answer::Reply(_) => Class::Reply,
                Answer::Done => Class::Success,
                Answer::Failed(_) => Class::Failure,
            },
            Payload::Kill { .. } => Class::Control,
        }
    }

    /// The crossing it refers to: the request an answer answers, the task an exception was
    /// raised in or a kill kills.
    pub(crate) fn refers_to(&self) -> Option<u32> {
        match self {
            Payload::Exception { task, .. } | Payload::Kill { task, .. } => Some(*task),
            Payload::Answer { request, .. } => Some(*request),
            _ => None,
        }
    }

    /// Its envelope in the bridge's log: the message's own name and data, answers as central
    /// carries them (a reply's data, a failure's reason, a success), a kill as central's kill
    /// request naming the task's crossing.
    pub(crate) fn log_envelope(&self) -> (MessageName, Vec<u8>) {
        let data = match self {
            Payload::Task { data, .. }
            | Payload::Query { data, .. }
            | Payload::Inform { data, .. }
            | Payload::Exception { data, .. } => data.clone(),
            Payload::Answer { answer, .. } => match answer {
                Answer::Reply(data) => data.clone(),
                Answer::Done => encode_data(&()).unwrap_or_default(),
                Answer::Failed(reason) => encode_data(&Failure {
                    reason: reason.clone(),
                })
                .unwrap_or_default(),
            },
            Payload::Kill { task, .. } => {
                let kill = KillTask {
                    task: crossing_id(*task),
                };
                let name = MessageName::new(names::KILL_TASK).unwrap_or_else(|_| self.name().clone());
                return (name, encode_data(&kill).unwrap_or_default());
            }
        };
        (self.name().clone(), data)
    }
}

/// How the bridge's log numbers crossing `n`: message id `m0.n` (link 0 is no central's).
pub fn crossing_id(n: u32) -> MessageId {
    MessageId::new(0, n)
}

impl Crossing {
    /// Its record in the bridge's log at `at_ns`; `cause` is its message id on the side the
    /// record is about (where it came from, or where it went).
    pub(crate) fn log_envelope(&self, cause: Option<MessageId>, at_ns: u64) -> Envelope {
        let (name, data) = self.payload.log_envelope();
        Envelope {
            id: crossing_id(self.id),
            class: self.payload.class(),
            name,
            sender: self.sender.clone(),
            context: None,
            node: None,
            correlation: self.payload.refers_to().map(crossing_id),
            cause,
            timestamp_ns: at_ns,
            options: SendOptions::default(),
            redelivery: 0,
            data,
        }
    }
}

/// One way's delay line: crossings go in, and each comes out its delay after it went in.
pub(crate) struct DelayLine {
    tx: mpsc::UnboundedSender<(Instant, Crossing)>,
    delay: Duration,
}

impl DelayLine {
    /// Starts a line with `delay` that hands each crossing to `release` when its time has
    /// come, once `ready` turns true (crossings taken before wait until then). The line
    /// ends when it is dropped, or when `release` returns false.
    pub(crate) fn start(
        delay: Duration,
        mut ready: watch::Receiver<bool>,
        release: impl Fn(Crossing) -> bool + Send + 'static,
    ) -> (DelayLine, tokio::task::JoinHandle<()>) {
        let (tx, mut rx) = mpsc::unbounded_channel::<(Instant, Crossing)>();
        let task = tokio::spawn(async move {
            if ready.wait_for(|r| *r).await.is_err() {
                return;
            }
            while let Some((due, crossing)) = rx.recv().await {
                tokio::time::sleep_until(due).await;
                if !release(crossing) {
                    return;
                }
            }
        });
        (DelayLine { tx, delay }, task)
    }

    /// Takes a crossing: it comes out the line's delay after it was received.
    pub(crate) fn take(&self, crossing: Crossing) -> bool {
        let due = crossing.received + self.delay;
        self.tx.send((due, crossing)).is_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inform(id: u32, received: Instant) -> Crossing {
        Crossing {
            id,
            direction: Direction::Down,
            sender: ModuleName::new("controller").unwrap(),
            received,
            received_ns: 0,
            payload: Payload::Inform {
                name: MessageName::new("telemetry").unwrap(),
                data: vec![id as u8],
            },
        }
    }

    #[tokio::test(start_paused = true)]
    async fn a_line_releases_each_crossing_its_delay_after_it_came_in_order() {
        let (ready_tx, ready) = watch::channel(false);
        let (out_tx, mut out) = mpsc::unbounded_channel();
        let (line, _task) = DelayLine::start(Duration::from_millis(1300), ready, move |c| {
            out_tx.send((c.id, Instant::now())).is_ok()
        });
        let t0 = Instant::now();
        line.take(inform(1, t0));
        tokio::time::sleep(Duration::from_millis(100)).await;
        line.take(inform(2, Instant::now()));
        // Nothing leaves before the line is ready.
        tokio::time::sleep(Duration::from_millis(50)).await;
        ready_tx.send_replace(true);
        let (a, at_a) = out.recv().await.unwrap();
        let (b, at_b) = out.recv().await.unwrap();
        assert_eq!((a, b), (1, 2));
        assert_eq!(at_a - t0, Duration::from_millis(1300));
        assert_eq!(at_b - t0, Duration::from_millis(1400));
    }

    #[test]
    fn answers_and_kills_are_logged_as_central_carries_them() {
        let failed = Payload::Answer {
            request: 4,
            name: MessageName::new("legMove").unwrap(),
            answer: Answer::Failed("no ground".into()),
        };
        assert_eq!(failed.class(), Class::Failure);
        assert_eq!(failed.refers_to(), Some(4));
        let (name, data) = failed.log_envelope();
        assert_eq!(name.as_str(), "legMove");
        let f: Failure = tca_messages::decode_data(&data).unwrap();
        assert_eq!(f.reason, "no ground");
        let kill = Payload::Kill {
            task: 9,
            name: MessageName::new("legMove").unwrap(),
        };
        let (name, data) = kill.log_envelope();
        assert_eq!(name.as_str(), names::KILL_TASK);
        let k: KillTask = tca_messages::decode_data(&data).unwrap();
        assert_eq!(k.task, crossing_id(9));
    }
}
