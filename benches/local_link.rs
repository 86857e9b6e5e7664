//! Same-machine link benchmarks: query round trips and goal throughput through central over
//! the local link (Unix socket), beside in-process and zenoh tcp loopback, logging on; each
//! beside raw baselines measured in the same run (a tokio channel round trip, a raw Unix socket
//! echo round trip, and the same frame relayed through a second process to a third and back:
//! the four socket hops of a routed query without central's work).
//!
//! Central runs as its own process (`tca central --listen local/... --listen tcp/... --log`),
//! the echo module as another (`tca module echo`), and the pinger here: three processes, as
//! CMU IPC's two-module test through its central. Goal throughput: a sender and a sink here,
//! each on its own link to the central process. Besides criterion's figures, each routed
//! round trip prints its p50 and p99 over 20,000 samples. Every timing loop runs as a task on
//! a runtime worker, as the `tca` command runs its work.
//!
//! Run: `cargo bench --bench local_link` (figures in BENCHMARKS.md, "Same-machine link").

use std::io::{Read, Write};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;

use std::time::Duration;

use bytes::Bytes;
use criterion::{Criterion, criterion_group};
use tca_central::StartOptions;
use tca_module::{Connector, Module};
use tca_ping::echo::{self, Ping};

#[path = "common/goal_flood.rs"]
mod goal_flood;
use goal_flood::GoalCount;
#[path = "common/on_worker.rs"]
mod on_worker;
#[path = "common/raw_relay.rs"]
mod raw_relay;
use on_worker::{samples_on_worker, time_on_worker};
use tokio::runtime::Runtime;
use tokio::sync::mpsc;

/// The allocator the `tca` command uses, so that what is measured here is what it runs.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Samples of the percentile pass after each routed round trip.
const PERCENTILE_SAMPLES: usize = 20_000;

fn runtime() -> Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime")
}

/// A `tca` child process, killed when dropped.
struct Process(Child);

