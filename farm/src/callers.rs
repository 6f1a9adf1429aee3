//! What one caller can hold of the coordinator (issue 35): connections, streams on one
//! connection, files being sent, and an upload that has stopped sending.
//!
//! * **Connections** (every listener: gRPC, the studio, the metrics endpoint) — at most
//!   `--max-connections` open, each sending its first bytes within `--first-request-timeout-s`
//!   and never silent for `--idle-timeout-s` ([`restauro_ops::connections`]).
//! * **Streams** — at most `--max-streams-per-connection` requests open at once on one gRPC
//!   connection (HTTP/2's SETTINGS_MAX_CONCURRENT_STREAMS).
//! * **Files sent** (results to clients, assets to workers) — at most `--max-downloads` at once,
//!   further requests refused at once (RESOURCE_EXHAUSTED, retry later). Each is read in chunks
//!   of [`DOWNLOAD_CHUNK_BYTES`] as the reader takes them: one chunk waits in the stream, none is
//!   read ahead, so what a stream holds is bounded by the chunk and HTTP/2's own window and send
//!   buffer (about 0.2 MiB), whether or not its reader reads. A reader that takes nothing for
//!   `--idle-timeout-s` loses the stream, and its place.
//! * **Uploads** (a scene's assets, a worker's tile) — a message must come every
//!   `--idle-timeout-s`, or the upload is refused and its share of the upload budget given back.

use crate::error::{FarmError, Result};
use restauro_ops::connections::ConnectionLimits;
use restauro_proto as pb;
use std::path::PathBuf;
use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;
use tokio::io::AsyncReadExt;
use tokio::sync::Semaphore;
use tokio_stream::wrappers::ReceiverStream;
use tokio_stream::{Stream, StreamExt};
use tonic::Status;

/// The size of the chunks a file is sent in: small, so that a stream whose reader does not read
/// holds little (the protocol's chunks of 1 MiB are the largest a message may carry).
pub const DOWNLOAD_CHUNK_BYTES: usize = 64 << 10;

/// The limits, as the coordinator's flags set them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CallerLimits {
    pub connections: ConnectionLimits,
    pub max_streams_per_connection: u32,
    pub max_downloads: usize,
}

impl Default for CallerLimits {
    fn default() -> Self {
        CallerLimits {
            connections: ConnectionLimits::default(),
            max_streams_per_connection: 64,
            max_downloads: 32,
        }
    }
}

impl CallerLimits {
    /// How long a caller may stay silent: a connection, a download's reader, an upload.
    pub fn idle(&self) -> Duration {
        self.connections.idle_timeout
    }
}

/// The files being sent, and the room for more.
pub struct Downloads {
    permits: Arc<Semaphore>,
    limits: CallerLimits,
}

/// A file's stream of chunks, as the gRPC services return it.
pub type ChunkStream = Pin<Box<dyn Stream<Item = Result<pb::Chunk, Status>> + Send>>;

impl Downloads {
    pub fn new(limits: CallerLimits) -> Self {
        Downloads { permits: Arc::new(Semaphore::new(limits.max_downloads.max(1))), limits }
    }

    /// Downloads in progress.
    pub fn in_progress(&self) -> usize {
        self.limits.max_downloads.max(1) - self.permits.available_permits()
    }

    /// `path` sent as `name` in chunks read as the reader takes them, `on_bytes` told of each;
    /// refused when `--max-downloads` files are being sent already.
    pub fn send(
        &self,
        name: String,
        path: PathBuf,
        on_bytes: impl Fn(u64) + Send + 'static,
    ) -> Result<ChunkStream> {
        let max = self.limits.max_downloads.max(1);
        let permit = self.permits.clone().try_acquire_owned().map_err(|_| FarmError::Limit {
            what: "files being sent at once".into(),
            value: max as u64,
            limit: max as u64,
            flag: "--max-downloads",
            fix: "try again in a moment",
        })?;
        let idle = self.limits.idle();
        // One chunk waits in the channel; the reading task reads the next only when it is
        // taken, so nothing is read ahead of the reader.
        let (tx, rx) = tokio::sync::mpsc::channel::<Result<pb::Chunk, Status>>(1);
        let cut = Arc::new(std::sync::Mutex::new(None));
        let stream = Download { rx: ReceiverStream::new(rx), cut: cut.clone(), ended: false };
        tokio::spawn(async move {
            let _permit = permit;
            let sender = Sender { tx, idle, name: name.clone() };
            if let Err(Some(status)) = read_into(&name, &path, on_bytes, &sender).await {
                // The reader stopped reading: if it ever reads again, the stream ends with why,
                // not as a whole file.
                *cut.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(status);
            }
        });
        Ok(Box::pin(stream))
    }
}

