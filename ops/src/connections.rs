//! What a connection may hold of a server: how many may be open at once, how soon one must say
//! something, and how long it may stay silent.
//!
//! Every listener of restauro's processes (the coordinator's gRPC port, the studio, the metrics
//! endpoints) accepts through a [`GuardedListener`]:
//!
//! * **A connection limit.** Beyond `max_connections` open at once, a new connection is closed
//!   as soon as it is accepted (and counted), so that the kernel's queue does not fill with
//!   connections nobody will serve.
//! * **A first-bytes deadline.** A connection must send its first bytes — the start of a request
//!   line, or HTTP/2's 24-byte preface — within `first_bytes_timeout`: a client that connects and
//!   says nothing (a slow loris's first move) is closed then, before any protocol state is kept
//!   for it.
//! * **An idle timeout.** A connection on which nothing is read or written for `idle_timeout` is
//!   closed — unless the server is at work on one of its requests ([`Busy`]: a studio snapshot
//!   waiting for its scene to load is silent, and not idle). An honest connection is never
//!   that quiet otherwise: gRPC clients answer the server's HTTP/2 pings, the studio's event
//!   stream sends a comment every 15 s, and a request in progress moves bytes.
//!
//! What a connection holds once it talks (streams, downloads, uploads) is bounded by the server
//! above this layer.

use std::io;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tokio::time::{Instant, Sleep};
use tracing::warn;

/// The limits of one listener.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConnectionLimits {
    pub max_connections: usize,
    /// The bytes a connection must send within `first_bytes_timeout`.
    pub first_bytes: usize,
    pub first_bytes_timeout: Duration,
    pub idle_timeout: Duration,
}

impl Default for ConnectionLimits {
    /// 512 connections; 16 bytes within 10 s; 120 s of silence.
    fn default() -> Self {
        ConnectionLimits {
            max_connections: 512,
            first_bytes: 16,
            first_bytes_timeout: Duration::from_secs(10),
            idle_timeout: Duration::from_secs(120),
        }
    }
}

/// A TCP listener that accepts within [`ConnectionLimits`].
pub struct GuardedListener {
    inner: TcpListener,
    limits: ConnectionLimits,
    open: Arc<Semaphore>,
    refused: Arc<AtomicU64>,
}

impl GuardedListener {
    pub fn new(inner: TcpListener, limits: ConnectionLimits) -> Self {
        let open = Arc::new(Semaphore::new(limits.max_connections.max(1)));
        GuardedListener { inner, limits, open, refused: Arc::new(AtomicU64::new(0)) }
    }

    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.inner.local_addr()
    }

    /// The connections closed at once because `max_connections` were open.
    pub fn refused(&self) -> Arc<AtomicU64> {
        self.refused.clone()
    }

    /// The next connection within the limit; those beyond it are closed as they come. Errors of
    /// `accept` itself (too many open files) are logged and retried after a pause.
    pub async fn accept(&self) -> (GuardedStream, SocketAddr) {
        loop {
            let (tcp, peer) = match self.inner.accept().await {
                Ok(accepted) => accepted,
                Err(e) => {
                    warn!(error = %e, "accepting a connection");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            };
            let Ok(permit) = self.open.clone().try_acquire_owned() else {
                // Dropped: closed at once.
                if self.refused.fetch_add(1, Ordering::Relaxed).is_multiple_of(100) {
                    warn!(
                        %peer,
                        max = self.limits.max_connections,
                        "refused a connection: the limit of open connections is reached \
                         (--max-connections)"
                    );
                }
                continue;
            };
            let _ = tcp.set_nodelay(true);
            return (GuardedStream::new(tcp, permit, self.limits), peer);
        }
    }
}

impl axum::serve::Listener for GuardedListener {
    type Io = GuardedStream;
    type Addr = SocketAddr;

    async fn accept(&mut self) -> (Self::Io, Self::Addr) {
        GuardedListener::accept(self).await
    }

    fn local_addr(&self) -> io::Result<Self::Addr> {
        GuardedListener::local_addr(self)
    }
}

/// An accepted connection, holding its place among the open ones until it is dropped.
pub struct GuardedStream {
    inner: TcpStream,
    _permit: OwnedSemaphorePermit,
    /// Bytes still to come before the first-bytes deadline is met.
    first_bytes_due: usize,
    first_bytes_by: Instant,
    idle_timeout: Duration,
    /// Fires at the first-bytes deadline, then at each idle deadline.
    timer: Pin<Box<Sleep>>,
    busy: Busy,
}

/// The requests of one connection the server is at work on: while there is one, the connection's
/// silence is the server's, and the idle timeout waits.
#[derive(Clone, Debug, Default)]
pub struct Busy(Arc<AtomicUsize>);

