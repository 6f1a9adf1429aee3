//! One file fetched over HTTP/1.1 (RFC 9110, 9112) into a partial file: redirects followed
//! by hand (to http or https only, never from https down to http), a range request resuming
//! what an earlier attempt left (RFC 9110 §14), the body bounded, and every wait bounded by
//! one timeout: connecting, the answer's headers, and each stretch without data.

use super::WebUrl;
use bytes::Bytes;
use http_body_util::{BodyExt, Empty};
use hyper::StatusCode;
use hyper::header::{CONTENT_LENGTH, CONTENT_RANGE, HOST, LOCATION, RANGE, USER_AGENT};
use hyper_util::rt::TokioIo;
use std::io::Write;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::net::TcpStream;

/// The most redirects one download follows.
pub const MAX_REDIRECTS: usize = 10;
/// Attempts of one download that resume a body broken off.
const ATTEMPTS: usize = 4;
/// The longest one download may take, in timeouts (an hour at the default 30 s).
pub const DEADLINE_TIMEOUTS: u32 = 120;

/// What a download may take.
pub struct Bounds {
    pub max_bytes: u64,
    pub timeout: Duration,
    pub tls: Arc<rustls::ClientConfig>,
    /// The longest the whole download may take.
    pub deadline: Duration,
    /// Connect to public addresses only (see [`super::Policy`]).
    pub public_only: bool,
}

/// Why a download stopped, in words that name what to do.
#[derive(Debug)]
pub struct Failure {
    pub problem: String,
    /// The body broke off after some bytes came: another attempt resumes it.
    pub resumable: bool,
}

fn fail(problem: impl Into<String>) -> Failure {
    Failure { problem: problem.into(), resumable: false }
}

/// Fetches `url` into `file` (which may hold the start of the body from an earlier attempt),
/// resuming a broken-off body a few times.
pub fn download(url: &WebUrl, file: &mut std::fs::File, bounds: &Bounds) -> Result<(), Failure> {
    // The loader is synchronous and may itself run inside an async runtime (the coordinator's):
    // the download gets a thread and a runtime of its own.
    std::thread::scope(|scope| {
        scope
            .spawn(|| {
                let runtime = tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                    .map_err(|e| fail(format!("cannot start the download ({e})")))?;
                // However a server trickles its bytes, one download ends.
                let deadline = bounds.deadline;
                runtime.block_on(async {
                    tokio::time::timeout(deadline, attempts(url, file, bounds))
                        .await
                        .unwrap_or_else(|_| {
                            Err(fail(format!(
                                "the download took longer than {} s ({DEADLINE_TIMEOUTS} × \
                                 RESTAURO_DOWNLOAD_TIMEOUT_S); what came is kept, and the next \
                                 run resumes it",
                                deadline.as_secs_f64()
                            )))
                        })
                })
            })
            .join()
            .unwrap_or_else(|_| Err(fail("the download stopped unexpectedly")))
    })
}

async fn attempts(url: &WebUrl, file: &mut std::fs::File, bounds: &Bounds) -> Result<(), Failure> {
    let mut attempt = 1;
    loop {
        match fetch(url, file, bounds).await {
            Err(failure) if failure.resumable && attempt < ATTEMPTS => {
                attempt += 1;
                tracing::warn!(%url, attempt, "{}; resuming", failure.problem);
            }
            result => return result,
        }
    }
}

/// One attempt: follows redirects to the body and appends it to `file`.
async fn fetch(url: &WebUrl, file: &mut std::fs::File, bounds: &Bounds) -> Result<(), Failure> {
    let mut current = url.clone();
    for _ in 0..=MAX_REDIRECTS {
        let offset = file.metadata().map_err(|e| fail(format!("the cache: {e}")))?.len();
        let response = request(&current, offset, bounds).await?;
        let status = response.status();
        if status.is_redirection() && status != StatusCode::NOT_MODIFIED {
            current = redirect(&current, &response)?;
            continue;
        }
        let start = match status {
            StatusCode::OK => 0,
            StatusCode::PARTIAL_CONTENT => range_start(&response)?,
            StatusCode::RANGE_NOT_SATISFIABLE if offset > 0 => {
                // What is kept is not a start of this file: start again.
                truncate(file)?;
                continue;
            }
            _ => return Err(fail(format!("the server answered {status}; check the URL"))),
        };
        if start != offset {
            truncate(file)?;
            if start != 0 {
                return Err(fail(format!("the server resumed at byte {start}, not {offset}")));
            }
        }
        return receive(response, file, start, bounds, &current).await;
    }
    Err(fail(format!(
        "more than {MAX_REDIRECTS} redirects (a redirect loop?); give the URL the redirects end \
         at"
    )))
}

