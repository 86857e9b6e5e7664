//! Backpressure through the real driver and in-process links. Modules that stop reading their
//! link: central never waits for them, holds new work for them (its senders meet over-limit
//! refusals), delivers it all once they read again, and disconnects one that does not read the
//! answers to its own requests, saying why. A log writer that falls behind: central takes
//! frames at its pace. Nothing is dropped without an answer.

use std::time::Duration;

use bytes::Bytes;
use tca_central::{CentralConfig, CentralHandle, StartOptions};
use tca_link::{FrameReceiver, InProcSender};
use tca_messages::control::{Hello, Register, Registration, names};
use tca_messages::{
    Class, DataFormat, Envelope, MessageId, MessageName, ModuleName, RouteError, SendOptions,
    decode, decode_data, encode, encode_data,
};

const STEP: Duration = Duration::from_secs(20);

/// A module speaking raw frames.
struct Raw {
    name: ModuleName,
    link: u32,
    seq: u32,
    tx: InProcSender,
    rx: FrameReceiver,
    _keep: tca_link::InProcLink,
}

impl Raw {
    async fn connect(central: &CentralHandle, name: &str, handles: &[(&str, Class)]) -> Raw {
        let mut keep = central.connect_in_process().unwrap();
        let mut raw = Raw {
            name: ModuleName::new(name).unwrap(),
            link: keep.link(),
            seq: 1,
            tx: keep.sender(),
            rx: keep.take_receiver().unwrap(),
            _keep: keep,
        };
        let hello = Hello {
            module: raw.name.clone(),
            capacity: 1,
            pid: 0,
            host: "test".into(),
            simulated_time: false,
        };
        let mut env = raw.envelope(Class::Control, names::HELLO, encode_data(&hello).unwrap());
        env.id = MessageId::new(0, 0);
        raw.send(&env);
        assert_eq!(raw.next().await.class, Class::Control, "welcome");
        let entries = handles
            .iter()
            .map(|(n, class)| Registration {
                name: MessageName::new(*n).unwrap(),
                class: *class,
                format: DataFormat::of::<u32>().unwrap(),
                reply: (*class == Class::Query).then(|| DataFormat::of::<u32>().unwrap()),
                replace: false,
            })
            .collect();
        let reg = Register { entries };
        let env = raw.envelope(Class::Control, names::REGISTER, encode_data(&reg).unwrap());
        raw.send(&env);
        assert_eq!(raw.next().await.class, Class::Reply, "registered");
        raw
    }

    fn envelope(&mut self, class: Class, name: &str, data: Vec<u8>) -> Envelope {
        self.seq += 1;
        Envelope {
            id: MessageId::new(self.link, self.seq),
            class,
            name: MessageName::new(name).unwrap(),
            sender: self.name.clone(),
            context: None,
            node: None,
            correlation: None,
            cause: None,
            timestamp_ns: 1,
            options: SendOptions::default(),
            redelivery: 0,
            data,
        }
    }

    fn send(&self, env: &Envelope) {
        self.tx.send(Bytes::from(encode(env).unwrap())).unwrap();
    }

    /// Asks central for the registry and returns what came before its answer: the answers to
    /// everything sent before.
    async fn sync(&mut self) -> Vec<Envelope> {
        let ask = self.envelope(Class::Control, names::REGISTRY, encode_data(&()).unwrap());
        self.send(&ask);
        let mut before = Vec::new();
        loop {
            let env = self.next().await;
            if env.correlation == Some(ask.id) && env.class == Class::Reply {
                return before;
            }
            before.push(env);
        }
    }

    async fn next(&mut self) -> Envelope {
        self.next_or_closed()
            .await
            .expect("a frame, not a closed link")
    }

    async fn next_or_closed(&mut self) -> Option<Envelope> {
        let frame = tokio::time::timeout(STEP, self.rx.recv())
            .await
            .expect("a frame within the step")?;
        Some(decode(&frame, usize::MAX).unwrap())
    }
}

