//! Round trips between two processes on this machine, three ways: a Unix socket with blocking
//! reads, iceoryx2's shared-memory publish-subscribe with each side sleeping on an iceoryx2
//! event until the other notifies it, and the same with both sides spinning on the shared
//! memory (a core each, all the time). Each round trip carries one 8-byte counter there and
//! back; 2,000 warm-up trips, then 20,000 timed. The program starts a copy of itself as the
//! echo (`echo MODE`).
//!
//! `cargo run --release --manifest-path benches/ipc-candidates/Cargo.toml [socket|wait|spin]`
//! (all three by default).

use std::io::{Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

use iceoryx2::prelude::*;

type Error = Box<dyn core::error::Error>;

const WARM_UP: usize = 2_000;
const TIMED: usize = 20_000;
/// How long an echo runs at most, so that none is left behind.
const ECHO_LIFETIME: Duration = Duration::from_secs(60);

fn main() -> Result<(), Error> {
    // iceoryx2 warns that it found no config file and uses its defaults, as meant here.
    set_log_level(LogLevel::Error);
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("echo") {
        let mode = args.get(1).map(String::as_str).unwrap_or_default();
        let at = args.get(2).map(String::as_str).unwrap_or_default();
        return echo(mode, at);
    }
    let modes: Vec<&str> = match args.first() {
        Some(m) => vec![m.as_str()],
        None => vec!["socket", "wait", "spin"],
    };
    for mode in modes {
        let mut samples = match mode {
            "socket" => socket_round_trips()?,
            "wait" | "spin" => iceoryx2_round_trips(mode)?,
            other => {
                return Err(format!("unknown mode {other:?}: give socket, wait or spin").into());
            }
        };
        samples.sort_by(f64::total_cmp);
        println!(
            "{:<44} p50 {:>6.1} µs   p99 {:>6.1} µs   min {:>5.1} µs",
            describe(mode),
            samples[samples.len() / 2],
            samples[samples.len() * 99 / 100],
            samples[0]
        );
    }
    Ok(())
}

fn describe(mode: &str) -> &'static str {
    match mode {
        "socket" => "Unix socket, blocking reads",
        "wait" => "iceoryx2, sleeping on events",
        _ => "iceoryx2, both sides spinning",
    }
}

fn start_echo(mode: &str, at: &str) -> Result<Child, Error> {
    Ok(Command::new(std::env::current_exe()?)
        .args(["echo", mode, at])
        .spawn()?)
}

/// Times `trip` WARM_UP + TIMED times; the timed ones in µs.
fn time(mut trip: impl FnMut(u64) -> Result<(), Error>) -> Result<Vec<f64>, Error> {
    let mut samples = Vec::with_capacity(TIMED);
    for i in 0..(WARM_UP + TIMED) as u64 {
        let t = Instant::now();
        trip(i)?;
        if i as usize >= WARM_UP {
            samples.push(t.elapsed().as_secs_f64() * 1e6);
        }
    }
    Ok(samples)
}

fn socket_round_trips() -> Result<Vec<f64>, Error> {
    let dir = std::env::temp_dir().join(format!("tca-ipc-candidates-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("echo.sock");
    let listener = UnixListener::bind(&path)?;
    let mut child = start_echo(
        "socket",
        path.to_str().ok_or("a temporary path that is not UTF-8")?,
    )?;
    let (mut s, _) = listener.accept()?;
    let result = time(|i| {
        s.write_all(&i.to_le_bytes())?;
        let mut back = [0u8; 8];
        s.read_exact(&mut back)?;
        if u64::from_le_bytes(back) != i {
            return Err("the echo answered out of turn".into());
        }
        Ok(())
    });
    drop(s);
    let _ = child.wait();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// The services of one measurement, named after this process so that runs do not meet.
struct Ports {
    node: Node<ipc::Service>,
    prefix: String,
}

impl Ports {
    fn new(prefix: String) -> Result<Self, Error> {
        Ok(Ports {
            node: NodeBuilder::new().create::<ipc::Service>()?,
            prefix,
        })
    }

    fn topic(
        &self,
        name: &str,
    ) -> Result<
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, u64, ()>,
        Error,
    > {
        let name = format!("{}/{name}", self.prefix);
        Ok(self
            .node
            .service_builder(&name.as_str().try_into()?)
            .publish_subscribe::<u64>()
            .open_or_create()?)
    }

    fn event(
        &self,
        name: &str,
    ) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, Error> {
        let name = format!("{}/{name}", self.prefix);
        Ok(self
            .node
            .service_builder(&name.as_str().try_into()?)
            .event()
            .open_or_create()?)
    }
}

fn iceoryx2_round_trips(mode: &str) -> Result<Vec<f64>, Error> {
    let spin = mode == "spin";
    let prefix = format!("tca-ipc-candidates/{}", std::process::id());
    let ports = Ports::new(prefix.clone())?;
    let out = ports.topic("there")?.publisher_builder().create()?;
    let back = ports.topic("back")?.subscriber_builder().create()?;
    let ring = ports.event("there-event")?.notifier_builder().create()?;
    let woken = ports.event("back-event")?.listener_builder().create()?;
    let mut child = start_echo(mode, &prefix)?;
    // The echo's ports must exist before the first sample, or it is lost.
    let there = ports.topic("there")?;
    let started = Instant::now();
    while there.dynamic_config().number_of_subscribers() == 0 {
        if started.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            return Err("the echo did not open its ports within 10 s".into());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(100));
    let result = time(|i| {
        out.send_copy(i)?;
        if !spin {
            ring.notify()?;
        }
        loop {
            if !spin {
                woken.timed_wait_all(|_| {}, Duration::from_millis(100))?;
            }
            if let Some(sample) = back.receive()? {
                if *sample != i {
                    return Err("the echo answered out of turn".into());
                }
                return Ok(());
            }
        }
    });
    let _ = child.kill();
    let _ = child.wait();
    result
}

fn echo(mode: &str, at: &str) -> Result<(), Error> {
    let until = Instant::now() + ECHO_LIFETIME;
    if mode == "socket" {
        let mut s = UnixStream::connect(at)?;
        let mut buf = [0u8; 8];
        while Instant::now() < until && s.read_exact(&mut buf).is_ok() {
            s.write_all(&buf)?;
        }
        return Ok(());
    }
    let spin = mode == "spin";
    let ports = Ports::new(at.to_string())?;
    let back = ports.topic("back")?.publisher_builder().create()?;
    let ring = ports.event("back-event")?.notifier_builder().create()?;
    let woken = ports.event("there-event")?.listener_builder().create()?;
    let there = ports.topic("there")?.subscriber_builder().create()?;
    while Instant::now() < until {
        if !spin {
            woken.timed_wait_all(|_| {}, Duration::from_millis(100))?;
        }
        while let Some(sample) = there.receive()? {
            back.send_copy(*sample)?;
            if !spin {
                ring.notify()?;
            }
        }
    }
    Ok(())
}