fn truncate(file: &std::fs::File) -> Result<(), Failure> {
    file.set_len(0).map_err(|e| fail(format!("the cache: {e}")))
}

/// The URL a redirect points to: http or https only, and never from https to http.
fn redirect(
    from: &WebUrl,
    response: &hyper::Response<hyper::body::Incoming>,
) -> Result<WebUrl, Failure> {
    let location =
        response.headers().get(LOCATION).and_then(|l| l.to_str().ok()).ok_or_else(|| {
            fail(format!("the server redirected ({}) without a Location", response.status()))
        })?;
    let to = from.join(location).map_err(|e| fail(format!("the server redirected to {e}")))?;
    if from.is_secure() && !to.is_secure() {
        return Err(fail(format!(
            "the server redirected from https to {to}; a file fetched over https is not \
             fetched in the clear"
        )));
    }
    tracing::debug!(%from, %to, "redirected");
    Ok(to)
}

/// Where a 206 answer's bytes start (`Content-Range: bytes 500-999/1000`).
fn range_start(response: &hyper::Response<hyper::body::Incoming>) -> Result<u64, Failure> {
    response
        .headers()
        .get(CONTENT_RANGE)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("bytes "))
        .and_then(|v| v.split('-').next())
        .and_then(|v| v.trim().parse().ok())
        .ok_or_else(|| fail("the server sent part of the file without saying which part"))
}

/// Sends the GET (asking for the bytes from `offset` on) and waits for the answer's headers.
async fn request(
    url: &WebUrl,
    offset: u64,
    bounds: &Bounds,
) -> Result<hyper::Response<hyper::body::Incoming>, Failure> {
    let seconds = bounds.timeout.as_secs_f64();
    let timed_out =
        |what: &str| fail(format!("{what} within {seconds} s (RESTAURO_DOWNLOAD_TIMEOUT_S)"));
    let tcp = tokio::time::timeout(bounds.timeout, connect(url, bounds.public_only))
        .await
        .map_err(|_| timed_out("could not connect"))??;
    let mut builder = hyper::Request::get(url.path_and_query())
        .header(HOST, url.authority())
        .header(USER_AGENT, concat!("restauro/", env!("CARGO_PKG_VERSION")));
    if offset > 0 {
        builder = builder.header(RANGE, format!("bytes={offset}-"));
    }
    let request = builder.body(Empty::<Bytes>::new()).map_err(|e| fail(e.to_string()))?;
    let answer = async {
        if url.is_secure() {
            let name = rustls::pki_types::ServerName::try_from(url.host().to_owned())
                .map_err(|e| fail(format!("`{}` is not a host name ({e})", url.host())))?;
            let tls = tokio_rustls::TlsConnector::from(bounds.tls.clone())
                .connect(name, tcp)
                .await
                .map_err(|e| fail(format!("the TLS handshake failed ({e}); {}", super::TLS_FIX)))?;
            send(TokioIo::new(tls), request).await
        } else {
            send(TokioIo::new(tcp), request).await
        }
    };
    tokio::time::timeout(bounds.timeout, answer)
        .await
        .map_err(|_| timed_out("the server sent no answer"))?
}

/// Connects to the first of the host's addresses that answers (only its public ones, when
/// `public_only`).
async fn connect(url: &WebUrl, public_only: bool) -> Result<TcpStream, Failure> {
    let (host, port) = (url.host(), url.port());
    let addresses: Vec<std::net::SocketAddr> = tokio::net::lookup_host((host, port))
        .await
        .map_err(|e| fail(format!("cannot find the host `{host}` ({e})")))?
        .collect();
    let mut problem = format!("the host `{host}` has no address");
    for address in addresses {
        if public_only && !is_public(address.ip()) {
            problem = format!(
                "`{host}` is at {}, not a public address: this coordinator fetches only from \
                 public servers (its operator may allow more with --fetch-private-urls); or \
                 fetch the files with the client, `restauro scene bundle --out`, and send the \
                 bundle",
                address.ip()
            );
            continue;
        }
        match TcpStream::connect(address).await {
            Ok(tcp) => return Ok(tcp),
            Err(e) => problem = format!("cannot connect to {address} ({e})"),
        }
    }
    Err(fail(problem))
}

