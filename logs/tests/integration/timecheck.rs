//! The time check's capacity rule: a module's capacity comes from its hello (which reaches
//! central before its link has a module), and tasks handled at once are judged against it.

use bytes::Bytes;
use tca_logs::*;
use tca_messages::control::{ControlRequest, Hello};
use tca_messages::*;

const MODULE: &str = "gait";

fn frame(direction: Direction, link: u32, peer: Option<&str>, envelope: &Envelope) -> RecordKind {
    RecordKind::Frame(FrameRecord {
        direction,
        link,
        peer: peer.map(|p| ModuleName::new(p).unwrap()),
        name: envelope.name.clone(),
        class: envelope.class,
        frame: Bytes::from(encode(envelope).unwrap()),
    })
}

fn envelope(class: Class, name: &str, seq: u32, at_ns: u64, data: Vec<u8>) -> Envelope {
    Envelope {
        id: MessageId::new(0, seq),
        class,
        name: MessageName::new(name).unwrap(),
        sender: ModuleName::new("central").unwrap(),
        context: None,
        node: None,
        correlation: None,
        cause: None,
        timestamp_ns: at_ns,
        options: SendOptions::default(),
        redelivery: 0,
        data,
    }
}

/// A log where `MODULE` says hello with `capacity` (as its first frame, before its link is
/// known) and is handed `tasks` goals that all run from 1 s to 2 s of simulated time.
fn log_with(capacity: u32, tasks: u32) -> LogFile {
    let hello = ControlRequest::Hello(Hello {
        module: ModuleName::new(MODULE).unwrap(),
        capacity,
        pid: 1,
        host: "test".into(),
        simulated_time: true,
    });
    let mut hello_env = envelope(
        Class::Control,
        hello.name(),
        0,
        0,
        hello.encode_data().unwrap(),
    );
    hello_env.sender = ModuleName::new(MODULE).unwrap();
    let mut records = vec![LogRecord {
        at_ns: 0,
        kind: frame(Direction::In, 1, None, &hello_env),
    }];
    for k in 0..tasks {
        let goal = envelope(
            Class::Goal,
            "legged.gaitStep",
            10 + k,
            1_000_000_000,
            Vec::new(),
        );
        records.push(LogRecord {
            at_ns: 1,
            kind: frame(Direction::Out, 1, Some(MODULE), &goal),
        });
    }
    for k in 0..tasks {
        let mut done = envelope(
            Class::Success,
            "legged.gaitStep",
            100 + k,
            2_000_000_000,
            Vec::new(),
        );
        done.id = MessageId::new(1, 100 + k);
        done.sender = ModuleName::new(MODULE).unwrap();
        done.correlation = Some(MessageId::new(0, 10 + k));
        records.push(LogRecord {
            at_ns: 2,
            kind: frame(Direction::In, 1, Some(MODULE), &done),
        });
    }
    LogFile {
        path: "memory.mcap".into(),
        records,
        formats: Default::default(),
        truncated: None,
    }
}

#[test]
fn tasks_at_once_within_the_capacity_its_hello_gave_pass() {
    let check = time_check(&log_with(4, 4));
    assert_eq!(check.handlings, 4, "{}", check.text());
    assert!(check.holds(), "{}", check.text());
}

#[test]
fn tasks_at_once_beyond_the_capacity_its_hello_gave_are_reported() {
    let check = time_check(&log_with(2, 3));
    assert!(!check.holds());
    assert!(
        check
            .violations
            .iter()
            .any(|v| v.contains("gait handled 3 tasks at once") && v.contains("capacity 2")),
        "{}",
        check.text()
    );
}
