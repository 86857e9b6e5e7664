//! The local link's wire: a greeting from central, then frames, each a little-endian `u32`
//! length followed by that many bytes (an encoded envelope).
//!
//! Central's greeting is [`MAGIC`] and one status byte: [`ADMITTED`], or [`REFUSED`] followed
//! by a length-prefixed UTF-8 reason, after which central closes the socket.

use bytes::{Buf, Bytes, BytesMut};
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};

/// The first bytes central writes on a local link (protocol version 1).
pub const MAGIC: &[u8; 4] = b"TCA\x01";
/// The status byte of an admitted connection.
pub const ADMITTED: u8 = 0;
/// The status byte of a refused connection.
pub const REFUSED: u8 = 1;

/// Writes one frame (not flushed).
pub async fn write_frame<W: AsyncWrite + Unpin>(w: &mut W, frame: &[u8]) -> std::io::Result<()> {
    let len = u32::try_from(frame.len()).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("frame of {} bytes is too large", frame.len()),
        )
    })?;
    w.write_all(&len.to_le_bytes()).await?;
    w.write_all(frame).await
}

/// Reads one frame; `None` at a clean end of stream (between frames). A frame longer than
/// `max` bytes is an error.
pub async fn read_frame<R: AsyncRead + Unpin>(
    r: &mut R,
    max: usize,
) -> std::io::Result<Option<Bytes>> {
    let mut len = [0u8; 4];
    match r.read_exact(&mut len).await {
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
        Err(e) => return Err(e),
    }
    let len = u32::from_le_bytes(len) as usize;
    if len > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("frame of {len} bytes is over the limit of {max}"),
        ));
    }
    let mut buf = BytesMut::zeroed(len);
    r.read_exact(&mut buf).await?;
    Ok(Some(buf.freeze()))
}

/// Bytes asked of the socket at once, at least.
const READ_CHUNK: usize = 64 << 10;

/// Reads frames from a stream into one growing buffer and hands each out as a slice of it
/// (no copy per frame, as tokio-util's framed readers do).
#[derive(Debug)]
pub struct FrameReader<R> {
    inner: R,
    buf: BytesMut,
    max: usize,
}

impl<R: AsyncRead + Unpin> FrameReader<R> {
    /// Reads frames of at most `max` bytes from `inner`.
    pub fn new(inner: R, max: usize) -> Self {
        FrameReader {
            inner,
            buf: BytesMut::with_capacity(READ_CHUNK),
            max,
        }
    }

    /// The next frame; `None` at a clean end of stream (between frames). A frame longer than
    /// the limit, or a stream ending inside a frame, is an error.
    pub async fn next(&mut self) -> std::io::Result<Option<Bytes>> {
        loop {
            let mut need = 4;
            if self.buf.len() >= 4 {
                let len = u32::from_le_bytes([self.buf[0], self.buf[1], self.buf[2], self.buf[3]])
                    as usize;
                if len > self.max {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        format!("frame of {len} bytes is over the limit of {}", self.max),
                    ));
                }
                if self.buf.len() >= 4 + len {
                    self.buf.advance(4);
                    return Ok(Some(self.buf.split_to(len).freeze()));
                }
                need = 4 + len;
            }
            let want = (need - self.buf.len()).max(READ_CHUNK / 4);
            if self.buf.capacity() - self.buf.len() < want {
                self.buf.reserve(want.max(READ_CHUNK));
            }
            if self.inner.read_buf(&mut self.buf).await? == 0 {
                return if self.buf.is_empty() {
                    Ok(None)
                } else {
                    Err(std::io::Error::new(
                        std::io::ErrorKind::UnexpectedEof,
                        "the stream ended inside a frame",
                    ))
                };
            }
        }
    }
}

