//! A transport-only baseline for routed round trips across processes: the same 20-byte
//! length-prefixed frame as the local link, sent from the bench through a relay process to an
//! echo process and back (four socket hops, as a query routed through central to a module in
//! another process makes), with none of central's work. The relay and the echo are this bench
//! executable started again with [`ROLE_VAR`] set; each runs its sockets on a tokio runtime
//! with the `tca` command's default of two workers.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{UnixListener, UnixStream};

/// Environment variable naming the role a started copy of the bench plays.
pub(crate) const ROLE_VAR: &str = "TCA_BENCH_RAW_RELAY_ROLE";

/// Bytes in a frame: a 4-byte length and a 16-byte payload.
pub(crate) const FRAME: usize = 20;

/// Plays the role named in [`ROLE_VAR`] if it is set (and returns true): `echo`, `SOCKET` or
/// `relay`, `SOCKET`, `TARGET` (one word per line), until its peer closes.
pub(crate) fn run_role_if_asked() -> bool {
    let Ok(role) = std::env::var(ROLE_VAR) else {
        return false;
    };
    let words: Vec<&str> = role.split('\n').collect();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(async {
        match words.as_slice() {
            ["echo", socket] => echo(Path::new(socket)).await,
            ["relay", socket, target] => relay(Path::new(socket), Path::new(target)).await,
            _ => panic!("{ROLE_VAR}={role:?}: expected `echo`, SOCKET or `relay`, SOCKET, TARGET, one per line"),
        }
    });
    true
}

async fn echo(socket: &Path) {
    let listener = UnixListener::bind(socket).expect("echo binds");
    let (mut s, _) = listener.accept().await.expect("echo accepts");
    let mut frame = [0u8; FRAME];
    while s.read_exact(&mut frame).await.is_ok() {
        if s.write_all(&frame).await.is_err() {
            return;
        }
    }
}

async fn relay(socket: &Path, target: &Path) {
    let listener = UnixListener::bind(socket).expect("relay binds");
    let (left, _) = listener.accept().await.expect("relay accepts");
    let right = connect(target).await;
    let (mut lr, mut lw) = left.into_split();
    let (mut rr, mut rw) = right.into_split();
    let up = tokio::spawn(async move {
        let mut frame = [0u8; FRAME];
        while lr.read_exact(&mut frame).await.is_ok() {
            if rw.write_all(&frame).await.is_err() {
                return;
            }
        }
    });
    let mut frame = [0u8; FRAME];
    while rr.read_exact(&mut frame).await.is_ok() {
        if lw.write_all(&frame).await.is_err() {
            break;
        }
    }
    up.abort();
}

/// Connects to `socket`, waiting for it to appear.
pub(crate) async fn connect(socket: &Path) -> UnixStream {
    for _ in 0..500 {
        if let Ok(s) = UnixStream::connect(socket).await {
            return s;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    panic!("nothing listens on {}", socket.display());
}

/// The relay and echo processes, killed when dropped.
pub(crate) struct RawRelay {
    children: Vec<Child>,
    /// The relay's socket: connect here and send frames.
    pub(crate) socket: PathBuf,
    _dir: tempfile::TempDir,
}

impl RawRelay {
    /// Starts the echo and the relay in front of it.
    pub(crate) fn start() -> Self {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let echo = dir.path().join("echo.sock");
        let socket = dir.path().join("relay.sock");
        let me = std::env::current_exe().expect("the bench executable");
        let spawn = |role: String| {
            Command::new(&me)
                .env(ROLE_VAR, role)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .spawn()
                .expect("a copy of the bench starts")
        };
        let children = vec![
            spawn(format!("echo\n{}", echo.display())),
            spawn(format!("relay\n{}\n{}", socket.display(), echo.display())),
        ];
        RawRelay {
            children,
            socket,
            _dir: dir,
        }
    }
}

impl Drop for RawRelay {
    fn drop(&mut self) {
        for c in &mut self.children {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}