impl Busy {
    /// Marks a request in progress until the guard is dropped.
    pub fn working(&self) -> Working {
        self.0.fetch_add(1, Ordering::Relaxed);
        Working(self.0.clone())
    }

    fn is_busy(&self) -> bool {
        self.0.load(Ordering::Relaxed) > 0
    }
}

/// A request in progress on its connection (see [`Busy::working`]).
pub struct Working(Arc<AtomicUsize>);

impl Drop for Working {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::Relaxed);
    }
}

impl GuardedStream {
    fn new(inner: TcpStream, permit: OwnedSemaphorePermit, limits: ConnectionLimits) -> Self {
        let first_bytes_by = Instant::now() + limits.first_bytes_timeout;
        GuardedStream {
            inner,
            _permit: permit,
            first_bytes_due: limits.first_bytes,
            first_bytes_by,
            idle_timeout: limits.idle_timeout,
            timer: Box::pin(tokio::time::sleep_until(
                first_bytes_by.min(Instant::now() + limits.idle_timeout),
            )),
            busy: Busy::default(),
        }
    }

    /// The handle through which the server says it is at work on one of this connection's
    /// requests.
    pub fn busy(&self) -> Busy {
        self.busy.clone()
    }

    /// The underlying socket (its peer address, for a server that wants it).
    pub fn tcp(&self) -> &TcpStream {
        &self.inner
    }

    /// Bytes moved: the idle deadline starts again.
    fn moved(&mut self, read: usize) {
        self.first_bytes_due = self.first_bytes_due.saturating_sub(read);
        let mut next = Instant::now() + self.idle_timeout;
        if self.first_bytes_due > 0 {
            next = next.min(self.first_bytes_by);
        }
        self.timer.as_mut().reset(next);
    }

    /// An error once a deadline has passed; registers the waker for it otherwise.
    fn check(&mut self, cx: &mut Context<'_>) -> io::Result<()> {
        while self.timer.as_mut().poll(cx).is_ready() {
            if self.first_bytes_due == 0 && self.busy.is_busy() {
                // The server's silence, not the client's: look again an idle period later.
                let next = Instant::now() + self.idle_timeout;
                self.timer.as_mut().reset(next);
                continue;
            }
            let why = if self.first_bytes_due > 0 {
                "the connection sent no request in time"
            } else {
                "the connection was silent for too long"
            };
            return Err(io::Error::new(io::ErrorKind::TimedOut, why));
        }
        Ok(())
    }
}

impl AsyncRead for GuardedStream {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let before = buf.filled().len();
        match Pin::new(&mut self.inner).poll_read(cx, buf) {
            Poll::Ready(Ok(())) => {
                let read = buf.filled().len() - before;
                self.moved(read);
                Poll::Ready(Ok(()))
            }
            Poll::Ready(Err(e)) => Poll::Ready(Err(e)),
            Poll::Pending => {
                self.check(cx)?;
                Poll::Pending
            }
        }
    }
}

impl AsyncWrite for GuardedStream {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        data: &[u8],
    ) -> Poll<io::Result<usize>> {
        match Pin::new(&mut self.inner).poll_write(cx, data) {
            Poll::Ready(Ok(n)) => {
                // Writing is no answer to the first-bytes deadline: only reading moves it.
                if self.first_bytes_due == 0 {
                    self.moved(0);
                }
                Poll::Ready(Ok(n))
            }
            Poll::Pending => {
                self.check(cx)?;
                Poll::Pending
            }
            ready => ready,
        }
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_shutdown(cx)
    }
}

