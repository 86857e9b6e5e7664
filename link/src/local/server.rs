//! Central's side of the local link: a listener on the endpoint's Unix socket.
//!
//! Each accepted connection is checked against the [`PeerPolicy`] by the peer's user id, then
//! opens a link through [`Attach`]: frames read from the socket go into the link's bounded
//! inbox (one arriving at a full inbox is answered with an over-limit error instead of being
//! routed, as over zenoh), and frames central sends are written to the socket as they come,
//! batched while more are waiting. The socket's end (the module exited or was killed) closes
//! the link at once. When central stops, every socket is closed, which the modules notice at
//! once; a link central closes while it goes on (after a goodbye, or a module too slow) keeps
//! its socket until the module closes it, as over zenoh.

use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use bytes::Bytes;
use tokio::io::{AsyncWriteExt, BufWriter};
use tokio::net::{UnixListener, UnixStream};
use tokio::sync::{oneshot, watch};
use tokio::task::JoinHandle;

use crate::inbox::Inbox;
use crate::local::endpoint::LocalEndpoint;
use crate::local::frame::{FrameReader, write_frame, write_greeting};
use crate::local::peer::PeerPolicy;
use crate::outbox::FrameReceiver;
use crate::{LinkError, LinkId, Result};

/// Bytes written to the socket at once, at most (frames are batched up to this).
const WRITE_BUFFER: usize = 64 << 10;

/// What a listener needs from central: links for new connections.
pub trait Attach: Send + Sync + 'static {
    /// Opens a link: its number, its inbox, and the receiver of what central sends on it.
    /// `None` when central has stopped.
    fn attach(&self) -> Option<(LinkId, Arc<Inbox>, FrameReceiver)>;

    /// The connection of `link` ended (the module left, crashed or broke the protocol).
    fn closed(&self, link: LinkId);
}

/// Central listening on a local endpoint. Dropping it (when central stops) stops accepting,
/// removes the socket file and closes every connection once what central sent on it is
/// written.
#[derive(Debug)]
pub struct LocalListener {
    endpoint: LocalEndpoint,
    path: PathBuf,
    task: JoinHandle<()>,
    stop: watch::Sender<bool>,
}

