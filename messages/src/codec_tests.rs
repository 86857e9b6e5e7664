//! Round trips, golden bytes and refusals of the codec.

use proptest::prelude::*;

use crate::*;

fn sample() -> Envelope {
    Envelope {
        id: MessageId::new(2, 5),
        class: Class::Command,
        name: MessageName::new("moveBase").unwrap(),
        sender: ModuleName::new("gait").unwrap(),
        context: Some(NodeId(3)),
        node: None,
        correlation: None,
        cause: None,
        timestamp_ns: 1_000,
        options: SendOptions::default(),
        redelivery: 0,
        data: encode_data(&1.5f64).unwrap(),
    }
}

#[test]
fn golden_bytes_of_a_frame() {
    // Any change to these bytes is a wire-protocol change: bump PROTOCOL_VERSION.
    let frame = encode(&sample()).unwrap();
    let expected: Vec<u8> = [
        vec![2],                            // protocol version
        vec![0x85, 0x80, 0x80, 0x80, 0x20], // id = 2 << 32 | 5, varint
        vec![2],                            // class Command
        vec![8],
        b"moveBase".to_vec(), // name
        vec![4],
        b"gait".to_vec(),                      // sender
        vec![1, 3],                            // context Some(n3)
        vec![0],                               // node None
        vec![0],                               // correlation None
        vec![0],                               // cause None
        vec![0xe8, 0x07],                      // timestamp 1000
        vec![0, 0],                            // options: no constraints, notify false
        vec![0],                               // redelivery
        vec![8, 0, 0, 0, 0, 0, 0, 0xf8, 0x3f], // data: 8 bytes of 1.5f64
    ]
    .concat();
    assert_eq!(frame, expected);
    assert_eq!(decode(&frame, DEFAULT_MAX_FRAME_BYTES).unwrap(), sample());
}

#[test]
fn bad_frames_are_refused_with_reasons() {
    let frame = encode(&sample()).unwrap();
    assert_eq!(decode(&[], 100), Err(CodecError::Empty));
    let mut v2 = frame.clone();
    v2[0] = 9;
    assert!(matches!(
        decode(&v2, 1 << 20),
        Err(CodecError::Version { found: 9, .. })
    ));
    assert!(matches!(
        decode(&frame, 10),
        Err(CodecError::TooLarge { limit: 10, .. })
    ));
    let mut long = frame.clone();
    long.push(0);
    assert!(matches!(
        decode(&long, 1 << 20),
        Err(CodecError::Trailing { extra: 1, .. })
    ));
    let short = &frame[..frame.len() - 3];
    let err = decode(short, 1 << 20).unwrap_err();
    assert!(err.to_string().starts_with("malformed envelope"), "{err}");
    assert!(err.to_string().len() > "malformed envelope: ".len());
    // class byte 200 is not a class
    let mut bad_class = frame.clone();
    bad_class[6] = 200;
    assert!(decode(&bad_class, 1 << 20).is_err());
    // a space in the name
    let mut bad_name = frame;
    bad_name[8] = b' ';
    let err = decode(&bad_name, 1 << 20).unwrap_err();
    assert!(err.to_string().contains("message name"), "{err}");
}

fn name() -> impl Strategy<Value = String> {
    "[A-Za-z0-9_.-]{1,24}"
}

fn class() -> impl Strategy<Value = Class> {
    proptest::sample::select(Class::ALL.to_vec())
}

fn point() -> impl Strategy<Value = PointRef> {
    let task = prop_oneof![
        Just(TaskRef::This),
        any::<u64>().prop_map(|m| TaskRef::Message(MessageId(m))),
        any::<u64>().prop_map(|n| TaskRef::Node(NodeId(n))),
    ];
    let tp = proptest::sample::select(vec![
        TimePoint::HandlingStart,
        TimePoint::HandlingEnd,
        TimePoint::AchievementStart,
        TimePoint::AchievementEnd,
    ]);
    (task, tp).prop_map(|(task, point)| PointRef { task, point })
}

prop_compose! {
    fn envelope()(id in any::<u64>(), class in class(), name in name(), sender in name(),
                  context in proptest::option::of(any::<u64>()),
                  node in proptest::option::of(any::<u64>()),
                  correlation in proptest::option::of(any::<u64>()),
                  ts in any::<u64>(), notify in any::<bool>(), redelivery in any::<u32>(),
                  constraints in proptest::collection::vec((point(), point()), 0..4),
                  data in proptest::collection::vec(any::<u8>(), 0..300)) -> Envelope {
        Envelope {
            id: MessageId(id), class,
            name: MessageName::new(name).unwrap(),
            sender: ModuleName::new(sender).unwrap(),
            context: context.map(NodeId), node: node.map(NodeId),
            correlation: correlation.map(MessageId), timestamp_ns: ts,
            cause: None,
            options: SendOptions {
                constraints: constraints.into_iter()
                    .map(|(before, after)| ConstraintSpec { before, after }).collect(),
                notify,
            },
            redelivery, data,
        }
    }
}

proptest! {
    #[test]
    fn envelopes_round_trip(e in envelope()) {
        let frame = encode(&e).unwrap();
        prop_assert_eq!(decode(&frame, usize::MAX).unwrap(), e);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let _ = decode(&bytes, 1 << 20);
    }

    #[test]
    fn corrupted_frames_never_panic(e in envelope(), at in any::<usize>(), byte in any::<u8>()) {
        let mut frame = encode(&e).unwrap();
        let i = at % frame.len();
        frame[i] = byte;
        let _ = decode(&frame, 1 << 20);
    }

    #[test]
    fn control_payloads_round_trip(n in name(), cap in any::<u32>(), pid in any::<u32>()) {
        let hello = control::Hello {
            module: ModuleName::new(n).unwrap(), capacity: cap, pid, host: "h".into(), simulated_time: false,
        };
        let bytes = encode_data(&hello).unwrap();
        prop_assert_eq!(decode_data::<control::Hello>(&bytes).unwrap(), hello);
    }
}