/// Writes central's greeting: admitted, or refused with `reason`.
pub async fn write_greeting<W: AsyncWrite + Unpin>(
    w: &mut W,
    refusal: Option<&str>,
) -> std::io::Result<()> {
    w.write_all(MAGIC).await?;
    match refusal {
        None => w.write_all(&[ADMITTED]).await?,
        Some(reason) => {
            w.write_all(&[REFUSED]).await?;
            write_frame(w, reason.as_bytes()).await?;
        }
    }
    w.flush().await
}

/// Reads central's greeting: `Ok(None)` when admitted, `Ok(Some(reason))` when refused.
pub async fn read_greeting<R: AsyncRead + Unpin>(r: &mut R) -> std::io::Result<Option<String>> {
    let mut head = [0u8; 5];
    r.read_exact(&mut head).await?;
    if &head[..4] != MAGIC {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "the socket's server is not a tca central (or speaks another version)",
        ));
    }
    match head[4] {
        ADMITTED => Ok(None),
        REFUSED => {
            let reason = read_frame(r, 64 << 10).await?.unwrap_or_default();
            Ok(Some(String::from_utf8_lossy(&reason).into_owned()))
        }
        other => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("unknown greeting status {other}"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn frames_round_trip_and_long_ones_are_refused() {
        let (mut a, mut b) = tokio::io::duplex(1024);
        write_frame(&mut a, b"hello").await.unwrap();
        write_frame(&mut a, b"").await.unwrap();
        write_frame(&mut a, &[7u8; 100]).await.unwrap();
        assert_eq!(
            read_frame(&mut b, 64).await.unwrap().unwrap(),
            &b"hello"[..]
        );
        assert_eq!(read_frame(&mut b, 64).await.unwrap().unwrap(), &b""[..]);
        let err = read_frame(&mut b, 64).await.unwrap_err();
        assert!(err.to_string().contains("over the limit"), "{err}");
        drop(a);
        let (a, mut b) = tokio::io::duplex(16);
        drop(a);
        assert!(read_frame(&mut b, 64).await.unwrap().is_none());
    }

    #[tokio::test]
    async fn a_frame_reader_slices_frames_across_reads() {
        let (mut a, b) = tokio::io::duplex(7);
        let mut reader = FrameReader::new(b, 64);
        let writer = tokio::spawn(async move {
            write_frame(&mut a, b"hello").await.unwrap();
            write_frame(&mut a, b"").await.unwrap();
            write_frame(&mut a, &[9u8; 40]).await.unwrap();
            write_frame(&mut a, &[1u8; 65]).await.unwrap();
        });
        assert_eq!(reader.next().await.unwrap().unwrap(), &b"hello"[..]);
        assert_eq!(reader.next().await.unwrap().unwrap(), &b""[..]);
        assert_eq!(reader.next().await.unwrap().unwrap(), &[9u8; 40][..]);
        let err = reader.next().await.unwrap_err();
        assert!(err.to_string().contains("over the limit"), "{err}");
        writer.abort();
        let (mut a, b) = tokio::io::duplex(64);
        a.write_all(&[3, 0, 0, 0, 1]).await.unwrap();
        drop(a);
        let mut reader = FrameReader::new(b, 64);
        assert!(reader.next().await.is_err(), "ended inside a frame");
        let (a, b) = tokio::io::duplex(64);
        drop(a);
        assert!(FrameReader::new(b, 64).next().await.unwrap().is_none());
    }

    #[tokio::test]
    async fn greetings_admit_or_refuse_with_a_reason() {
        let (mut a, mut b) = tokio::io::duplex(1024);
        write_greeting(&mut a, None).await.unwrap();
        write_greeting(&mut a, Some("uid 1001 may not connect"))
            .await
            .unwrap();
        assert_eq!(read_greeting(&mut b).await.unwrap(), None);
        assert_eq!(
            read_greeting(&mut b).await.unwrap().as_deref(),
            Some("uid 1001 may not connect")
        );
        let (mut a, mut b) = tokio::io::duplex(1024);
        a.write_all(b"HTTP/").await.unwrap();
        assert!(read_greeting(&mut b).await.is_err());
    }
}