impl LocalListener {
    /// Listens on `endpoint`'s socket (mode 0600, in the private runtime directory). A socket
    /// file left by a central that died is replaced; one a live central listens on is an error.
    /// Frames longer than `max_frame_bytes` end their connection. Call within a tokio runtime.
    pub fn bind(
        endpoint: &LocalEndpoint,
        peers: PeerPolicy,
        max_frame_bytes: usize,
        attach: Arc<dyn Attach>,
    ) -> Result<Self> {
        let path = endpoint.prepare()?;
        clear_stale(endpoint, &path)?;
        let listener = UnixListener::bind(&path).map_err(|e| {
            LinkError::Config(format!(
                "cannot listen on {endpoint} ({}): {e}",
                path.display()
            ))
        })?;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).map_err(|e| {
            LinkError::Config(format!("cannot make {} private: {e}", path.display()))
        })?;
        let peers = Arc::new(peers);
        let name = endpoint.to_string();
        let (stop, stopped) = watch::channel(false);
        let task = tokio::spawn(async move {
            loop {
                match listener.accept().await {
                    Ok((stream, _)) => {
                        tokio::spawn(serve(
                            stream,
                            peers.clone(),
                            max_frame_bytes,
                            attach.clone(),
                            stopped.clone(),
                        ));
                    }
                    Err(e) => {
                        tracing::warn!(endpoint = %name, error = %e, "accepting a local connection failed");
                        tokio::time::sleep(std::time::Duration::from_millis(10)).await;
                    }
                }
            }
        });
        tracing::info!(%endpoint, path = %path.display(), "central listening on a local socket");
        Ok(LocalListener {
            endpoint: endpoint.clone(),
            path,
            task,
            stop,
        })
    }

    /// The endpoint.
    pub fn endpoint(&self) -> &LocalEndpoint {
        &self.endpoint
    }

    /// The socket file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for LocalListener {
    fn drop(&mut self) {
        self.task.abort();
        self.stop.send_replace(true);
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Removes a socket file no central listens on any more; refuses to touch a live one or a
/// file that is not a socket.
fn clear_stale(endpoint: &LocalEndpoint, path: &Path) -> Result<()> {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    if !meta.file_type().is_socket() {
        return Err(LinkError::Config(format!(
            "cannot listen on {endpoint}: {} exists and is not a socket; remove it",
            path.display()
        )));
    }
    match std::os::unix::net::UnixStream::connect(path) {
        Ok(_) => Err(LinkError::Config(format!(
            "a central is already listening on {endpoint} ({}); stop it, or give this one \
             another name such as local/{}-2",
            path.display(),
            endpoint.name()
        ))),
        Err(_) => {
            tracing::info!(path = %path.display(), "replacing the socket of a central that stopped");
            std::fs::remove_file(path).map_err(|e| {
                LinkError::Config(format!(
                    "cannot remove the stale socket {}: {e}",
                    path.display()
                ))
            })
        }
    }
}

/// One connection: the peer check, then frames both ways until either side ends.
async fn serve(
    stream: UnixStream,
    peers: Arc<PeerPolicy>,
    max_frame_bytes: usize,
    attach: Arc<dyn Attach>,
    stopped: watch::Receiver<bool>,
) {
    let refusal = match stream.peer_cred() {
        Ok(cred) => peers.admit(cred.uid(), cred.pid()).err(),
        Err(e) => Some(format!("cannot tell who the peer is: {e}")),
    };
    let (reader, writer) = stream.into_split();
    // Buffered both ways: a burst of frames costs a few system calls, not two per frame.
    let mut reader = FrameReader::new(reader, max_frame_bytes);
    let mut writer = BufWriter::with_capacity(WRITE_BUFFER, writer);
    if let Some(reason) = refusal {
        tracing::warn!(%reason, "refused a local connection");
        let _ = write_greeting(&mut writer, Some(&reason)).await;
        return;
    }
    if write_greeting(&mut writer, None).await.is_err() {
        return;
    }
    let Some((link, inbox, rx)) = attach.attach() else {
        return;
    };
    let (reader_done, reader_ended) = oneshot::channel();
    tokio::spawn(write_frames(link, writer, rx, stopped, reader_ended));
    loop {
        match reader.next().await {
            Ok(Some(frame)) => inbox.push_or_refuse(frame),
            Ok(None) => break,
            Err(e) => {
                tracing::warn!(link, error = %e, "local link broken; closing it");
                break;
            }
        }
    }
    attach.closed(link);
    drop(reader_done);
}

/// Writes what central sends on `link` to the socket, batching frames already waiting. Once
/// central has closed the link, keeps the socket until the module ends it or central stops
/// (then shuts the socket, which the module notices).
async fn write_frames(
    link: LinkId,
    mut w: BufWriter<tokio::net::unix::OwnedWriteHalf>,
    mut rx: FrameReceiver,
    mut stopped: watch::Receiver<bool>,
    reader_ended: oneshot::Receiver<()>,
) {
    while let Some(frame) = rx.recv().await {
        if let Err(e) = write_batch(&mut w, frame, &mut rx).await {
            tracing::debug!(link, error = %e, "writing to a local link failed");
            return;
        }
    }
    tokio::select! {
        _ = stopped.wait_for(|s| *s) => {}
        _ = reader_ended => {}
    }
    let _ = w.shutdown().await;
}

/// Writes `first` and every frame already waiting, then flushes.
pub(crate) async fn write_batch<W: tokio::io::AsyncWrite + Unpin>(
    w: &mut BufWriter<W>,
    first: Bytes,
    rx: &mut FrameReceiver,
) -> std::io::Result<()> {
    write_frame(w, &first).await?;
    while w.buffer().len() < WRITE_BUFFER
        && let Some(frame) = rx.try_recv()
    {
        write_frame(w, &frame).await?;
    }
    w.flush().await
}
