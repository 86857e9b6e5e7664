//! A module's side of the local link: a Unix socket to central that outlives central.
//!
//! One task per link carries frames both ways. When the socket ends (central was killed or
//! stopped) the module hears [`Presence::Down`] at once; the task then connects again,
//! backing off from [`RETRY_PERIOD_INIT_MS`] to [`RETRY_PERIOD_MAX_MS`], and on success the
//! module hears [`Presence::Up`] and says hello again. What the module sent while central was
//! gone is dropped. Dropping the link ([`Link::keep`]) closes the socket, which central notices
//! at once.

use std::path::{Path, PathBuf};
use std::time::Duration;

use bytes::Bytes;
use futures::future::BoxFuture;
use tokio::io::{AsyncWriteExt, BufWriter};
use tokio::net::UnixStream;
use tokio::sync::{mpsc, oneshot};

use crate::local::endpoint::{LocalEndpoint, check_private_dir};
use crate::local::frame::{FrameReader, read_greeting, write_frame};
use crate::outbox::FrameReceiver;
use crate::transport::{FrameSender, Link, Presence, SendFrame, Transport};
use crate::zenoh::{RETRY_PERIOD_INIT_MS, RETRY_PERIOD_MAX_MS};
use crate::{LinkError, Result};

/// Largest frame a module accepts from central.
const MAX_FRAME_FROM_CENTRAL: usize = 1 << 30;

/// Bytes written to the socket at once, at most.
const WRITE_BUFFER: usize = 64 << 10;

/// How long central may take to greet a new connection.
const GREETING_TIMEOUT: Duration = Duration::from_secs(5);

/// Opens links to a central on this machine over its local socket.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LocalTransport {
    endpoint: LocalEndpoint,
}

impl LocalTransport {
    /// Connects to central at `endpoint` (`local` or `local/NAME`).
    pub fn new(endpoint: &str) -> Result<Self> {
        Ok(LocalTransport {
            endpoint: LocalEndpoint::parse(endpoint)?,
        })
    }

    /// The endpoint it connects to.
    pub fn endpoint(&self) -> &LocalEndpoint {
        &self.endpoint
    }

    async fn open_link(&self) -> Result<Link> {
        let path = self.endpoint.socket_path()?;
        let stream = connect(&self.endpoint, &path).await?;
        let (up_tx, up_rx) = mpsc::unbounded_channel();
        let (down_tx, down_rx) = mpsc::unbounded_channel();
        let (presence_tx, presence) = mpsc::unbounded_channel();
        let (keep, stop) = oneshot::channel::<()>();
        let carrier = Carrier {
            endpoint: self.endpoint.clone(),
            path,
            up: up_rx,
            down: down_tx,
            presence: presence_tx,
            stop,
        };
        tokio::spawn(carrier.run(stream));
        Ok(Link {
            sender: FrameSender::new(LocalSender(up_tx)),
            receiver: FrameReceiver::from(down_rx),
            presence: Some(presence),
            keep: Box::new(keep),
        })
    }
}

impl Transport for LocalTransport {
    fn open(&self) -> BoxFuture<'_, Result<Link>> {
        Box::pin(self.open_link())
    }

    fn describe(&self) -> String {
        format!("central on this machine at {}", self.endpoint)
    }
}

/// Frames to central, handed to the link's task.
#[derive(Debug)]
struct LocalSender(mpsc::UnboundedSender<Bytes>);

impl SendFrame for LocalSender {
    fn send(&self, frame: Bytes) -> Result<()> {
        self.0.send(frame).map_err(|_| LinkError::Stopped)
    }
}

