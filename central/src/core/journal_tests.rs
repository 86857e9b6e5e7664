//! Property tests of the journal's core side: a central saved part-way through a random run and
//! restored, given the rest of the run's events, does exactly what the original did (every
//! frame sent, every log record, every close); so does one that replays the rest from the
//! journal entries the original wrote. Runs on the wall clock and on the simulated clock, with
//! goals, commands, queries and informs delivered, answered, failed and killed, and modules
//! leaving and coming back.

use bytes::Bytes;
use proptest::prelude::*;
use tca_messages::control::{self, Hello, Kill, Register, Registration, names};
use tca_messages::*;

use super::*;
use crate::journal::format;

/// A tiny deterministic generator (the run adapts to what central sends, so it draws as it goes).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const MODULES: [(&str, &str, Class); 4] = [
    ("m1", "q", Class::Query),
    ("m2", "g", Class::Goal),
    ("m3", "c", Class::Command),
    ("m4", "i", Class::Inform),
];

/// Builds the events of a run as central answers them.
struct Run {
    central: Central,
    rng: Rng,
    now: u64,
    sim: u64,
    seq: u32,
    simulated: bool,
    /// The link each module is on now (links are never reused).
    links: [Option<LinkId>; 4],
    next_link: LinkId,
    /// Messages central delivered to a handler and not yet answered: (module index, envelope).
    delivered: Vec<(usize, Envelope)>,
    nodes: Vec<NodeId>,
    events: Vec<(u64, Event)>,
    actions: Vec<String>,
}

fn actions_text(out: &mut Vec<Action>) -> Vec<String> {
    out.drain(..).map(|a| format!("{a:?}")).collect()
}

impl Run {
    fn new(seed: u64, simulated: bool) -> Self {
        let mut central = Central::new(config(simulated));
        central.record_journal(42);
        Run {
            central,
            rng: Rng(seed),
            now: 1_000_000_000,
            sim: 1_000,
            seq: 10,
            simulated,
            links: [None; 4],
            next_link: 1,
            delivered: Vec::new(),
            nodes: Vec::new(),
            events: Vec::new(),
            actions: Vec::new(),
        }
    }

    fn step(&mut self, event: Event) {
        self.now += 1_000_000;
        self.events.push((self.now, event.clone()));
        let mut out = Vec::new();
        self.central.handle(self.now, event, &mut out);
        for action in &out {
            if let Action::Send(link, frame) = action {
                self.observe(*link, frame);
            }
        }
        self.actions.extend(actions_text(&mut out));
    }

    fn observe(&mut self, link: LinkId, frame: &Bytes) {
        let Ok(e) = decode(frame, usize::MAX) else {
            return;
        };
        let Some(m) = self.links.iter().position(|l| *l == Some(link)) else {
            return;
        };
        if let Some(node) = e.node {
            self.nodes.push(node);
        }
        if e.class.is_handled() && e.sender.as_str() != "central" || e.class.is_task() {
            self.delivered.push((m, e));
        }
    }

    fn envelope(&mut self, m: usize, class: Class, name: &str, data: Vec<u8>) -> Envelope {
        self.seq += 1;
        self.sim += 1_000 + self.rng.below(5_000) as u64;
        let link = self.links[m].unwrap_or(0);
        Envelope {
            id: MessageId::new(link, self.seq),
            class,
            name: MessageName::new(name).unwrap(),
            sender: ModuleName::new(MODULES[m].0).unwrap(),
            context: None,
            node: None,
            correlation: None,
            cause: None,
            timestamp_ns: if self.simulated { self.sim } else { self.now },
            options: SendOptions::default(),
            redelivery: 0,
            data,
        }
    }

    fn frame(&mut self, m: usize, e: &Envelope) {
        let Some(link) = self.links[m] else { return };
        self.step(Event::Frame(link, Bytes::from(encode(e).unwrap())));
    }

