//! Fuzzing on stable: proptest feeds arbitrary and mutated bytes to the decoders (frames,
//! control payloads, data formats and values), to the traffic-log reader, and as event
//! sequences to central's core. Every input must be answered with `Ok` or an error: no panic,
//! no hang, no unbounded allocation (see also `alloc_bound.rs`).
//!
//! In CI each target runs `FUZZ_CASES` cases (default 64). The long run drives every target in
//! turn with fresh seeds until `FUZZ_SECONDS` have passed and prints how many inputs ran:
//!
//! ```text
//! FUZZ_SECONDS=600 nice -n 10 cargo test -p tca-central --release --test integration -- \
//!     --ignored --nocapture fuzz_long_run
//! ```

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use bytes::Bytes;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestError, TestRng, TestRunner};
use tca_central::core::{Action, Central, Event};
use tca_central::{CentralConfig, Policy};
use tca_logs::{
    Direction, FrameRecord, LinkEvent, LinkRecord, LogFile, LogRecord, LogWriter, ProblemRecord,
    RecordKind, RegisteredRecord, ShowFilter,
};
use tca_messages::control::{
    AuthHello, Constrain, ControlKind, ControlRequest, Credentials, Hello, Kill, Monitor,
    MonitorAction, Register, RegisterOutcome, Registration, Registry, TaskEnded, TreeView, Welcome,
    names,
};
use tca_messages::{
    Class, ConstraintSpec, DataFormat, Envelope, Failure, MessageId, MessageName, ModuleName,
    NodeId, RouteError, SendOptions, TaskRef, decode, decode_data, encode, encode_data,
};

// ---------------------------------------------------------------------------------------------
// Seeds: valid inputs that mutations start from, so the fuzzer gets past the first checks.

fn name(s: &str) -> MessageName {
    MessageName::new(s).unwrap()
}

fn envelope(link: u32, seq: u32, class: Class, msg: &str, module: &str, data: Vec<u8>) -> Envelope {
    Envelope {
        id: MessageId::new(link, seq),
        class,
        name: name(msg),
        sender: ModuleName::new(module).unwrap(),
        context: None,
        node: None,
        correlation: None,
        cause: None,
        timestamp_ns: 1_000,
        options: SendOptions::default(),
        redelivery: 0,
        data,
    }
}

fn hello(module: &str) -> Hello {
    Hello {
        module: ModuleName::new(module).unwrap(),
        capacity: 1,
        pid: 1,
        host: "h".into(),
        simulated_time: false,
    }
}

fn registration(msg: &str, class: Class) -> Registration {
    Registration {
        name: name(msg),
        class,
        format: DataFormat::of::<(u32, String, Vec<f64>)>().unwrap(),
        reply: (class == Class::Query).then(|| DataFormat::of::<Option<Vec<u8>>>().unwrap()),
        replace: false,
    }
}

