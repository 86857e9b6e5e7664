//! What crosses the bridge, and the delay line that holds it back.
//!
//! Every crossing has its own number. A forwarded query, goal or command, an inform, an
//! exception raised inside a forwarded task, the answer or outcome that goes back, and the
//! kill of a forwarded task when its origin is killed: each crosses once, one way, and waits
//! in that way's delay line until its time has come. A line releases in the order it took
//! (every crossing waits the same), so nothing overtakes.

use std::time::Duration;

use std::sync::{Mutex, mpsc};
use std::time::Instant;
use tca_messages::control::{KillTask, names};
use tca_messages::{
    Class, Envelope, Failure, MessageId, MessageName, ModuleName, SendOptions, encode_data,
};

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
                let name =
                    MessageName::new(names::KILL_TASK).unwrap_or_else(|_| self.name().clone());
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
///
/// The line releases on a thread of its own, which sleeps on the operating system's clock:
/// a crossing leaves on time however busy the async runtime is with everything else.
pub(crate) struct DelayLine {
    tx: mpsc::Sender<(Instant, Crossing)>,
    rx: Mutex<Option<mpsc::Receiver<(Instant, Crossing)>>>,
    delay: Duration,
}

impl DelayLine {
    /// A line with `delay`; crossings taken wait in it until it [`runs`](Self::run).
    pub(crate) fn new(delay: Duration) -> Self {
        let (tx, rx) = mpsc::channel();
        DelayLine {
            tx,
            rx: Mutex::new(Some(rx)),
            delay,
        }
    }

    /// Starts handing each crossing to `release` when its time has come, on a thread named
    /// `name` with `runtime` entered (so `release` may spawn tasks). The thread ends when the
    /// line is dropped, or when `release` returns false. A line runs once.
    pub(crate) fn run(
        &self,
        name: &str,
        runtime: tokio::runtime::Handle,
        mut release: impl FnMut(Crossing) -> bool + Send + 'static,
    ) -> std::io::Result<()> {
        let Some(rx) = self.rx.lock().unwrap_or_else(|p| p.into_inner()).take() else {
            return Ok(());
        };
        std::thread::Builder::new()
            .name(name.to_owned())
            .spawn(move || {
                let _runtime = runtime.enter();
                above_the_process();
                while let Ok((due, crossing)) = rx.recv() {
                    let now = Instant::now();
                    if due > now {
                        std::thread::sleep(due - now);
                    }
                    if !release(crossing) {
                        return;
                    }
                }
            })
            .map(|_| ())
    }

    /// Takes a crossing: it comes out the line's delay after it was received.
    pub(crate) fn take(&self, crossing: Crossing) -> bool {
        let due = crossing.received + self.delay;
        self.tx.send((due, crossing)).is_ok()
    }
}

/// Under a real-time FIFO scheduler (`tca --realtime`), puts the calling delay-line thread
/// one priority above the rest of the process: a runtime worker or the log writer busy at the
/// process's priority would otherwise hold a core the line needs at its release time. Under
/// the ordinary scheduler nothing changes.
fn above_the_process() {
    use thread_priority::{
        RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue, ThreadSchedulePolicy,
    };
    let id = thread_priority::thread_native_id();
    let Ok((ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo), params)) =
        thread_priority::thread_schedule_policy_param(id)
    else {
        return;
    };
    let Ok(above) = u8::try_from(params.sched_priority + 1) else {
        return;
    };
    let Ok(value) = ThreadPriorityValue::try_from(above) else {
        return;
    };
    let policy = ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo);
    match thread_priority::set_thread_priority_and_policy(
        id,
        ThreadPriority::Crossplatform(value),
        policy,
    ) {
        Ok(()) => tracing::debug!(priority = above, "delay line above the process"),
        Err(e) => tracing::debug!(error = ?e, "delay line left at the process's priority"),
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

    #[tokio::test]
    async fn a_line_releases_each_crossing_its_delay_after_it_came_in_order() {
        let (out_tx, out) = mpsc::channel();
        let line = DelayLine::new(Duration::from_millis(300));
        let t0 = Instant::now();
        line.take(inform(1, t0));
        line.take(inform(2, t0 + Duration::from_millis(100)));
        // Nothing leaves before the line runs.
        std::thread::sleep(Duration::from_millis(50));
        line.run("test-line", tokio::runtime::Handle::current(), move |c| {
            out_tx.send((c.id, Instant::now())).is_ok()
        })
        .unwrap();
        let (a, at_a) = out.recv().unwrap();
        let (b, at_b) = out.recv().unwrap();
        assert_eq!((a, b), (1, 2));
        let (da, db) = (at_a - t0, at_b - t0);
        assert!(
            da >= Duration::from_millis(300) && da < Duration::from_millis(400),
            "{da:?}"
        );
        assert!(
            db >= Duration::from_millis(400) && db < Duration::from_millis(500),
            "{db:?}"
        );
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

    /// The scheduling policy and priority of the thread a line releases on, when the thread
    /// that starts the line runs under `policy` (`None`: the policy could not be set here).
    fn line_policy_under(
        policy: Option<thread_priority::ThreadSchedulePolicy>,
        priority: u8,
    ) -> Option<(thread_priority::ThreadSchedulePolicy, i32)> {
        std::thread::spawn(move || {
            use thread_priority::{ThreadPriority, ThreadPriorityValue};
            if let Some(policy) = policy {
                thread_priority::set_thread_priority_and_policy(
                    thread_priority::thread_native_id(),
                    ThreadPriority::Crossplatform(ThreadPriorityValue::try_from(priority).ok()?),
                    policy,
                )
                .ok()?;
            }
            let runtime = tokio::runtime::Builder::new_current_thread()
                .build()
                .unwrap();
            let line = DelayLine::new(Duration::ZERO);
            let (tx, rx) = mpsc::channel();
            line.run("policy-probe", runtime.handle().clone(), move |_| {
                let (p, params) = thread_priority::thread_schedule_policy_param(
                    thread_priority::thread_native_id(),
                )
                .unwrap();
                let _ = tx.send((p, params.sched_priority));
                false
            })
            .unwrap();
            line.take(inform(1, Instant::now()));
            rx.recv_timeout(Duration::from_secs(5)).ok()
        })
        .join()
        .unwrap()
    }

    #[test]
    fn a_line_runs_one_priority_above_a_real_time_process_and_ordinary_otherwise() {
        use thread_priority::{
            NormalThreadSchedulePolicy, RealtimeThreadSchedulePolicy, ThreadSchedulePolicy,
        };
        let fifo = ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo);
        let (policy, _) = line_policy_under(None, 0).expect("the line released");
        assert_eq!(
            policy,
            ThreadSchedulePolicy::Normal(NormalThreadSchedulePolicy::Other),
            "an ordinary process's line stays ordinary"
        );
        match line_policy_under(Some(fifo), 5) {
            Some(got) => assert_eq!(got, (fifo, 6), "one above the process's 5"),
            None => eprintln!("this user may not use the real-time scheduler; half checked"),
        }
        match line_policy_under(Some(fifo), 99) {
            Some(got) => assert_eq!(got, (fifo, 99), "99 is the top: left there"),
            None => eprintln!("this user may not use the real-time scheduler; half checked"),
        }
    }
}
