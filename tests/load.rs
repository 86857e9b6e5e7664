//! CI's check of the load benchmark's promise, short: 100 modules exchanging queries, goals
//! and informs through one central for 2 s, in-process, over zenoh and over the local link, logging on. Nothing may
//! be lost, central's queues stay within their limits, and the process's peak memory stays
//! far from what unbounded queues would take. (The figures come from `cargo bench --bench
//! load`; nothing here is timed.) This file holds a single test, so the peak memory is its own.

use std::time::Duration;

use tca_load::{LoadOptions, TransportKind};

/// Far above what 100 modules need (about 100 MiB), far below what unbounded queues take.
const PEAK_RSS_LIMIT_KIB: u64 = 1 << 20;

#[test]
fn a_hundred_modules_lose_nothing_and_central_stays_bounded() {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    for transport in [
        TransportKind::InProcess,
        TransportKind::Zenoh,
        TransportKind::Local,
    ] {
        let options = LoadOptions {
            modules: 100,
            duration: Duration::from_secs(2),
            transport,
            ..LoadOptions::default()
        };
        let dir = tempfile::tempdir().unwrap();
        let report = runtime
            .block_on(tca_load::run(&options, dir.path()))
            .unwrap();
        let table = report.table();
        assert_eq!(report.losses(), Vec::<String>::new(), "{table}");
        assert_eq!(report.past_limits(), Vec::<String>::new(), "{table}");
        for c in [report.queries, report.goals, report.informs] {
            assert!(c.completed > 0, "every class flowed: {table}");
        }
        assert!(report.log_bytes > 0, "logging on: {table}");
        if let Some(peak) = report.peak_rss_kib {
            assert!(peak < PEAK_RSS_LIMIT_KIB, "{table}");
        }
    }
}