    fn connect(&mut self, m: usize) {
        let link = self.next_link;
        self.next_link += 1;
        self.links[m] = Some(link);
        self.step(Event::Opened(link));
        let (module, name, class) = MODULES[m];
        let mut hello = self.envelope(
            m,
            Class::Control,
            names::HELLO,
            encode_data(&Hello {
                module: ModuleName::new(module).unwrap(),
                capacity: 1 + (m as u32 % 2),
                pid: 0,
                host: "test".into(),
                simulated_time: self.simulated,
            })
            .unwrap(),
        );
        hello.id = MessageId::new(0, 0);
        self.frame(m, &hello);
        let register = self.envelope(
            m,
            Class::Control,
            names::REGISTER,
            encode_data(&Register {
                entries: vec![Registration {
                    name: MessageName::new(name).unwrap(),
                    class,
                    format: DataFormat::of::<u8>().unwrap(),
                    reply: (class == Class::Query).then(|| DataFormat::of::<u8>().unwrap()),
                    replace: false,
                }],
            })
            .unwrap(),
        );
        self.frame(m, &register);
    }

    /// One random thing happens.
    fn act(&mut self) {
        let m = self.rng.below(4);
        match self.rng.below(10) {
            0..=3 => {
                // Send a message of a random kind, maybe under a node of a task it handles.
                let (_, name, class) = MODULES[self.rng.below(4)];
                let data = vec![self.rng.below(256) as u8];
                let mut e = self.envelope(m, class, name, data);
                if class.is_task() && !self.nodes.is_empty() && self.rng.below(2) == 0 {
                    e.context = Some(self.nodes[self.rng.below(self.nodes.len())]);
                }
                e.options.notify = self.rng.below(2) == 0;
                self.frame(m, &e);
            }
            4..=6 => {
                // A handler answers something it was delivered.
                if self.delivered.is_empty() {
                    return;
                }
                let (h, asked) = self.delivered.remove(self.rng.below(self.delivered.len()));
                let class = match asked.class {
                    Class::Query if self.rng.below(4) > 0 => Class::Reply,
                    _ if self.rng.below(4) == 0 => Class::Failure,
                    _ => Class::Success,
                };
                let data = match class {
                    Class::Failure => encode_data(&Failure {
                        reason: "no".into(),
                    })
                    .unwrap(),
                    _ => vec![1],
                };
                let mut e = self.envelope(h, class, asked.name.as_str(), data);
                e.correlation = Some(asked.id);
                e.cause = Some(asked.id);
                e.node = asked.node;
                self.frame(h, &e);
            }
            7 => {
                // Kill a node.
                if self.nodes.is_empty() {
                    return;
                }
                let node = self.nodes[self.rng.below(self.nodes.len())];
                let e = self.envelope(
                    m,
                    Class::Control,
                    names::KILL,
                    encode_data(&Kill { node }).unwrap(),
                );
                self.frame(m, &e);
            }
            8 => {
                // A module leaves, or comes back.
                match self.links[m] {
                    Some(link) => {
                        self.links[m] = None;
                        self.delivered.retain(|(h, _)| *h != m);
                        self.step(Event::Closed(link));
                    }
                    None => self.connect(m),
                }
            }
            _ => {
                self.now += self.rng.below(2_000) as u64 * 1_000_000;
                self.step(Event::Tick);
            }
        }
    }
}

fn config(simulated: bool) -> CentralConfig {
    CentralConfig {
        max_waiting: 6,
        max_wait: std::time::Duration::from_millis(800),
        simulated_time: simulated,
        ..CentralConfig::default()
    }
}

fn entries(bytes: &[u8]) -> Vec<JournalEntry> {
    let mut file = format::MAGIC.to_vec();
    let head = format::Head {
        version: String::new(),
        id: 0,
        config: CentralConfig::default(),
        log_records: None,
        log_prefix: Vec::new(),
        log_kept_as: None,
        state: Vec::new(),
    };
    format::append_record(&mut file, &head).unwrap();
    file.extend_from_slice(bytes);
    format::parse(&file).unwrap().unwrap().entries
}

/// The first difference between two action lists, if any.
fn same(expected: &[String], got: &[String], what: &str) -> Result<(), TestCaseError> {
    let i = expected.iter().zip(got).position(|(a, b)| a != b);
    if i.is_none() && expected.len() == got.len() {
        return Ok(());
    }
    let i = i.unwrap_or(expected.len().min(got.len()));
    Err(TestCaseError::fail(format!(
        "{what} central differs at action {i} of {} / {}:\nexpected {:?}\ngot      {:?}",
        expected.len(),
        got.len(),
        expected.get(i),
        got.get(i)
    )))
}

