//! A hand-written HTTP/2 client of restauro's gRPC services, for callers no tonic client would
//! be: one that asks for a file and never reads it (its flow-control window never opened), one
//! that announces an upload and then sends nothing.

use bytes::{BufMut, Bytes, BytesMut};
use h2::client::SendRequest;
use restauro_proto::PROTOCOL_HEADER;

/// One HTTP/2 connection to a coordinator.
pub struct Raw {
    send: SendRequest<Bytes>,
    authority: String,
}

/// The head of a call's response.
pub enum Head {
    /// The call goes on: its body stream, never read unless the test reads it.
    Streaming(h2::RecvStream),
    /// Refused at once (gRPC's "Trailers-Only" response): the status code and message.
    Refused(i32, String),
}

/// A gRPC message as it travels: not compressed, its length, its bytes.
pub fn frame(message: &impl prost::Message) -> Bytes {
    let body = message.encode_to_vec();
    let mut out = BytesMut::with_capacity(5 + body.len());
    out.put_u8(0);
    out.put_u32(u32::try_from(body.len()).expect("a test's message is small"));
    out.put_slice(&body);
    out.freeze()
}

impl Raw {
    /// Connects to `url` (`http://HOST:PORT`) with HTTP/2's default windows (64 KiB).
    pub async fn connect(url: &str) -> Raw {
        let authority = url.trim_start_matches("http://").to_owned();
        let tcp = tokio::net::TcpStream::connect(&authority).await.unwrap();
        let (send, connection) = h2::client::handshake(tcp).await.unwrap();
        tokio::spawn(async move {
            let _ = connection.await;
        });
        Raw { send, authority }
    }

    /// Starts a call of `path` (`/restauro.v1.Work/FetchAsset`) with `token`, sending `message`
    /// and, if `end`, ending the request there. Returns the response's head (its body is left
    /// unread) and the request's stream, for more messages.
    pub async fn call(
        &mut self,
        path: &str,
        token: &str,
        message: &impl prost::Message,
        end: bool,
    ) -> Result<(Head, h2::SendStream<Bytes>), h2::Error> {
        let request = http::Request::post(format!("http://{}{path}", self.authority))
            .header("content-type", "application/grpc")
            .header("te", "trailers")
            .header("authorization", format!("Bearer {token}"))
            .header(PROTOCOL_HEADER, restauro_proto::PROTOCOL_VERSION.to_string())
            .body(())
            .unwrap();
        let send = std::future::poll_fn(|cx| self.send.poll_ready(cx));
        send.await?;
        let (response, mut stream) = self.send.send_request(request, false)?;
        stream.send_data(frame(message), end)?;
        let (head, body) = response.await?.into_parts();
        let status = head.headers.get("grpc-status").and_then(|v| v.to_str().ok()?.parse().ok());
        let head = match status {
            Some(code) => {
                let message = head
                    .headers
                    .get("grpc-message")
                    .and_then(|v| v.to_str().ok())
                    .map(percent_decode)
                    .unwrap_or_default();
                Head::Refused(code, message)
            }
            None => Head::Streaming(body),
        };
        Ok((head, stream))
    }
}

/// The whole body of a response, read as a good reader reads it (opening the window as it
/// goes), and the gRPC status of its trailers.
pub async fn read_to_end(mut body: h2::RecvStream) -> (usize, Option<(i32, String)>) {
    let mut bytes = 0;
    while let Some(data) = body.data().await {
        let Ok(data) = data else { break };
        bytes += data.len();
        let _ = body.flow_control().release_capacity(data.len());
    }
    let status = match body.trailers().await {
        Ok(Some(t)) => t.get("grpc-status").and_then(|v| v.to_str().ok()?.parse().ok()).map(|c| {
            let m = t.get("grpc-message").and_then(|v| v.to_str().ok()).map(percent_decode);
            (c, m.unwrap_or_default())
        }),
        _ => None,
    };
    (bytes, status)
}

/// gRPC's percent-encoding of its messages, undone.
fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && let Some(v) = text.get(i + 1..i + 3).and_then(|h| u8::from_str_radix(h, 16).ok())
        {
            out.push(v);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The resident memory of process `pid` (kB, from /proc), and its peak.
pub fn memory_kb(pid: u32) -> (u64, u64) {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.split_whitespace().next()?.parse().ok())
            .unwrap_or(0)
    };
    (field("VmRSS:"), field("VmHWM:"))
}