/// Valid frames of every kind a module sends.
fn seed_frames() -> Vec<Vec<u8>> {
    let data = encode_data(&(7u32, "x".to_owned(), vec![1.5f64])).unwrap();
    let mut goal = envelope(1, 3, Class::Goal, "g", "m1", data.clone());
    goal.options.constraints = vec![ConstraintSpec::sequential_achievement(
        TaskRef::Message(MessageId::new(1, 2)),
        TaskRef::This,
    )];
    goal.context = Some(NodeId(1));
    let mut reply = envelope(
        2,
        4,
        Class::Reply,
        "q",
        "m2",
        encode_data(&Some(vec![1u8])).unwrap(),
    );
    reply.correlation = Some(MessageId::new(1, 9));
    let monitor = Monitor {
        node: NodeId(1),
        query: name("q"),
        query_data: data.clone(),
        period_ms: Some(10),
        action: MonitorAction::Send {
            class: Class::Inform,
            name: name("i"),
            data: data.clone(),
        },
    };
    let envs = vec![
        envelope(
            1,
            0,
            Class::Control,
            names::HELLO,
            "m1",
            encode_data(&hello("m1")).unwrap(),
        ),
        envelope(
            1,
            0,
            Class::Control,
            names::HELLO_AUTH,
            "m1",
            encode_data(&AuthHello {
                hello: hello("m1"),
                credentials: Credentials {
                    identity: "m1".into(),
                    secret: "s".into(),
                },
            })
            .unwrap(),
        ),
        envelope(
            1,
            1,
            Class::Control,
            names::REGISTER,
            "m1",
            encode_data(&Register {
                entries: vec![
                    registration("q", Class::Query),
                    registration("g", Class::Goal),
                ],
            })
            .unwrap(),
        ),
        envelope(1, 2, Class::Query, "q", "m1", data.clone()),
        goal,
        reply,
        envelope(1, 5, Class::Inform, "i", "m1", data.clone()),
        envelope(
            1,
            6,
            Class::Control,
            names::MONITOR,
            "m1",
            encode_data(&monitor).unwrap(),
        ),
        envelope(
            1,
            7,
            Class::Control,
            names::CONSTRAIN,
            "m1",
            encode_data(&Constrain {
                constraint: ConstraintSpec::delay_planning(
                    TaskRef::Node(NodeId(1)),
                    TaskRef::Node(NodeId(2)),
                ),
            })
            .unwrap(),
        ),
        envelope(
            1,
            8,
            Class::Control,
            names::KILL,
            "m1",
            encode_data(&Kill { node: NodeId(1) }).unwrap(),
        ),
        envelope(
            1,
            9,
            Class::Failure,
            "g",
            "m1",
            encode_data(&Failure {
                reason: "no".into(),
            })
            .unwrap(),
        ),
    ];
    envs.iter().map(|e| encode(e).unwrap()).collect()
}

/// A small valid traffic log (MCAP) with every record kind.
fn seed_log() -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("seed.mcap");
    let mut w = LogWriter::create(&path).unwrap();
    let frames = seed_frames();
    let mut at = 1_000_000_000u64;
    let mut push = |w: &mut LogWriter, kind: RecordKind| {
        at += 1_000;
        w.append(&LogRecord { at_ns: at, kind }).unwrap();
    };
    push(
        &mut w,
        RecordKind::Link(LinkRecord {
            link: 1,
            event: LinkEvent::Connected,
            module: Some(ModuleName::new("m1").unwrap()),
            detail: "pid 1".into(),
        }),
    );
    push(
        &mut w,
        RecordKind::Registered(RegisteredRecord {
            module: ModuleName::new("m1").unwrap(),
            registration: registration("q", Class::Query),
        }),
    );
    for f in frames.iter().take(6) {
        let env = decode(f, usize::MAX).unwrap();
        push(
            &mut w,
            RecordKind::Frame(FrameRecord {
                direction: Direction::In,
                link: 1,
                peer: Some(env.sender.clone()),
                name: env.name.clone(),
                class: env.class,
                frame: Bytes::from(f.clone()),
            }),
        );
    }
    push(
        &mut w,
        RecordKind::Problem(ProblemRecord {
            link: Some(1),
            module: None,
            error: "bad".into(),
            frame_prefix: vec![1, 2, 3],
        }),
    );
    w.finish().unwrap();
    std::fs::read(&path).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Mutations.

