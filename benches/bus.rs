//! Bus benchmarks: routed query round trips and goal throughput through central, in-process
//! and over zenoh loopback, logging on (goals in-process also with central keeping its
//! journal); with the baselines measured in the same run (a raw tokio channel round trip, a raw
//! zenoh get/queryable round trip through a router) and central's own cost per message (the
//! sans-I/O core plus the log writer, no transport). Every timing loop runs as a task on a
//! runtime worker, as the `tca` command runs its work.
//!
//! Run: `cargo bench --bench bus` (figures in BENCHMARKS.md).

use std::sync::Arc;

use std::time::Duration;

use bytes::Bytes;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use tca_central::{Action, Central, CentralConfig, Event, StartOptions};
use tca_messages::control::{Hello, Register, names};
use tca_messages::*;
use tca_module::{Connector, Module};
use tca_ping::echo::{self, Ping};

#[path = "common/goal_flood.rs"]
mod goal_flood;
use goal_flood::GoalCount;
#[path = "common/on_worker.rs"]
mod on_worker;
use on_worker::time_on_worker;
use tokio::runtime::Runtime;
use tokio::sync::mpsc;

/// The allocator the `tca` command uses, so that what is measured here is what it runs.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn runtime() -> Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime")
}

fn free_endpoint() -> String {
    tca_link::net::free_loopback_endpoint().expect("a free loopback port")
}

/// Baseline: a request/response over two tokio channels between two tasks.
fn raw_tokio(c: &mut Criterion, rt: &Runtime) {
    let (req_tx, mut req_rx) = mpsc::unbounded_channel::<Bytes>();
    let (rep_tx, rep_rx) = mpsc::unbounded_channel::<Bytes>();
    rt.spawn(async move {
        while let Some(b) = req_rx.recv().await {
            let _ = rep_tx.send(b);
        }
    });
    let rep_rx = Arc::new(tokio::sync::Mutex::new(rep_rx));
    c.bench_function("baseline/tokio_channel_round_trip", |b| {
        b.iter_custom(|iters| {
            let req_tx = req_tx.clone();
            let rep_rx = rep_rx.clone();
            time_on_worker(rt, iters, move || {
                let req_tx = req_tx.clone();
                let rep_rx = rep_rx.clone();
                async move {
                    req_tx.send(Bytes::from_static(b"ping")).unwrap();
                    rep_rx.lock().await.recv().await.unwrap()
                }
            })
        })
    });
}

/// Baseline: zenoh get -> queryable -> reply, two client sessions through a router.
fn raw_zenoh(c: &mut Criterion, rt: &Runtime) {
    let endpoint = free_endpoint();
    let (router, asker, _queryable) = rt.block_on(async {
        let router =
            zenoh::open(tca_link::zenoh::router_config(std::slice::from_ref(&endpoint)).unwrap())
                .await
                .unwrap();
        let client = || async {
            zenoh::open(tca_link::zenoh::client_config(std::slice::from_ref(&endpoint)).unwrap())
                .await
                .unwrap()
        };
        let answerer = client().await;
        let queryable = answerer
            .declare_queryable("bench/echo")
            .callback(|query| {
                use zenoh::Wait;
                let payload = query
                    .payload()
                    .map(|p| p.to_bytes().into_owned())
                    .unwrap_or_default();
                let _ = query.reply("bench/echo", payload).wait();
            })
            .await
            .unwrap();
        let asker = client().await;
        tokio::time::sleep(Duration::from_millis(300)).await;
        (router, asker, (answerer, queryable))
    });
    c.bench_function("baseline/zenoh_get_queryable_round_trip", |b| {
        b.iter_custom(|iters| {
            let asker = asker.clone();
            time_on_worker(rt, iters, move || {
                let asker = asker.clone();
                async move {
                    let replies = asker
                        .get("bench/echo")
                        .payload(vec![0u8; 16])
                        .await
                        .unwrap();
                    replies.recv_async().await.unwrap()
                }
            })
        })
    });
    drop(router);
}

struct Bus {
    central: tca_central::RunningCentral,
    pinger: Module,
    _echo: Module,
    _dir: tempfile::TempDir,
}

fn bus(rt: &Runtime, zenoh: bool) -> Bus {
    rt.block_on(async {
        let dir = tempfile::tempdir().unwrap();
        let endpoint = free_endpoint();
        let central = tca_central::start(StartOptions {
            log: Some(dir.path().join("bench.mcap")),
            listen: if zenoh {
                vec![endpoint.clone()]
            } else {
                vec![]
            },
            ..StartOptions::default()
        })
        .await
        .unwrap();
        let connector = if zenoh {
            Connector::zenoh(endpoint)
        } else {
            Connector::from(central.in_process())
        };
        let echo = echo::connect(&connector, "echo").await.unwrap();
        let pinger = Module::builder("pinger").connect(&connector).await.unwrap();
        Bus {
            central,
            pinger,
            _echo: echo,
            _dir: dir,
        }
    })
}