fn check(seed: u64, simulated: bool, steps: usize, cut: usize) -> Result<(), TestCaseError> {
    let mut run = Run::new(seed, simulated);
    for m in 0..4 {
        run.connect(m);
    }
    for _ in 0..cut {
        run.act();
    }
    let saved = run.central.save().unwrap();
    let mut journal = Vec::new();
    run.central.take_journal(&mut journal);
    journal.clear();
    let (events_before, actions_before) = (run.events.len(), run.actions.len());
    for _ in cut..steps {
        run.act();
    }
    run.central.take_journal(&mut journal);
    let expected = &run.actions[actions_before..];
    let later = &run.events[events_before..];

    // Restored, then handed the same events.
    let mut restored = Central::restore(&saved, config(simulated)).unwrap();
    restored.set_journal_id(42);
    let mut out = Vec::new();
    let mut got = Vec::new();
    for (now, event) in later {
        restored.handle(*now, event.clone(), &mut out);
        got.extend(actions_text(&mut out));
    }
    same(expected, &got, "restored")?;
    prop_assert_eq!(restored.render_tree(), run.central.render_tree());

    // Restored, then replaying the journal's entries.
    let entries = entries(&journal);
    prop_assert_eq!(entries.len(), later.len());
    let mut replayed = Central::restore(&saved, config(simulated)).unwrap();
    replayed.set_journal_id(42);
    let mut got = Vec::new();
    for entry in entries {
        replayed.replay(entry, &mut out).unwrap();
        got.extend(actions_text(&mut out));
    }
    same(expected, &got, "replayed")?;
    prop_assert_eq!(replayed.render_tree(), run.central.render_tree());
    prop_assert_eq!(replayed.counters(), run.central.counters());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn a_restored_central_does_what_the_original_did(
        seed in any::<u64>(),
        simulated in any::<bool>(),
        cut in 0usize..150,
    ) {
        check(seed, simulated, 150, cut)?;
    }
}

#[test]
fn a_crash_closes_every_link_and_tasks_are_delivered_again_marked() {
    let mut run = Run::new(3, false);
    for m in 0..4 {
        run.connect(m);
    }
    let goal = run.envelope(0, Class::Goal, "g", vec![1]);
    run.frame(0, &goal);
    assert!(
        run.delivered
            .iter()
            .any(|(m, e)| *m == 1 && e.id == goal.id),
        "the goal went to m2"
    );
    let saved = run.central.save().unwrap();
    let mut restored = Central::restore(&saved, config(false)).unwrap();
    assert_eq!(restored.highest_link(), 4);
    let mut out = Vec::new();
    restored.links_lost(run.now + 1, &mut out);
    assert!(restored.connected_modules().is_empty());
    assert_eq!(restored.live_nodes(), 1, "the goal lives on");
    // m2 comes back (on a new link) and gets the goal again, marked.
    let mut back = Run {
        central: restored,
        next_link: 5,
        links: [None; 4],
        ..Run::new(4, false)
    };
    back.connect(1);
    let again: Vec<&Envelope> = back
        .delivered
        .iter()
        .filter(|(_, e)| e.id == goal.id)
        .map(|(_, e)| e)
        .collect();
    assert_eq!(again.len(), 1, "{:?}", back.actions);
    assert_eq!(again[0].redelivery, 1);
}

