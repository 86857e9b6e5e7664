//! Writing a log and reading it back, whole, truncated and corrupt.

use bytes::Bytes;
use proptest::prelude::*;
use tca_logs::*;
use tca_messages::control::Registration;
use tca_messages::*;

fn envelope(seq: u32, y: f64) -> Envelope {
    Envelope {
        id: MessageId::new(2, seq),
        class: Class::Command,
        name: MessageName::new("moveBase").unwrap(),
        sender: ModuleName::new("gait").unwrap(),
        context: None,
        node: Some(NodeId(u64::from(seq))),
        correlation: None,
        cause: None,
        timestamp_ns: 0,
        options: SendOptions::default(),
        redelivery: 0,
        data: encode_data(&y).unwrap(),
    }
}

fn records(n: u32) -> Vec<LogRecord> {
    let mut out = vec![LogRecord {
        at_ns: 1_000,
        kind: RecordKind::Registered(RegisteredRecord {
            module: ModuleName::new("controller").unwrap(),
            registration: Registration {
                name: MessageName::new("moveBase").unwrap(),
                class: Class::Command,
                format: DataFormat::of::<f64>().unwrap(),
                reply: None,
                replace: false,
            },
        }),
    }];
    for seq in 0..n {
        out.push(LogRecord {
            at_ns: 2_000 + u64::from(seq),
            kind: RecordKind::Frame(FrameRecord {
                direction: Direction::Out,
                link: 1,
                peer: Some(ModuleName::new("controller").unwrap()),
                name: MessageName::new("moveBase").unwrap(),
                class: Class::Command,
                frame: Bytes::from(encode(&envelope(seq, f64::from(seq) / 2.0)).unwrap()),
            }),
        });
    }
    out
}

#[test]
fn a_finished_log_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.mcap");
    let mut w = LogWriter::create(&path).unwrap();
    let written = records(100);
    for r in &written {
        w.append(r).unwrap();
    }
    w.finish().unwrap();
    let log = LogFile::open(&path).unwrap();
    assert!(log.truncated.is_none());
    assert_eq!(log.records, written);
    let lines = render(&log, &ShowFilter::default());
    assert!(
        lines
            .iter()
            .any(|l| l.contains("command   gait -> controller  moveBase  n3  m2.3  1.5")),
        "{lines:#?}"
    );
}

#[test]
fn a_log_cut_short_reads_up_to_its_last_flush() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("b.mcap");
    let mut w = LogWriter::create(&path).unwrap();
    let written = records(50);
    for r in &written {
        w.append(r).unwrap();
    }
    w.flush().unwrap();
    // Records after the flush are in an unfinished chunk, as when central is killed.
    for r in records(10).iter().skip(1) {
        w.append(r).unwrap();
    }
    let bytes = std::fs::read(&path).unwrap();
    std::mem::forget(w); // no summary, no end magic: the state a kill -9 leaves
    let log = LogFile::parse(&path, &bytes).unwrap();
    assert_eq!(log.records, written, "everything up to the flush is there");
    // And a file chopped at any byte still reads without panicking.
    for cut in (8..bytes.len()).step_by(97) {
        let _ = LogFile::parse(&path, &bytes[..cut]);
    }
}

#[test]
fn a_file_that_is_not_a_log_is_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.mcap");
    std::fs::write(&path, b"this is not a log").unwrap();
    let err = LogFile::open(&path).unwrap_err().to_string();
    assert!(err.contains("MCAP magic"), "{err}");
    let missing = LogFile::open(&dir.path().join("nope.mcap"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("nope.mcap"), "{missing}");
}

proptest! {
    #[test]
    fn corrupted_logs_never_panic(at in 0usize..4096, byte in any::<u8>(), cut in 0usize..4096) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.mcap");
        let mut w = LogWriter::create(&path).unwrap();
        for r in &records(20) {
            w.append(r).unwrap();
        }
        w.finish().unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        let i = at % bytes.len();
        bytes[i] = byte;
        let end = cut.min(bytes.len());
        let _ = LogFile::parse(&path, &bytes[..end]);
        let _ = LogFile::parse(&path, &bytes);
    }
}

#[test]
fn the_json_export_opens_as_plain_mcap_with_decoded_data() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("e.mcap");
    let mut w = LogWriter::create(&path).unwrap();
    for r in &records(5) {
        w.append(r).unwrap();
    }
    w.finish().unwrap();
    let log = LogFile::open(&path).unwrap();
    let out = dir.path().join("e.json.mcap");
    assert_eq!(export_json(&log, &out).unwrap(), 6);
    let bytes = std::fs::read(&out).unwrap();
    let mut seen = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.channel.message_encoding, "json");
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        if m.channel.topic == "moveBase" {
            assert_eq!(v["class"], "command");
            assert_eq!(v["from"], "gait");
            assert_eq!(v["to"], "controller");
            assert_eq!(v["data"], serde_json::json!(f64::from(seen) / 2.0));
            seen += 1;
        }
    }
    assert_eq!(seen, 5);
}