async fn central(max_outbox_frames: u32, max_queued_messages: u32) -> tca_central::RunningCentral {
    tca_central::start(StartOptions {
        config: CentralConfig {
            max_outbox_frames,
            max_queued_messages,
            ..CentralConfig::default()
        },
        ..StartOptions::default()
    })
    .await
    .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn central_takes_frames_at_the_pace_of_its_log_writer() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("traffic.mcap");
    // A backlog of one record is already too much: central waits for the writer after
    // every batch.
    let central = tca_central::start(StartOptions {
        config: CentralConfig {
            max_log_backlog: 1,
            ..CentralConfig::default()
        },
        log: Some(log.clone()),
        ..StartOptions::default()
    })
    .await
    .unwrap();
    let handle = central.handle();
    let mut slow = Raw::connect(&handle, "reader", &[("note", Class::Inform)]).await;
    let mut fast = Raw::connect(&handle, "writer", &[]).await;
    for i in 0..2000u32 {
        let note = fast.envelope(Class::Inform, "note", encode_data(&i).unwrap());
        fast.send(&note);
    }
    for i in 0..2000u32 {
        let note = slow.next().await;
        assert_eq!(decode_data::<u32>(&note.data).unwrap(), i);
    }
    let stats = central.shutdown().await.unwrap();
    assert!(stats.log_waits > 0, "{stats:?}");
    // Everything is in the log: the informs in and out.
    let file = tca_logs::LogFile::open(&log).unwrap();
    let notes = file
        .records
        .iter()
        .filter(|r| matches!(&r.kind, tca_logs::RecordKind::Frame(f) if f.name.as_str() == "note"))
        .count();
    assert_eq!(notes, 4000);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn work_for_a_module_that_stops_reading_is_held_then_delivered_and_senders_back_off() {
    let central = central(16, 32).await;
    let handle = central.handle();
    let mut slow = Raw::connect(&handle, "slow", &[("note", Class::Inform)]).await;
    let mut fast = Raw::connect(&handle, "fast", &[]).await;
    // Slow stops reading; fast sends 200 informs to it, four at a time, reading its answers
    // in between (its own outbox is bounded too). Half of slow's outbox (8 frames) goes out,
    // 32 more wait in central charged to fast, and the rest are refused: fast hears an
    // over-limit error for each.
    let mut sent = Vec::new();
    let mut refused = std::collections::HashSet::new();
    for chunk in 0..50u32 {
        for i in chunk * 4..chunk * 4 + 4 {
            let note = fast.envelope(Class::Inform, "note", encode_data(&i).unwrap());
            fast.send(&note);
            sent.push((note.id, i));
        }
        for err in fast.sync().await {
            match decode_data::<RouteError>(&err.data).unwrap() {
                RouteError::OverLimit { setting, .. } if setting == "max_queued_messages" => {
                    refused.insert(err.correlation.unwrap());
                }
                other => panic!("unexpected answer to fast: {other}"),
            }
        }
    }
    assert_eq!(refused.len(), 160);
    let stats = handle.stats().await.unwrap();
    assert!(
        stats.high_water.outbox_frames <= 16,
        "{:?}",
        stats.high_water
    );
    assert_eq!(stats.high_water.queued_messages, 32);
    assert!(stats.counters.congestions >= 1);
    // Slow reads again: it gets every inform that was not refused, in the order sent.
    let expected: Vec<u32> = sent
        .iter()
        .filter(|(id, _)| !refused.contains(id))
        .map(|(_, i)| *i)
        .collect();
    assert_eq!(expected.len(), 40);
    let mut got = Vec::new();
    while got.len() < expected.len() {
        let note = slow.next().await;
        assert_eq!(note.name.as_str(), "note");
        got.push(decode_data::<u32>(&note.data).unwrap());
    }
    assert_eq!(got, expected);
    let stats = central.shutdown().await.unwrap();
    assert!(
        stats.high_water.outbox_frames <= 16,
        "{:?}",
        stats.high_water
    );
    assert_eq!(stats.modules.len(), 2, "nobody was disconnected: {stats:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_that_never_reads_its_answers_is_disconnected_as_too_slow() {
    let central = central(16, 1024).await;
    let handle = central.handle();
    let mut echo = Raw::connect(&handle, "echo", &[("ask", Class::Query)]).await;
    let mut asker = Raw::connect(&handle, "asker", &[]).await;
    // The echo module answers every query it gets.
    let answering = tokio::spawn(async move {
        while let Some(q) = echo.next_or_closed().await {
            let mut reply = echo.envelope(Class::Reply, "ask", q.data.clone());
            reply.correlation = Some(q.id);
            echo.send(&reply);
        }
    });
    // The asker sends 100 queries and does not read the replies.
    for i in 0..100u32 {
        let q = asker.envelope(Class::Query, "ask", encode_data(&i).unwrap());
        if asker.tx.send(Bytes::from(encode(&q).unwrap())).is_err() {
            break; // Already disconnected.
        }
    }
    // Central disconnects it once its outbox is past 16 frames.
    let deadline = tokio::time::Instant::now() + STEP;
    while handle.stats().await.unwrap().counters.too_slow == 0 {
        assert!(tokio::time::Instant::now() < deadline, "never disconnected");
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    // When it reads at last: the replies that fit, then why the link closed, then the end.
    let mut replies = 0;
    let last = loop {
        let env = asker.next().await;
        if env.class != Class::Reply {
            break env;
        }
        replies += 1;
    };
    assert!((8..=17).contains(&replies), "{replies} replies");
    let why = decode_data::<RouteError>(&last.data).unwrap().to_string();
    assert!(
        why.contains("disconnected module asker as too slow") && why.contains("max_outbox_frames"),
        "{why}"
    );
    assert!(asker.next_or_closed().await.is_none(), "the link is closed");
    let stats = handle.stats().await.unwrap();
    assert_eq!(stats.counters.too_slow, 1);
    assert_eq!(stats.modules, vec![ModuleName::new("echo").unwrap()]);
    assert!(
        stats.high_water.outbox_frames <= 18,
        "{:?}",
        stats.high_water
    );
    central.shutdown().await.unwrap();
    answering.abort();
}