/// Connects to central's socket and reads its greeting.
async fn connect(endpoint: &LocalEndpoint, path: &Path) -> Result<UnixStream> {
    let start = format!("start one with `tca central --listen {endpoint}`");
    if let Some(dir) = path.parent()
        && dir.exists()
    {
        check_private_dir(dir)?;
    }
    let mut stream = UnixStream::connect(path).await.map_err(|e| {
        LinkError::Open(match e.kind() {
            std::io::ErrorKind::NotFound => format!(
                "no central at {endpoint}: {} does not exist; {start}",
                path.display()
            ),
            std::io::ErrorKind::ConnectionRefused => format!(
                "no central at {endpoint}: {} was left by a central that stopped; {start}",
                path.display()
            ),
            std::io::ErrorKind::PermissionDenied => format!(
                "cannot connect to central at {endpoint}: permission denied on {} (it belongs \
                 to another user; run the module as central's user)",
                path.display()
            ),
            _ => format!("cannot connect to central at {endpoint}: {e}"),
        })
    })?;
    let greeting = tokio::time::timeout(GREETING_TIMEOUT, read_greeting(&mut stream))
        .await
        .map_err(|_| {
            LinkError::Open(format!(
                "central at {endpoint} did not greet within {GREETING_TIMEOUT:?}"
            ))
        })?
        .map_err(|e| LinkError::Open(format!("central at {endpoint}: {e}")))?;
    match greeting {
        None => Ok(stream),
        Some(reason) => Err(LinkError::Open(format!(
            "central at {endpoint} refused this connection: {reason}"
        ))),
    }
}

/// How one connection ended.
enum End {
    /// The module dropped the link: stop.
    Stop,
    /// The socket ended or broke: central is gone.
    Lost,
}

/// The task that carries one link's frames, across reconnections.
struct Carrier {
    endpoint: LocalEndpoint,
    path: PathBuf,
    up: mpsc::UnboundedReceiver<Bytes>,
    down: mpsc::UnboundedSender<Bytes>,
    presence: mpsc::UnboundedSender<Presence>,
    stop: oneshot::Receiver<()>,
}

impl Carrier {
    async fn run(mut self, mut stream: UnixStream) {
        loop {
            if let End::Stop = self.carry(stream).await {
                return;
            }
            tracing::warn!(endpoint = %self.endpoint, "central's local socket ended; connecting again");
            let _ = self.presence.send(Presence::Down);
            match self.reconnect().await {
                Some(s) => stream = s,
                None => return,
            }
            tracing::info!(endpoint = %self.endpoint, "connected to central again");
            let _ = self.presence.send(Presence::Up);
        }
    }

    /// Carries frames both ways on one connection until it ends or the module stops.
    async fn carry(&mut self, stream: UnixStream) -> End {
        let (r, w) = stream.into_split();
        let mut r = FrameReader::new(r, MAX_FRAME_FROM_CENTRAL);
        let mut w = BufWriter::with_capacity(WRITE_BUFFER, w);
        let down = &self.down;
        let up = &mut self.up;
        let reader = async {
            loop {
                match r.next().await {
                    Ok(Some(frame)) => {
                        if down.send(frame).is_err() {
                            return End::Stop;
                        }
                    }
                    Ok(None) => return End::Lost,
                    Err(e) => {
                        tracing::warn!(error = %e, "bad data from central's local socket");
                        return End::Lost;
                    }
                }
            }
        };
        let writer = async {
            loop {
                let Some(frame) = up.recv().await else {
                    return End::Stop;
                };
                if write_batch(&mut w, frame, up).await.is_err() {
                    return End::Lost;
                }
            }
        };
        tokio::select! {
            end = reader => end,
            end = writer => end,
            _ = &mut self.stop => End::Stop,
        }
    }

    /// Connects again, backing off; `None` when the module stopped meanwhile.
    async fn reconnect(&mut self) -> Option<UnixStream> {
        let mut wait = Duration::from_millis(RETRY_PERIOD_INIT_MS);
        loop {
            tokio::select! {
                _ = &mut self.stop => return None,
                _ = tokio::time::sleep(wait) => {}
            }
            // What was sent to the central that is gone means nothing to the next one.
            while self.up.try_recv().is_ok() {}
            match connect(&self.endpoint, &self.path).await {
                Ok(stream) => {
                    while self.up.try_recv().is_ok() {}
                    return Some(stream);
                }
                Err(e) => tracing::debug!(error = %e, "central is not back yet"),
            }
            wait = (wait * 2).min(Duration::from_millis(RETRY_PERIOD_MAX_MS));
        }
    }
}

/// Writes `first` and every frame already waiting, then flushes.
async fn write_batch<W: tokio::io::AsyncWrite + Unpin>(
    w: &mut BufWriter<W>,
    first: Bytes,
    up: &mut mpsc::UnboundedReceiver<Bytes>,
) -> std::io::Result<()> {
    write_frame(w, &first).await?;
    while w.buffer().len() < WRITE_BUFFER
        && let Ok(frame) = up.try_recv()
    {
        write_frame(w, &frame).await?;
    }
    w.flush().await
}