/// Accepted connections as a stream, for servers that take one (tonic's
/// `serve_with_incoming`), each wrapped by `wrap`.
pub fn incoming<T: Send + 'static>(
    listener: GuardedListener,
    wrap: impl Fn(GuardedStream) -> T + Send + 'static,
) -> impl tokio_stream::Stream<Item = io::Result<T>> {
    let (tx, rx) = tokio::sync::mpsc::channel(16);
    tokio::spawn(async move {
        loop {
            let (stream, _) = listener.accept().await;
            if tx.send(Ok(wrap(stream))).await.is_err() {
                return;
            }
        }
    });
    tokio_stream::wrappers::ReceiverStream::new(rx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    async fn listener(limits: ConnectionLimits) -> (GuardedListener, SocketAddr) {
        let tcp = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = tcp.local_addr().unwrap();
        (GuardedListener::new(tcp, limits), addr)
    }

    fn limits(max: usize, first_ms: u64, idle_ms: u64) -> ConnectionLimits {
        ConnectionLimits {
            max_connections: max,
            first_bytes: 4,
            first_bytes_timeout: Duration::from_millis(first_ms),
            idle_timeout: Duration::from_millis(idle_ms),
        }
    }

    /// A connection that says nothing is closed at the first-bytes deadline; one that speaks
    /// is served, and closed once silent for the idle timeout.
    #[tokio::test]
    async fn silence_is_closed_and_speech_is_served() {
        let (guarded, addr) = listener(limits(8, 200, 600)).await;
        let server = tokio::spawn(async move {
            let mut outcomes = Vec::new();
            for _ in 0..2 {
                let (mut s, _) = guarded.accept().await;
                let mut buf = [0u8; 16];
                let started = Instant::now();
                let mut got = 0;
                let end = loop {
                    match s.read(&mut buf).await {
                        Ok(0) => break "eof",
                        Ok(n) => got += n,
                        Err(e) if e.kind() == io::ErrorKind::TimedOut => break "timed out",
                        Err(_) => break "error",
                    }
                };
                outcomes.push((end, got, started.elapsed()));
            }
            outcomes
        });
        let _silent = TcpStream::connect(addr).await.unwrap();
        let mut talker = TcpStream::connect(addr).await.unwrap();
        talker.write_all(b"GET / HTTP/1.1\r\n").await.unwrap();
        let outcomes = server.await.unwrap();
        let (end, got, after) = outcomes[0];
        assert_eq!((end, got), ("timed out", 0));
        assert!(
            after >= Duration::from_millis(190) && after < Duration::from_millis(550),
            "{after:?}"
        );
        let (end, got, after) = outcomes[1];
        assert_eq!((end, got), ("timed out", 16));
        assert!(after >= Duration::from_millis(590), "{after:?}");
    }

    /// A connection whose request the server is at work on is not cut for its silence (the
    /// silence is the server's); once the work is done, the idle timeout runs again.
    #[tokio::test]
    async fn a_connection_waiting_for_its_answer_is_not_idle() {
        let (guarded, addr) = listener(limits(8, 5_000, 300)).await;
        let server = tokio::spawn(async move {
            let (mut s, _) = guarded.accept().await;
            let mut buf = [0u8; 16];
            assert_eq!(s.read(&mut buf).await.unwrap(), 16);
            let working = s.busy().working();
            // Three idle periods at work, polling the connection as a server does meanwhile.
            let read = tokio::time::timeout(Duration::from_millis(900), s.read(&mut buf)).await;
            assert!(read.is_err(), "the connection was cut while its answer was being made");
            drop(working);
            s.write_all(b"answer").await.unwrap();
            let started = Instant::now();
            let end = s.read(&mut buf).await;
            (end.map_err(|e| e.kind()), started.elapsed())
        });
        let mut client = TcpStream::connect(addr).await.unwrap();
        client.write_all(b"GET / HTTP/1.1\r\n").await.unwrap();
        let (end, after) = server.await.unwrap();
        assert_eq!(end, Err(io::ErrorKind::TimedOut));
        assert!(
            after >= Duration::from_millis(290) && after < Duration::from_millis(800),
            "{after:?}"
        );
    }

    /// Beyond the limit, connections are closed as they come; a closed one frees its place.
    #[tokio::test]
    async fn beyond_the_limit_connections_are_closed() {
        let (guarded, addr) = listener(limits(2, 5_000, 5_000)).await;
        let refused = guarded.refused();
        let (tx, mut rx) = tokio::sync::mpsc::channel(8);
        tokio::spawn(async move {
            loop {
                let accepted = guarded.accept().await;
                if tx.send(accepted).await.is_err() {
                    return;
                }
            }
        });
        let mut a = TcpStream::connect(addr).await.unwrap();
        let _b = TcpStream::connect(addr).await.unwrap();
        let (first, _) = rx.recv().await.unwrap();
        let (_second, _) = rx.recv().await.unwrap();
        let mut c = TcpStream::connect(addr).await.unwrap();
        let mut buf = [0u8; 1];
        // The third is closed by the server: end of file (or a reset).
        let read = tokio::time::timeout(Duration::from_secs(5), c.read(&mut buf)).await.unwrap();
        assert!(matches!(read, Ok(0) | Err(_)), "{read:?}");
        assert_eq!(refused.load(Ordering::Relaxed), 1);
        drop(first);
        a.write_all(b"x").await.ok();
        let _d = TcpStream::connect(addr).await.unwrap();
        let accepted = tokio::time::timeout(Duration::from_secs(5), rx.recv()).await;
        assert!(accepted.is_ok(), "a freed place takes a new connection");
    }
}
