//! Property test: arbitrary event sequences (garbage frames, well-formed envelopes with random
//! classes, names, correlations and contexts, links opening and closing, time passing) never
//! make the core panic, every frame it sends decodes, and the per-sender queue accounting
//! always equals a recount from scratch (no leak, no double refund).

use std::time::Duration;

use bytes::Bytes;
use proptest::prelude::*;
use tca_messages::control::{Hello, Register, Registration, names};
use tca_messages::*;

use super::*;

#[derive(Clone, Debug)]
enum Op {
    Garbage(u32, Vec<u8>),
    Send {
        link: u32,
        class: Class,
        name: usize,
        correlation: Option<u32>,
        context: Option<u64>,
        data: Vec<u8>,
    },
    Open(u32),
    Close(u32),
    Tick(u64),
}

const NAMES: [&str; 5] = ["q", "g", "c", "i", names::KILL];

fn op() -> impl Strategy<Value = Op> {
    let link = 1u32..5;
    prop_oneof![
        (link.clone(), proptest::collection::vec(any::<u8>(), 0..64))
            .prop_map(|(l, b)| Op::Garbage(l, b)),
        (
            link.clone(),
            proptest::sample::select(Class::ALL.to_vec()),
            0usize..NAMES.len(),
            proptest::option::of(0u32..40),
            proptest::option::of(0u64..20),
            proptest::collection::vec(any::<u8>(), 0..16),
        )
            .prop_map(|(link, class, name, correlation, context, data)| Op::Send {
                link,
                class,
                name,
                correlation,
                context,
                data
            }),
        link.clone().prop_map(Op::Open),
        link.prop_map(Op::Close),
        (0u64..2_000).prop_map(Op::Tick),
    ]
}

fn hello(link: u32) -> Envelope {
    let module = ModuleName::new(format!("m{link}")).unwrap();
    Envelope {
        id: MessageId::new(0, 0),
        class: Class::Control,
        name: MessageName::new(names::HELLO).unwrap(),
        sender: module.clone(),
        context: None,
        node: None,
        correlation: None,
        cause: None,
        timestamp_ns: 0,
        options: SendOptions::default(),
        redelivery: 0,
        data: encode_data(&Hello {
            module,
            capacity: link,
            pid: 0,
            host: String::new(),
            simulated_time: false,
        })
        .unwrap(),
    }
}

fn registration(link: u32) -> Envelope {
    let (name, class) = match link {
        1 => ("q", Class::Query),
        2 => ("g", Class::Goal),
        3 => ("c", Class::Command),
        _ => ("i", Class::Inform),
    };
    let mut e = hello(link);
    e.id = MessageId::new(link, 1);
    e.name = MessageName::new(names::REGISTER).unwrap();
    e.data = encode_data(&Register {
        entries: vec![Registration {
            name: MessageName::new(name).unwrap(),
            class,
            format: DataFormat::of::<Vec<u8>>().unwrap(),
            reply: (class == Class::Query).then(|| DataFormat::of::<Vec<u8>>().unwrap()),
            replace: false,
        }],
    })
    .unwrap();
    e
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn central_never_panics(ops in proptest::collection::vec(op(), 1..120)) {
        let mut central = Central::new(CentralConfig {
            max_waiting: 4,
            max_wait: Duration::from_millis(500),
            max_queued_messages: 3,
            max_queued_bytes: 24,
            ..CentralConfig::default()
        });
        let mut now = 1_000_000_000u64;
        let mut out = Vec::new();
        let mut seq = 10u32;
        for link in 1..5 {
            central.handle(now, Event::Opened(link), &mut out);
            let frame = Bytes::from(encode(&hello(link)).unwrap());
            central.handle(now, Event::Frame(link, frame), &mut out);
            let frame = Bytes::from(encode(&registration(link)).unwrap());
            central.handle(now, Event::Frame(link, frame), &mut out);
        }
        for op in ops {
            now += 1_000_000;
            match op {
                Op::Garbage(link, bytes) => {
                    central.handle(now, Event::Frame(link, Bytes::from(bytes)), &mut out)
                }
                Op::Send { link, class, name, correlation, context, data } => {
                    seq += 1;
                    let e = Envelope {
                        id: MessageId::new(link, seq),
                        class,
                        name: MessageName::new(NAMES[name]).unwrap(),
                        sender: ModuleName::new(format!("m{link}")).unwrap(),
                        context: context.map(NodeId),
                        node: None,
                        correlation: correlation.map(|c| MessageId::new(1 + c % 4, c)),
                        cause: None,
                        timestamp_ns: now,
                        options: SendOptions::default(),
                        redelivery: 0,
                        data,
                    };
                    let frame = Bytes::from(encode(&e).unwrap());
                    central.handle(now, Event::Frame(link, frame), &mut out);
                }
                Op::Open(link) => {
                    central.handle(now, Event::Opened(link), &mut out);
                    let frame = Bytes::from(encode(&hello(link)).unwrap());
                    central.handle(now, Event::Frame(link, frame), &mut out);
                    let frame = Bytes::from(encode(&registration(link)).unwrap());
                    central.handle(now, Event::Frame(link, frame), &mut out);
                }
                Op::Close(link) => central.handle(now, Event::Closed(link), &mut out),
                Op::Tick(ms) => {
                    now += ms * 1_000_000;
                    central.handle(now, Event::Tick, &mut out)
                }
            }
            for action in out.drain(..) {
                if let Action::Send(_, frame) = action {
                    prop_assert!(decode(&frame, usize::MAX).is_ok());
                }
            }
            prop_assert_eq!(central.recount_queued(), central.queued_totals());
        }
    }
}