fn routed_query(c: &mut Criterion, rt: &Runtime, zenoh: bool) {
    let bus = bus(rt, zenoh);
    let name = if zenoh {
        "central/zenoh_routed_query_round_trip"
    } else {
        "central/inproc_routed_query_round_trip"
    };
    c.bench_function(name, |b| {
        b.iter_custom(|iters| {
            let pinger = bus.pinger.clone();
            time_on_worker(rt, iters, move || {
                let pinger = pinger.clone();
                async move {
                    pinger
                        .query(&Ping {
                            seq: 1,
                            payload: vec![0; 16],
                        })
                        .await
                        .unwrap()
                }
            })
        })
    });
    rt.block_on(async { bus.central.shutdown().await.unwrap() });
}

/// Goals through central, in-process or over zenoh, central keeping a journal or not.
fn goal_throughput(c: &mut Criterion, rt: &Runtime, zenoh: bool, journal: bool) {
    let goals = GoalCount::new();
    let (central, sender, _sink, _dir) = rt.block_on(async {
        let dir = tempfile::tempdir().unwrap();
        let endpoint = free_endpoint();
        let central = tca_central::start(StartOptions {
            log: Some(dir.path().join("bench.mcap")),
            listen: if zenoh {
                vec![endpoint.clone()]
            } else {
                vec![]
            },
            journal: journal.then(|| dir.path().join("central.journal")),
            ..StartOptions::default()
        })
        .await
        .unwrap();
        let connector = if zenoh {
            Connector::zenoh(endpoint)
        } else {
            Connector::from(central.in_process())
        };
        let sink = goals.sink("sink").connect(&connector).await.unwrap();
        let sender = Module::builder("sender").connect(&connector).await.unwrap();
        (central, sender, sink, dir)
    });
    let name = match (zenoh, journal) {
        (true, false) => "central/zenoh_goal_throughput",
        (true, true) => "central/zenoh_goal_throughput_journaled",
        (false, false) => "central/inproc_goal_throughput",
        (false, true) => "central/inproc_goal_throughput_journaled",
    };
    goal_flood::measure(c, rt, name, &sender, &goals);
    rt.block_on(async { central.shutdown().await.unwrap() });
}

/// Central's own cost: a query and its reply through the core, log records written to an MCAP
/// file by the writer, no transport.
fn core_cost(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = tca_logs::LogWriter::create(&dir.path().join("core.mcap")).unwrap();
    let mut core = Central::new(CentralConfig::default());
    let mut out = Vec::new();
    let now = now_ns();
    let env =
        |link: u32, seq: u32, module: &str, class: Class, name: &str, data: Vec<u8>| Envelope {
            id: MessageId::new(link, seq),
            class,
            name: MessageName::new(name).unwrap(),
            sender: ModuleName::new(module).unwrap(),
            context: None,
            node: None,
            correlation: None,
            cause: None,
            timestamp_ns: now,
            options: SendOptions::default(),
            redelivery: 0,
            data,
        };
    for (link, module) in [(1u32, "echo"), (2u32, "pinger")] {
        core.handle(now, Event::Opened(link), &mut out);
        let hello = Hello {
            module: ModuleName::new(module).unwrap(),
            capacity: 1,
            pid: 0,
            host: "bench".into(),
            simulated_time: false,
        };
        let e = env(
            0,
            0,
            module,
            Class::Control,
            names::HELLO,
            encode_data(&hello).unwrap(),
        );
        core.handle(
            now,
            Event::Frame(link, encode(&e).unwrap().into()),
            &mut out,
        );
    }
    let reg = control::Registration {
        name: MessageName::new("tca-ping").unwrap(),
        class: Class::Query,
        format: DataFormat::of::<Ping>().unwrap(),
        reply: Some(DataFormat::of::<Ping>().unwrap()),
        replace: false,
    };
    let e = env(
        1,
        1,
        "echo",
        Class::Control,
        names::REGISTER,
        encode_data(&Register { entries: vec![reg] }).unwrap(),
    );
    core.handle(now, Event::Frame(1, encode(&e).unwrap().into()), &mut out);
    out.clear();
    let payload = encode_data(&Ping {
        seq: 1,
        payload: vec![0; 16],
    })
    .unwrap();
    let mut seq = 10u32;
    let mut group = c.benchmark_group("central");
    group.throughput(Throughput::Elements(2));
    group.bench_function("core_query_and_reply_with_logging", |b| {
        b.iter(|| {
            seq += 1;
            let q = env(2, seq, "pinger", Class::Query, "tca-ping", payload.clone());
            let mut r = env(1, seq, "echo", Class::Reply, "tca-ping", payload.clone());
            r.correlation = Some(q.id);
            core.handle(now, Event::Frame(2, encode(&q).unwrap().into()), &mut out);
            core.handle(now, Event::Frame(1, encode(&r).unwrap().into()), &mut out);
            for a in out.drain(..) {
                if let Action::Log(rec) = a {
                    writer.append(&rec).unwrap();
                }
            }
        })
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    let rt = runtime();
    core_cost(c);
    raw_tokio(c, &rt);
    routed_query(c, &rt, false);
    goal_throughput(c, &rt, false, false);
    goal_throughput(c, &rt, false, true);
    raw_zenoh(c, &rt);
    routed_query(c, &rt, true);
    goal_throughput(c, &rt, true, false);
}

criterion_group! {
    name = bus_benches;
    config = Criterion::default().measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    targets = benches
}
criterion_main!(bus_benches);