/// Whether `ip` is an address of the public Internet: not loopback, private (RFC 1918, RFC
/// 4193), link-local, shared (RFC 6598), unspecified, broadcast, multicast or documentation.
pub fn is_public(ip: std::net::IpAddr) -> bool {
    use std::net::IpAddr;
    match ip {
        IpAddr::V4(v4) => {
            let [a, b, ..] = v4.octets();
            !(v4.is_loopback()
                || v4.is_private()
                || v4.is_link_local()
                || v4.is_unspecified()
                || v4.is_broadcast()
                || v4.is_multicast()
                || v4.is_documentation()
                || a == 0
                || (a == 100 && (64..128).contains(&b)))
        }
        IpAddr::V6(v6) => {
            if let Some(v4) = v6.to_ipv4_mapped() {
                return is_public(IpAddr::V4(v4));
            }
            let first = v6.segments()[0];
            !(v6.is_loopback()
                || v6.is_unspecified()
                || v6.is_multicast()
                || (first & 0xfe00) == 0xfc00
                || (first & 0xffc0) == 0xfe80
                || first == 0x2001 && v6.segments()[1] == 0x0db8)
        }
    }
}

async fn send<T>(
    io: T,
    request: hyper::Request<Empty<Bytes>>,
) -> Result<hyper::Response<hyper::body::Incoming>, Failure>
where
    T: hyper::rt::Read + hyper::rt::Write + Unpin + Send + 'static,
{
    let (mut sender, connection) = hyper::client::conn::http1::handshake(io)
        .await
        .map_err(|e| fail(format!("cannot speak HTTP with the server ({e})")))?;
    tokio::spawn(connection);
    sender.send_request(request).await.map_err(|e| fail(format!("the request failed ({e})")))
}

/// Appends the body to `file`, refusing more than `max_bytes` in all and any stretch of
/// `timeout` without data; logs progress every few seconds.
async fn receive(
    response: hyper::Response<hyper::body::Incoming>,
    file: &mut std::fs::File,
    start: u64,
    bounds: &Bounds,
    url: &WebUrl,
) -> Result<(), Failure> {
    let announced = response
        .headers()
        .get(CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok())
        .map(|length| start + length);
    let too_big = |size: u64| {
        fail(format!(
            "the file is {size} bytes, over the limit of {} bytes; {}",
            bounds.max_bytes,
            restauro_scene::assets::MAX_FILE_FIX
        ))
    };
    if let Some(total) = announced.filter(|&t| t > bounds.max_bytes) {
        return Err(too_big(total));
    }
    let mut body = response.into_body();
    let mut received = start;
    let mut last_report = Instant::now();
    loop {
        let frame = match tokio::time::timeout(bounds.timeout, body.frame()).await {
            Err(_) => {
                let mut f = fail(format!(
                    "no data for {} s after byte {received} (RESTAURO_DOWNLOAD_TIMEOUT_S)",
                    bounds.timeout.as_secs_f64()
                ));
                f.resumable = received > start;
                return Err(f);
            }
            Ok(None) => break,
            Ok(Some(Err(e))) => {
                return Err(Failure {
                    problem: format!("the body broke off after byte {received} ({e})"),
                    resumable: received > start || announced.is_some(),
                });
            }
            Ok(Some(Ok(frame))) => frame,
        };
        let Ok(data) = frame.into_data() else { continue };
        received += data.len() as u64;
        if received > bounds.max_bytes {
            return Err(too_big(received));
        }
        file.write_all(&data).map_err(|e| fail(format!("the cache: {e}")))?;
        if last_report.elapsed() > Duration::from_secs(2) {
            last_report = Instant::now();
            let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
            match announced {
                Some(total) => {
                    tracing::info!(%url, "downloading: {:.1} of {:.1} MiB", mib(received), mib(total))
                }
                None => tracing::info!(%url, "downloading: {:.1} MiB", mib(received)),
            }
        }
    }
    if let Some(total) = announced.filter(|&t| t != received) {
        return Err(Failure {
            problem: format!("the body ended at byte {received} of {total}"),
            resumable: true,
        });
    }
    file.flush().map_err(|e| fail(format!("the cache: {e}")))
}

#[cfg(test)]
mod tests {
    use super::is_public;

    /// The special-purpose ranges of the IANA registries (RFC 6890 and its successors).
    #[test]
    fn only_public_addresses_are_public() {
        for private in [
            "127.0.0.1",
            "10.1.2.3",
            "172.16.0.1",
            "192.168.1.1",
            "169.254.169.254",
            "100.64.0.1",
            "0.0.0.0",
            "255.255.255.255",
            "224.0.0.1",
            "192.0.2.1",
            "::1",
            "::",
            "fd00::1",
            "fe80::1",
            "ff02::1",
            "2001:db8::1",
            "::ffff:10.0.0.1",
        ] {
            assert!(!is_public(private.parse().unwrap()), "{private}");
        }
        for public in
            ["8.8.8.8", "93.184.216.34", "100.128.0.1", "2606:4700::1111", "::ffff:1.1.1.1"]
        {
            assert!(is_public(public.parse().unwrap()), "{public}");
        }
    }
}
