//! Length prefixes that claim gigabytes must not make the decoders reserve them: each input
//! here claims ~4 GB and is answered with an error, and the process's peak virtual memory
//! (`VmPeak`, which counts reservations even when no page is touched) grows by far less.
//! This file holds a single test so that nothing else runs in its process meanwhile.

use std::path::Path;

use tca_logs::LogFile;
use tca_messages::control::Register;
use tca_messages::{
    Class, DataFormat, Envelope, MessageId, MessageName, ModuleName, SendOptions, decode,
    decode_data, encode,
};

/// A varint of 4 294 967 295.
const HUGE_VARINT: [u8; 5] = [0xFF, 0xFF, 0xFF, 0xFF, 0x0F];

fn vm_peak_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmPeak:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// A frame whose data length (its last field) claims ~4 GB, with no data behind it.
fn frame_claiming_4gb() -> Vec<u8> {
    let envelope = Envelope {
        id: MessageId::new(1, 1),
        class: Class::Inform,
        name: MessageName::new("i").unwrap(),
        sender: ModuleName::new("m").unwrap(),
        context: None,
        node: None,
        correlation: None,
        cause: None,
        timestamp_ns: 0,
        options: SendOptions::default(),
        redelivery: 0,
        data: Vec::new(),
    };
    let mut frame = encode(&envelope).unwrap();
    assert_eq!(frame.pop(), Some(0), "the data length is the last byte");
    frame.extend_from_slice(&HUGE_VARINT);
    frame
}

/// An MCAP file whose first record claims a 4 GB body.
fn log_claiming_4gb(opcode: u8) -> Vec<u8> {
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    bytes.push(opcode);
    bytes.extend_from_slice(&(4u64 << 30).to_le_bytes());
    bytes.extend_from_slice(&[0u8; 64]);
    bytes
}

/// An MCAP chunk record (opcode 0x06) whose uncompressed size claims 4 GB.
fn log_chunk_claiming_4gb() -> Vec<u8> {
    let mut body = Vec::new();
    body.extend_from_slice(&0u64.to_le_bytes()); // message start time
    body.extend_from_slice(&0u64.to_le_bytes()); // message end time
    body.extend_from_slice(&(4u64 << 30).to_le_bytes()); // uncompressed size
    body.extend_from_slice(&0u32.to_le_bytes()); // uncompressed crc
    body.extend_from_slice(&0u32.to_le_bytes()); // compression: "" (none)
    body.extend_from_slice(&(4u64 << 30).to_le_bytes()); // records length
    body.extend_from_slice(&[0u8; 16]);
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    // A minimal header record: profile "" and library "".
    bytes.push(0x01);
    bytes.extend_from_slice(&8u64.to_le_bytes());
    bytes.extend_from_slice(&[0u8; 8]);
    bytes.push(0x06);
    bytes.extend_from_slice(&(body.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&body);
    bytes
}

#[test]
fn gigabyte_claims_are_refused_without_reserving_them() {
    let before = vm_peak_kib();

    let frame = frame_claiming_4gb();
    let err = decode(&frame, usize::MAX).unwrap_err();
    assert!(!err.to_string().is_empty());

    for target in [
        decode_data::<Register>(&HUGE_VARINT).map(|_| ()),
        decode_data::<Vec<u64>>(&HUGE_VARINT).map(|_| ()),
        decode_data::<Vec<u8>>(&HUGE_VARINT).map(|_| ()),
        decode_data::<String>(&HUGE_VARINT).map(|_| ()),
        decode_data::<DataFormat>(&HUGE_VARINT).map(|_| ()),
    ] {
        assert!(target.is_err());
    }
    for format in [
        DataFormat::of::<Vec<u8>>().unwrap(),
        DataFormat::of::<Vec<(u64, String)>>().unwrap(),
        DataFormat::of::<std::collections::BTreeMap<String, u32>>().unwrap(),
        DataFormat::of::<String>().unwrap(),
    ] {
        assert!(format.decode_value(&HUGE_VARINT).is_err());
    }
    for log in [
        log_claiming_4gb(0x01),
        log_claiming_4gb(0x06),
        log_claiming_4gb(0x05),
        log_chunk_claiming_4gb(),
    ] {
        // Either an error or a log flagged as cut short; never the claimed gigabytes.
        if let Ok(parsed) = LogFile::parse(Path::new("bomb.mcap"), &log) {
            assert!(parsed.records.is_empty());
        }
    }

    let after = vm_peak_kib();
    if let (Some(before), Some(after)) = (before, after) {
        let grown_mib = after.saturating_sub(before) / 1024;
        assert!(
            grown_mib < 512,
            "peak virtual memory grew by {grown_mib} MiB decoding length bombs"
        );
    }
}