#[derive(Clone, Debug)]
enum Mutation {
    Flip(usize, u8),
    Set(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
    Truncate(usize),
    /// A varint claiming a huge length or count (~4 GB), the classic allocation bomb.
    HugeVarint(usize),
    /// A little-endian u64 claiming a huge length (MCAP record lengths).
    HugeU64(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let pos = any::<usize>();
    prop_oneof![
        3 => (pos, 1u8..=255).prop_map(|(p, b)| Mutation::Flip(p, b)),
        2 => (pos, any::<u8>()).prop_map(|(p, b)| Mutation::Set(p, b)),
        1 => (pos, proptest::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(p, b)| Mutation::Insert(p, b)),
        1 => (pos, 1usize..16).prop_map(|(p, n)| Mutation::Delete(p, n)),
        1 => pos.prop_map(Mutation::Truncate),
        1 => pos.prop_map(Mutation::HugeVarint),
        1 => pos.prop_map(Mutation::HugeU64),
    ]
}

fn apply(mut bytes: Vec<u8>, mutations: &[Mutation]) -> Vec<u8> {
    for m in mutations {
        let len = bytes.len();
        let at = |p: usize| if len == 0 { 0 } else { p % (len + 1) };
        match m {
            Mutation::Flip(p, b) if len > 0 => bytes[p % len] ^= b,
            Mutation::Set(p, b) if len > 0 => bytes[p % len] = *b,
            Mutation::Insert(p, b) => {
                let i = at(*p);
                bytes.splice(i..i, b.iter().copied());
            }
            Mutation::Delete(p, n) if len > 0 => {
                let i = p % len;
                bytes.drain(i..(i + n).min(len));
            }
            Mutation::Truncate(p) => bytes.truncate(at(*p)),
            Mutation::HugeVarint(p) => {
                let i = at(*p);
                bytes.splice(i..i, [0xFF, 0xFF, 0xFF, 0xFF, 0x0F]);
            }
            Mutation::HugeU64(p) => {
                let i = at(*p);
                let end = (i + 8).min(bytes.len());
                bytes.splice(i..end, 0x0000_0001_0000_0000u64.to_le_bytes());
            }
            _ => {}
        }
    }
    bytes
}

/// Arbitrary bytes, or a seed with a few mutations.
fn input(seeds: Arc<Vec<Vec<u8>>>) -> impl Strategy<Value = Vec<u8>> {
    let n = seeds.len();
    prop_oneof![
        1 => proptest::collection::vec(any::<u8>(), 0..256),
        4 => (0..n, proptest::collection::vec(mutation(), 0..6))
            .prop_map(move |(i, ms)| apply(seeds[i].clone(), &ms)),
    ]
}

// ---------------------------------------------------------------------------------------------
// Targets. Each returns normally for every input; a panic is a finding.

/// Frames and control payloads.
fn target_codec(bytes: &[u8]) {
    match decode(bytes, tca_messages::DEFAULT_MAX_FRAME_BYTES) {
        Ok(env) => {
            // What decodes re-encodes to a frame that decodes to the same envelope. (Not always
            // to the same bytes: postcard accepts over-long varints, e.g. `b2 00` for 0x32; the
            // long run found that. Harmless: both decode to the same envelope, and central
            // re-encodes what it forwards.)
            let again = encode(&env).expect("a decoded envelope encodes");
            let back = decode(&again, usize::MAX).expect("a re-encoded envelope decodes");
            assert_eq!(back, env, "decode/encode round trip changed the envelope");
            target_payloads(&env.data);
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
    target_payloads(bytes);
}

fn target_payloads(bytes: &[u8]) {
    let _ = decode_data::<Hello>(bytes);
    let _ = decode_data::<AuthHello>(bytes);
    let _ = decode_data::<Welcome>(bytes);
    let _ = decode_data::<Register>(bytes);
    let _ = decode_data::<RegisterOutcome>(bytes);
    let _ = decode_data::<Registry>(bytes);
    let _ = decode_data::<Monitor>(bytes);
    let _ = decode_data::<Constrain>(bytes);
    let _ = decode_data::<TaskEnded>(bytes);
    let _ = decode_data::<TreeView>(bytes);
    let _ = decode_data::<RouteError>(bytes);
    let _ = decode_data::<Failure>(bytes);
    for kind in ControlKind::ALL {
        let _ = ControlRequest::decode(kind.name(), bytes);
    }
    if let Ok(reg) = decode_data::<Register>(bytes) {
        for r in &reg.entries {
            target_format(&r.format, bytes);
        }
    }
    if let Ok(format) = decode_data::<DataFormat>(bytes) {
        target_format(&format, bytes);
    }
}

/// A format received from the wire: validated, then used to decode data and compared.
fn target_format(format: &DataFormat, data: &[u8]) {
    if format.validate().is_err() {
        return;
    }
    let _ = format.decode_value(data);
    let _ = format.decode_value(&data[data.len() / 2..]);
    let known = DataFormat::of::<(u32, String, Vec<f64>)>().unwrap();
    let _ = known.differences(format);
    let _ = format.differences(&known);
    let _ = format.differences(format);
}

/// Log files: parsed, then rendered as `tca log show` would.
fn target_log(bytes: &[u8]) {
    if let Ok(log) = LogFile::parse(Path::new("fuzz.mcap"), bytes) {
        let _ = tca_logs::render(&log, &ShowFilter::default());
        let _ = tca_logs::render(
            &log,
            &ShowFilter {
                all_frames: true,
                ..ShowFilter::default()
            },
        );
        let _ = tca_logs::stats(&log, tca_logs::TimeBase::Envelope);
        let _ = tca_logs::stats(&log, tca_logs::TimeBase::Central);
    }
}

/// A policy with one identity per even link; odd links connect anonymously (and may only
/// send `i`).
fn fuzz_policy() -> Arc<Policy> {
    let mut text = String::from("[anonymous]\nregister = [\"i\"]\nsend = [\"i\", \"q\"]\n");
    for link in [2u32, 4] {
        text.push_str(&format!(
            "[[identity]]\nname = \"m{link}\"\nsecret_sha3 = \"{}\"\nregister = [\"*\"]\n\
             send = [\"q\", \"g\", \"tca.*\"]\n",
            tca_central::policy::hash_secret(&format!("m{link}"), "s")
        ));
    }
    Arc::new(Policy::parse(Path::new("fuzz.toml"), &text).unwrap())
}

/// Central's core: a sequence of (link, bytes) frames mixed with opens, closes and ticks.
fn target_core(ops: &[(u8, u32, Vec<u8>)]) {
    let mut central = Central::new(CentralConfig {
        max_waiting: 4,
        max_wait: Duration::from_millis(300),
        max_queued_messages: 3,
        max_queued_bytes: 64,
        policy: Some(fuzz_policy()),
        ..CentralConfig::default()
    });
    let mut out = Vec::new();
    let mut now = 1_000_000_000u64;
    for (kind, link, bytes) in ops {
        now += 1_000_000;
        let link = 1 + link % 4;
        let event = match kind % 8 {
            0 => Event::Opened(link),
            1 => Event::Closed(link),
            2 => {
                now += 100_000_000;
                Event::Tick
            }
            3 => Event::InboxFull(
                link,
                Bytes::from(bytes.clone()),
                tca_central::core::InboxUse {
                    frames: 9,
                    bytes: 9,
                },
            ),
            _ => Event::Frame(link, Bytes::from(bytes.clone())),
        };
        central.handle(now, event, &mut out);
        for action in out.drain(..) {
            if let Action::Send(_, frame) = action {
                assert!(
                    decode(&frame, usize::MAX).is_ok(),
                    "central sent a bad frame"
                );
            }
        }
    }
}

/// Frames a module on `link` would send, to seed the core target.
fn core_seeds() -> Vec<Vec<u8>> {
    let mut seeds = Vec::new();
    for link in 1..=4u32 {
        let module = format!("m{link}");
        let hello_env = if link % 2 == 0 {
            envelope(
                link,
                0,
                Class::Control,
                names::HELLO_AUTH,
                &module,
                encode_data(&AuthHello {
                    hello: hello(&module),
                    credentials: Credentials {
                        identity: module.clone(),
                        secret: "s".into(),
                    },
                })
                .unwrap(),
            )
        } else {
            envelope(
                link,
                0,
                Class::Control,
                names::HELLO,
                &module,
                encode_data(&hello(&module)).unwrap(),
            )
        };
        seeds.push(encode(&hello_env).unwrap());
        let (msg, class) = [
            ("q", Class::Query),
            ("g", Class::Goal),
            ("i", Class::Inform),
            ("c", Class::Command),
        ][(link - 1) as usize];
        let reg = envelope(
            link,
            1,
            Class::Control,
            names::REGISTER,
            &module,
            encode_data(&Register {
                entries: vec![registration(msg, class)],
            })
            .unwrap(),
        );
        seeds.push(encode(&reg).unwrap());
        let data = encode_data(&(1u32, "d".to_owned(), vec![0.5f64])).unwrap();
        for (seq, (msg, class)) in [
            ("q", Class::Query),
            ("g", Class::Goal),
            ("i", Class::Inform),
            ("c", Class::Command),
        ]
        .into_iter()
        .enumerate()
        {
            let e = envelope(link, 2 + seq as u32, class, msg, &module, data.clone());
            seeds.push(encode(&e).unwrap());
        }
    }
    seeds
}

fn core_ops(seeds: Arc<Vec<Vec<u8>>>) -> impl Strategy<Value = Vec<(u8, u32, Vec<u8>)>> {
    proptest::collection::vec((any::<u8>(), any::<u32>(), input(seeds)), 1..60)
}

// ---------------------------------------------------------------------------------------------
// CI runs: a few cases per target.

fn ci_cases() -> u32 {
    std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(64)
}

fn ci_config() -> ProptestConfig {
    ProptestConfig {
        cases: ci_cases(),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(ci_config())]

    #[test]
    fn codec_answers_every_input(bytes in input(Arc::new(seed_frames()))) {
        target_codec(&bytes);
    }

    #[test]
    fn log_reader_answers_every_input(bytes in input(Arc::new(vec![seed_log()]))) {
        target_log(&bytes);
    }

    #[test]
    fn core_answers_every_event_sequence(ops in core_ops(Arc::new(core_seeds()))) {
        target_core(&ops);
    }
}

#[test]
fn the_seeds_are_valid() {
    for f in seed_frames() {
        assert!(decode(&f, usize::MAX).is_ok());
    }
    let log = LogFile::parse(Path::new("seed.mcap"), &seed_log()).unwrap();
    assert!(log.records.len() >= 8, "{}", log.records.len());
    assert!(log.truncated.is_none());
}

// ---------------------------------------------------------------------------------------------
// The long run.

/// What a long run of one target found.
#[derive(Default)]
struct RunReport {
    /// Inputs run.
    inputs: u64,
    /// Distinct findings (by panic message), each with how often it was hit and one minimal
    /// input.
    findings: Vec<(String, u64, String)>,
}

/// Runs `test` on inputs from `strategy` until `deadline`, with a fresh seed per round of 2,000
/// cases. A failing round is recorded (its input shrunk) and the run goes on with a new seed.
fn run_until<S: Strategy>(
    strategy: S,
    deadline: Instant,
    round: &mut u64,
    test: impl Fn(&S::Value),
) -> RunReport
where
    S::Value: std::fmt::Debug,
{
    let count = AtomicU64::new(0);
    let mut report = RunReport::default();
    while Instant::now() < deadline {
        *round += 1;
        let mut seed = [0u8; 32];
        seed[..8].copy_from_slice(&round.to_le_bytes());
        let t = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos() as u64)
            .unwrap_or(0);
        seed[8..16].copy_from_slice(&t.to_le_bytes());
        let config = Config {
            cases: 2_000,
            failure_persistence: None,
            max_shrink_iters: 2_000,
            ..Config::default()
        };
        let mut runner =
            TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
        let result = runner.run(&strategy, |v| {
            count.fetch_add(1, Ordering::Relaxed);
            test(&v);
            Ok(())
        });
        let (reason, input) = match result {
            Ok(()) => continue,
            Err(TestError::Fail(reason, value)) => (reason.to_string(), format!("{value:?}")),
            Err(TestError::Abort(reason)) => (format!("aborted: {reason}"), String::new()),
        };
        match report.findings.iter_mut().find(|f| f.0 == reason) {
            Some(f) => f.1 += 1,
            None => report.findings.push((reason, 1, input)),
        }
    }
    report.inputs = count.load(Ordering::Relaxed);
    report
}

#[test]
#[ignore = "long run: FUZZ_SECONDS=600 cargo test -p tca-central --release --test integration -- --ignored fuzz_long_run"]
fn fuzz_long_run() {
    let seconds: u64 = std::env::var("FUZZ_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60);
    let start = Instant::now();
    let slice = Duration::from_secs(seconds) / 3;
    let mut round = 0u64;
    let mut lines = Vec::new();
    let mut findings = Vec::new();
    let mut record = |target: &str, t: Instant, unit: &str, report: RunReport| {
        lines.push(format!(
            "{target}: {} {unit} in {:.0?}, {} distinct findings",
            report.inputs,
            t.elapsed(),
            report.findings.len()
        ));
        for (reason, hits, input) in report.findings {
            let short: String = input.chars().take(4_000).collect();
            findings.push(format!(
                "{target}: {reason} (hit in {hits} rounds); minimal input: {short}"
            ));
        }
    };
    let t = Instant::now();
    let r = run_until(input(Arc::new(seed_frames())), t + slice, &mut round, |b| {
        target_codec(b)
    });
    record("codec", t, "inputs", r);
    let t = Instant::now();
    let r = run_until(
        input(Arc::new(vec![seed_log()])),
        t + slice,
        &mut round,
        |b| target_log(b),
    );
    record("log reader", t, "inputs", r);
    let t = Instant::now();
    let r = run_until(
        core_ops(Arc::new(core_seeds())),
        t + slice,
        &mut round,
        |ops| target_core(ops),
    );
    record("core", t, "event sequences (1-60 events each)", r);
    eprintln!(
        "fuzz long run, {:.0?} in all, {round} rounds of up to 2000 inputs:\n  {}",
        start.elapsed(),
        lines.join("\n  ")
    );
    assert!(findings.is_empty(), "findings:\n{}", findings.join("\n"));
}

/// The long run's finding in the log reader, reduced by hand: an MCAP chunk (no compression)
/// whose inner record claims more bytes than the chunk holds. mcap 0.26's linear reader then
/// subtracts past zero (`compressed_remaining -= ...`, sans_io/linear_reader.rs:745): a panic
/// with overflow checks (debug and test builds), a silent wrap in release builds, where the
/// reader goes on reading the rest of the file as the chunk's records. The fix belongs in
/// tca-logs' reader (check each chunk's inner record lengths against the chunk before handing
/// it to mcap, or read chunks itself) or in mcap. Fixed: the reader turns the panic into a
/// corrupt-file error.
#[test]
fn known_finding_mcap_chunk_record_overrun() {
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    let record = |bytes: &mut Vec<u8>, opcode: u8, body: &[u8]| {
        bytes.push(opcode);
        bytes.extend_from_slice(&(body.len() as u64).to_le_bytes());
        bytes.extend_from_slice(body);
    };
    // Header: profile "", library "".
    record(&mut bytes, 0x01, &[0u8; 8]);
    // Chunk: its records area is 9 bytes, one record header claiming 16 bytes of body.
    let mut inner = vec![0x01u8];
    inner.extend_from_slice(&16u64.to_le_bytes());
    let mut chunk = Vec::new();
    chunk.extend_from_slice(&0u64.to_le_bytes()); // message start time
    chunk.extend_from_slice(&0u64.to_le_bytes()); // message end time
    chunk.extend_from_slice(&(inner.len() as u64).to_le_bytes()); // uncompressed size
    chunk.extend_from_slice(&0u32.to_le_bytes()); // uncompressed crc (0: not checked)
    chunk.extend_from_slice(&0u32.to_le_bytes()); // compression ""
    chunk.extend_from_slice(&(inner.len() as u64).to_le_bytes()); // records length
    chunk.extend_from_slice(&inner);
    record(&mut bytes, 0x06, &chunk);
    // What follows the chunk: enough bytes for the overrun to read.
    bytes.extend_from_slice(&[0u8; 64]);
    let result = std::panic::catch_unwind(|| {
        LogFile::parse(Path::new("overrun.mcap"), &bytes).map(|l| l.records.len())
    });
    assert!(
        result.is_ok(),
        "the log reader panicked on a chunk record overrun"
    );
}