/// A file's chunks as they come, then, if the sending was cut, the reason.
struct Download {
    rx: ReceiverStream<Result<pb::Chunk, Status>>,
    cut: Arc<std::sync::Mutex<Option<Status>>>,
    ended: bool,
}

impl Stream for Download {
    type Item = Result<pb::Chunk, Status>;

    fn poll_next(
        mut self: Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<Option<Self::Item>> {
        use std::task::Poll;
        match Pin::new(&mut self.rx).poll_next(cx) {
            Poll::Ready(None) if !self.ended => {
                self.ended = true;
                let cut = self.cut.lock().unwrap_or_else(std::sync::PoisonError::into_inner).take();
                Poll::Ready(cut.map(Err))
            }
            other => other,
        }
    }
}

/// Where a download's chunks go: the stream's channel, waited on for at most `idle`.
struct Sender {
    tx: tokio::sync::mpsc::Sender<Result<pb::Chunk, Status>>,
    idle: Duration,
    name: String,
}

impl Sender {
    /// `Err(None)`: the reader has gone; `Err(Some(why))`: it took nothing for `idle`.
    async fn send(&self, chunk: Result<pb::Chunk, Status>) -> Result<(), Option<Status>> {
        match tokio::time::timeout(self.idle, self.tx.send(chunk)).await {
            Ok(Ok(())) => Ok(()),
            Ok(Err(_)) => Err(None),
            Err(_) => Err(Some(
                FarmError::Stalled {
                    what: format!("the download of {}", self.name),
                    seconds: self.idle.as_secs(),
                    flag: "--idle-timeout-s",
                    fix: "read the stream as it comes",
                }
                .into(),
            )),
        }
    }
}

/// Reads `path` and hands each chunk to `sender` (the first named `name`, every one with the
/// file's size; `on_bytes` told of each), an error chunk if the file cannot be read. Stops at
/// the first chunk not taken.
async fn read_into(
    name: &str,
    path: &std::path::Path,
    on_bytes: impl Fn(u64),
    sender: &Sender,
) -> Result<(), Option<Status>> {
    let io_error = |e| Err::<pb::Chunk, Status>(FarmError::io(path, e).into());
    let mut file = match tokio::fs::File::open(path).await {
        Ok(f) => f,
        Err(e) => return sender.send(io_error(e)).await,
    };
    let total = file.metadata().await.map_or(0, |m| m.len());
    let mut first = true;
    loop {
        let mut data = vec![0u8; DOWNLOAD_CHUNK_BYTES];
        let n = match file.read(&mut data).await {
            Ok(n) => n,
            Err(e) => return sender.send(io_error(e)).await,
        };
        if n == 0 && !first {
            return Ok(());
        }
        data.truncate(n);
        on_bytes(n as u64);
        let name = if first { name.to_owned() } else { String::new() };
        first = false;
        sender.send(Ok(pb::Chunk { name, total_bytes: total, data })).await?;
        if n == 0 {
            return Ok(());
        }
    }
}

/// The next message of an upload, or a refusal once none has come for `idle`.
pub async fn next_within<T>(
    stream: &mut tonic::Streaming<T>,
    idle: Duration,
    what: impl FnOnce() -> String,
) -> Result<Option<T>, Status> {
    match tokio::time::timeout(idle, stream.next()).await {
        Ok(None) => Ok(None),
        Ok(Some(message)) => message.map(Some),
        Err(_) => Err(FarmError::Stalled {
            what: what(),
            seconds: idle.as_secs(),
            flag: "--idle-timeout-s",
            fix: "send the upload's data as it is read; its share of the upload budget is given \
                  back",
        }
        .into()),
    }
}
