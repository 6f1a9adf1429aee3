//! A plain HTTP/1.1 client for the tests of the studio's API: one request per connection, and
//! a reader of Server-Sent Events. Hand-written, as the other wire helpers here are, so that a
//! test sees exactly the bytes the server sends.

use std::io::{self, BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

#[derive(Debug)]
pub struct Response {
    pub status: u16,
    /// Names in lower case.
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

impl Response {
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }

    pub fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.text()))
    }
}

/// How long a request waits for the server's next bytes, unless told otherwise.
const PATIENCE: Duration = Duration::from_secs(30);

fn send(
    addr: &str,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
    patience: Duration,
) -> io::Result<TcpStream> {
    let mut stream = TcpStream::connect(addr)?;
    stream.set_read_timeout(Some(patience))?;
    write_request(&mut stream, addr, method, path, headers, body)?;
    Ok(stream)
}

fn write_request(
    stream: &mut impl Write,
    addr: &str,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> io::Result<()> {
    let mut head = format!("{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n");
    for (k, v) in headers {
        head += &format!("{k}: {v}\r\n");
    }
    head += &format!("Content-Length: {}\r\n\r\n", body.len());
    stream.write_all(head.as_bytes())?;
    stream.write_all(body)
}

fn read_head(reader: &mut impl BufRead) -> io::Result<(u16, Vec<(String, String)>)> {
    let mut line = String::new();
    if reader.read_line(&mut line)? == 0 {
        return Err(io::Error::new(io::ErrorKind::UnexpectedEof, "closed before an answer"));
    }
    let status = line.split(' ').nth(1).and_then(|s| s.parse().ok()).unwrap_or(0);
    let mut headers = Vec::new();
    loop {
        let mut line = String::new();
        if reader.read_line(&mut line)? == 0 {
            return Err(io::Error::new(io::ErrorKind::UnexpectedEof, "closed within the head"));
        }
        let line = line.trim_end();
        if line.is_empty() {
            return Ok((status, headers));
        }
        if let Some((k, v)) = line.split_once(':') {
            headers.push((k.trim().to_ascii_lowercase(), v.trim().to_owned()));
        }
    }
}

/// One chunk of a `Transfer-Encoding: chunked` body; empty at its end.
fn read_chunk(reader: &mut impl BufRead) -> io::Result<Vec<u8>> {
    let mut size = String::new();
    reader.read_line(&mut size)?;
    let size = usize::from_str_radix(size.trim().split(';').next().unwrap_or(""), 16).unwrap_or(0);
    let mut data = vec![0u8; size + 2];
    reader.read_exact(&mut data)?;
    data.truncate(size);
    Ok(data)
}

/// `method path` with `headers` and `body`; the whole answer.
pub fn request(
    addr: &str,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> Response {
    try_request(addr, method, path, headers, body)
        .unwrap_or_else(|e| panic!("{method} {path} on {addr}: {e}"))
}

/// As [`request`], with what went wrong on the way instead of a panic.
pub fn try_request(
    addr: &str,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> io::Result<Response> {
    try_request_within(addr, method, path, headers, body, PATIENCE)
}

/// As [`try_request`], waiting up to `patience` for each of the server's bytes.
pub fn try_request_within(
    addr: &str,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
    patience: Duration,
) -> io::Result<Response> {
    read_response(BufReader::new(send(addr, method, path, headers, body, patience)?))
}

/// As [`request`], over TLS to `host:port` (`addr`), trusting only the authority in the PEM
/// file `ca` (and checking the certificate names `host`).
pub fn request_tls(
    addr: &str,
    ca: &std::path::Path,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> Response {
    use rustls::pki_types::pem::PemObject;
    use rustls::pki_types::{CertificateDer, ServerName};
    let mut roots = rustls::RootCertStore::empty();
    for cert in CertificateDer::pem_file_iter(ca).unwrap() {
        roots.add(cert.unwrap()).unwrap();
    }
    let provider = std::sync::Arc::new(rustls::crypto::ring::default_provider());
    let config = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .unwrap()
        .with_root_certificates(roots)
        .with_no_client_auth();
    let host = addr.rsplit_once(':').unwrap().0.to_owned();
    let name = ServerName::try_from(host).unwrap();
    let connection = rustls::ClientConnection::new(std::sync::Arc::new(config), name).unwrap();
    let tcp = TcpStream::connect(addr).unwrap();
    tcp.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let mut stream = rustls::StreamOwned::new(connection, tcp);
    write_request(&mut stream, addr, method, path, headers, body).unwrap();
    read_response(BufReader::new(stream)).unwrap()
}

fn read_response(mut reader: BufReader<impl Read>) -> io::Result<Response> {
    let (status, headers) = read_head(&mut reader)?;
    let chunked = headers.iter().any(|(k, v)| k == "transfer-encoding" && v.contains("chunked"));
    let mut body = Vec::new();
    if chunked {
        loop {
            let chunk = read_chunk(&mut reader)?;
            if chunk.is_empty() {
                break;
            }
            body.extend(chunk);
        }
    } else {
        reader.read_to_end(&mut body)?;
    }
    Ok(Response { status, headers, body })
}

#[derive(Clone, Debug)]
pub struct Event {
    pub kind: String,
    pub id: String,
    pub data: String,
}

impl Event {
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_str(&self.data).unwrap()
    }
}

/// A stream of Server-Sent Events (WHATWG HTML §9.2.6: `event:`, `id:` and `data:` lines,
/// an empty line ending each event; `:` lines are comments, as keep-alives are).
pub struct Events {
    reader: BufReader<TcpStream>,
    pending: String,
    pub status: u16,
}

impl Events {
    pub fn open(addr: &str, path: &str, headers: &[(&str, &str)]) -> Events {
        Self::try_open(addr, path, headers).unwrap_or_else(|e| panic!("{path} on {addr}: {e}"))
    }

    /// As [`Events::open`], with what went wrong instead of a panic.
    pub fn try_open(addr: &str, path: &str, headers: &[(&str, &str)]) -> io::Result<Events> {
        let mut reader = BufReader::new(send(addr, "GET", path, headers, b"", PATIENCE)?);
        let (status, _) = read_head(&mut reader)?;
        Ok(Events { reader, pending: String::new(), status })
    }

    /// The next event; panics when the stream ends or after 30 s of silence.
    pub fn next_event(&mut self) -> Event {
        self.try_next_event().unwrap_or_else(|e| panic!("the event stream: {e}"))
    }

    /// The next event, or why there is none (the stream ended, 30 s of silence).
    pub fn try_next_event(&mut self) -> io::Result<Event> {
        loop {
            if let Some(end) = self.pending.find("\n\n") {
                let block: String = self.pending.drain(..end + 2).collect();
                let (mut kind, mut id, mut data) =
                    (String::from("message"), String::new(), Vec::new());
                for line in block.lines() {
                    if let Some(v) = line.strip_prefix("event:") {
                        kind = v.trim().to_owned();
                    } else if let Some(v) = line.strip_prefix("id:") {
                        id = v.trim().to_owned();
                    } else if let Some(v) = line.strip_prefix("data:") {
                        data.push(v.strip_prefix(' ').unwrap_or(v).to_owned());
                    }
                }
                if !data.is_empty() {
                    return Ok(Event { kind, id, data: data.join("\n") });
                }
                continue;
            }
            let chunk = read_chunk(&mut self.reader)?;
            if chunk.is_empty() {
                return Err(io::Error::new(io::ErrorKind::UnexpectedEof, "the event stream ended"));
            }
            self.pending += &String::from_utf8_lossy(&chunk);
        }
    }
}