impl Process {
    fn spawn(args: &[&str]) -> Self {
        let child = Command::new(env!("CARGO_BIN_EXE_tca"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("tca starts");
        Process(child)
    }
}

impl Drop for Process {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Central as its own process, listening on a local socket and on zenoh tcp, logging.
struct CentralProcess {
    local: String,
    zenoh: String,
    _process: Process,
    _dir: tempfile::TempDir,
}

fn central_process() -> CentralProcess {
    let dir = tempfile::tempdir().unwrap();
    let local = format!("local/bench-{}", std::process::id());
    let zenoh = tca_link::net::free_loopback_endpoint().expect("a free port");
    let log = dir.path().join("bench.mcap");
    let process = Process::spawn(&[
        "central",
        "--listen",
        &local,
        "--listen",
        &zenoh,
        "--log",
        log.to_str().unwrap(),
    ]);
    CentralProcess {
        local,
        zenoh,
        _process: process,
        _dir: dir,
    }
}

/// Connects a module, retrying while central is still starting.
async fn connect_retrying(connector: &Connector, name: &str) -> Module {
    for _ in 0..300 {
        if let Ok(m) = Module::builder(name).connect(connector).await {
            return m;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("cannot connect {name} to {}", connector.describe());
}

/// Waits until the ping messages are handled by a connected module called `echo`.
async fn wait_for_echo(pinger: &Module) {
    for _ in 0..300 {
        let registry = pinger.registry().await.expect("registry");
        if registry
            .entries
            .iter()
            .any(|e| e.name.as_str() == "tca-ping" && e.handler.as_str() == "echo" && e.connected)
        {
            return;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("the echo module did not register");
}

fn ping() -> Ping {
    Ping {
        seq: 1,
        payload: vec![0; 16],
    }
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

/// Baseline: a 4-byte length and a 16-byte frame written to a Unix socket, echoed back by a
/// blocking thread, read back by a tokio task: one round trip of the local link's wire, with
/// no central. Criterion's figure, then p50/p99.
fn raw_unix_socket(c: &mut Criterion, rt: &Runtime) {
    let (server, client) = std::os::unix::net::UnixStream::pair().unwrap();
    std::thread::spawn(move || {
        let mut server = server;
        let mut buf = [0u8; raw_relay::FRAME];
        while server.read_exact(&mut buf).is_ok() {
            if server.write_all(&buf).is_err() {
                return;
            }
        }
    });
    client.set_nonblocking(true).unwrap();
    let client = rt.block_on(async { tokio::net::UnixStream::from_std(client).unwrap() });
    let client = Arc::new(tokio::sync::Mutex::new(client));
    round_trips(c, rt, "baseline/unix_socket_echo_round_trip", move || {
        frame_trip(client.clone())
    });
}

/// One round trip of a 20-byte frame (a 4-byte length and 16 bytes) over `client`.
async fn frame_trip(client: Arc<tokio::sync::Mutex<tokio::net::UnixStream>>) {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut s = client.lock().await;
    let mut frame = [0u8; raw_relay::FRAME];
    frame[..4].copy_from_slice(&16u32.to_le_bytes());
    s.write_all(&frame).await.unwrap();
    s.read_exact(&mut frame).await.unwrap();
}

/// Baseline: the 20-byte frame through a relay process to an echo process and back, four
/// socket hops across three processes as a routed query makes, with none of central's work
/// (see `common/raw_relay.rs`). Criterion's figure, then p50/p99.
fn raw_relay_round_trip(c: &mut Criterion, rt: &Runtime) {
    let relay = raw_relay::RawRelay::start();
    let socket = relay.socket.clone();
    let client = rt.block_on(async move { raw_relay::connect(&socket).await });
    let client = Arc::new(tokio::sync::Mutex::new(client));
    round_trips(c, rt, "baseline/unix_socket_relay_round_trip", move || {
        frame_trip(client.clone())
    });
    drop(relay);
}

/// Times routed query round trips from `pinger` (criterion), then prints p50/p99.
fn routed_query(c: &mut Criterion, rt: &Runtime, name: &str, pinger: &Module) {
    let pinger = pinger.clone();
    round_trips(c, rt, name, move || {
        let pinger = pinger.clone();
        async move { pinger.query(&ping()).await.unwrap() }
    });
}

/// Times round trips of `trip` (criterion, on a runtime worker), then prints p50/p99 over
/// [`PERCENTILE_SAMPLES`].
fn round_trips<F, Fut>(c: &mut Criterion, rt: &Runtime, name: &str, trip: F)
where
    F: FnMut() -> Fut + Clone + Send + 'static,
    Fut: std::future::Future + Send + 'static,
{
    c.bench_function(name, |b| {
        b.iter_custom(|iters| time_on_worker(rt, iters, trip.clone()))
    });
    let mut samples = samples_on_worker(rt, PERCENTILE_SAMPLES, trip);
    let report = tca_ping::report(&mut samples);
    eprintln!(
        "{name}: {} samples: min {:.1} µs, p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs",
        report.n, report.min_us, report.p50_us, report.p99_us, report.max_us
    );
}

/// In-process: central, echo and pinger in this process, logging on.
fn inproc_query(c: &mut Criterion, rt: &Runtime) {
    let dir = tempfile::tempdir().unwrap();
    let (central, pinger, _echo) = rt.block_on(async {
        let central = tca_central::start(StartOptions {
            log: Some(dir.path().join("bench.mcap")),
            ..StartOptions::default()
        })
        .await
        .unwrap();
        let connector = Connector::from(central.in_process());
        let echo = echo::connect(&connector, "echo").await.unwrap();
        let pinger = Module::builder("pinger").connect(&connector).await.unwrap();
        (central, pinger, echo)
    });
    routed_query(c, rt, "inproc/routed_query_round_trip", &pinger);
    rt.block_on(async { central.shutdown().await.unwrap() });
}

/// Across processes: the echo module as a process of its own connected at `echo_at`, the
/// pinger here connected at `ping_at`.
fn cross_process_query(c: &mut Criterion, rt: &Runtime, name: &str, echo_at: &str, ping_at: &str) {
    // Central is up once the pinger is connected; then the echo can join it.
    let pinger =
        rt.block_on(async { connect_retrying(&Connector::endpoint(ping_at), "pinger").await });
    let _echo = Process::spawn(&["module", "echo", "--connect", echo_at]);
    rt.block_on(wait_for_echo(&pinger));
    routed_query(c, rt, name, &pinger);
    rt.block_on(pinger.close());
}

/// Goals from a sender to a sink, each on its own link to central at `connector`.
fn goal_throughput(c: &mut Criterion, rt: &Runtime, name: &str, connector: Connector) {
    let goals = GoalCount::new();
    let sink_name = format!("sink-{}", name.replace('/', "-"));
    let (sender, sink) = rt.block_on(async {
        let sink = goals
            .sink(sink_name)
            .replace(true)
            .connect(&connector)
            .await
            .unwrap();
        let sender = connect_retrying(&connector, "sender").await;
        (sender, sink)
    });
    goal_flood::measure(c, rt, name, &sender, &goals);
    rt.block_on(async {
        sender.close().await;
        sink.close().await;
    });
}

fn benches(c: &mut Criterion) {
    let rt = runtime();
    raw_tokio(c, &rt);
    raw_unix_socket(c, &rt);
    inproc_query(c, &rt);
    let central = central_process();
    raw_relay_round_trip(c, &rt);
    cross_process_query(
        c,
        &rt,
        "local/routed_query_round_trip",
        &central.local,
        &central.local,
    );
    cross_process_query(
        c,
        &rt,
        "zenoh/routed_query_round_trip",
        &central.zenoh,
        &central.zenoh,
    );
    goal_throughput(
        c,
        &rt,
        "local/goal_throughput",
        Connector::endpoint(&central.local),
    );
    goal_throughput(
        c,
        &rt,
        "zenoh/goal_throughput",
        Connector::endpoint(&central.zenoh),
    );
    let dir = tempfile::tempdir().unwrap();
    let inproc = rt.block_on(async {
        tca_central::start(StartOptions {
            log: Some(dir.path().join("bench.mcap")),
            ..StartOptions::default()
        })
        .await
        .unwrap()
    });
    goal_throughput(
        c,
        &rt,
        "inproc/goal_throughput",
        Connector::from(inproc.in_process()),
    );
    rt.block_on(async { inproc.shutdown().await.unwrap() });
}

criterion_group! {
    name = local_link_benches;
    config = Criterion::default().measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    targets = benches
}

fn main() {
    // A copy of this executable started as the raw relay baseline's relay or echo.
    if raw_relay::run_role_if_asked() {
        return;
    }
    local_link_benches();
    Criterion::default().configure_from_args().final_summary();
}