#[test]
fn a_hello_is_journaled_without_its_secret_and_replayed_with_its_grant() {
    let text = format!(
        "[[identity]]\nname = \"ctl\"\nsecret_sha3 = \"{}\"\nregister = [\"c\"]\nsend = [\"i\"]\n",
        crate::policy::hash_secret("ctl", "s3cret-value"),
    );
    let policy = crate::Policy::parse(std::path::Path::new("p.toml"), &text).unwrap();
    let config = CentralConfig {
        policy: Some(std::sync::Arc::new(policy)),
        ..CentralConfig::default()
    };
    let mut central = Central::new(config.clone());
    let saved = central.save().unwrap();
    central.record_journal(1);
    let mut out = Vec::new();
    central.handle(10, Event::Opened(1), &mut out);
    let hello = control::AuthHello {
        hello: Hello {
            module: ModuleName::new("m3").unwrap(),
            capacity: 1,
            pid: 1,
            host: "test".into(),
            simulated_time: false,
        },
        credentials: control::Credentials {
            identity: "ctl".into(),
            secret: "s3cret-value".into(),
        },
    };
    let envelope = |id, class, name: &str, data| Envelope {
        id,
        class,
        name: MessageName::new(name).unwrap(),
        sender: ModuleName::new("m3").unwrap(),
        context: None,
        node: None,
        correlation: None,
        cause: None,
        timestamp_ns: 10,
        options: SendOptions::default(),
        redelivery: 0,
        data,
    };
    let frame = |e: &Envelope| Event::Frame(1, Bytes::from(encode(e).unwrap()));
    let hello = envelope(
        MessageId::new(0, 0),
        Class::Control,
        names::HELLO_AUTH,
        encode_data(&hello).unwrap(),
    );
    central.handle(11, frame(&hello), &mut out);
    // A send its grant refuses, after it.
    let refused = envelope(MessageId::new(1, 2), Class::Query, "q", vec![]);
    central.handle(12, frame(&refused), &mut out);
    let original = actions_text(&mut out);
    assert!(
        original.iter().any(|a| a.contains("no pattern of")),
        "{original:?}"
    );
    let mut journal = Vec::new();
    central.take_journal(&mut journal);
    assert!(
        !journal.windows(12).any(|w| w == b"s3cret-value"),
        "the secret is not in the journal"
    );
    // Replayed with no policy at all: the grant comes from the journal.
    let mut replayed = Central::restore(&saved, CentralConfig::default()).unwrap();
    replayed.set_journal_id(1);
    let mut got = Vec::new();
    for entry in entries(&journal) {
        replayed.replay(entry, &mut out).unwrap();
        got.extend(actions_text(&mut out));
    }
    assert_eq!(original, got);
}

#[test]
fn every_event_is_journaled_as_the_entry_it_is_read_back_as() {
    let frame = Bytes::from_static(b"a frame's bytes");
    let inbox = InboxUse {
        frames: 3,
        bytes: 400,
    };
    let outbox = OutboxUse {
        frames: 5,
        bytes: 600,
    };
    let l: LinkId = 7;
    let events = [
        (Event::Opened(l), JournaledEvent::Opened(l)),
        (
            Event::Frame(l, frame.clone()),
            JournaledEvent::Frame(l, frame.clone()),
        ),
        (Event::Closed(l), JournaledEvent::Closed(l)),
        (Event::Tick, JournaledEvent::Tick),
        (
            Event::InboxFull(l, frame.clone(), inbox),
            JournaledEvent::InboxFull(l, frame.clone(), (3, 400)),
        ),
        (
            Event::InboxDropped(l, 9),
            JournaledEvent::InboxDropped(l, 9),
        ),
        (
            Event::OutboxLevel(l, outbox),
            JournaledEvent::OutboxLevel(l, (5, 600)),
        ),
        (
            Event::OutboxFull(l, outbox),
            JournaledEvent::OutboxFull(l, (5, 600)),
        ),
        (
            Event::Identified(l, "ctl".into()),
            JournaledEvent::Identified(l, "ctl".into()),
        ),
    ];
    for (i, (event, journaled)) in events.into_iter().enumerate() {
        let at_ns = 1_000 + i as u64;
        let mut core = Central::new(CentralConfig::default());
        core.record_journal(1);
        let open = core.journal_begin(at_ns, &event);
        core.journal_end(at_ns, open);
        let mut written = Vec::new();
        core.take_journal(&mut written);
        let mut expected = Vec::new();
        let entry = JournalEntry {
            at_ns,
            event: journaled,
            facts: Vec::new(),
        };
        format::append_record(&mut expected, &entry).unwrap();
        assert_eq!(written, expected, "{entry:?}");
        assert_eq!(entries(&written), vec![entry]);
    }
}
