//! The object store's HTTP client: one HTTP/1.1 connection a request, over plain TCP or TLS
//! (rustls with ring and the system's certificate authorities), on the hyper and rustls the
//! farm already builds — no second HTTP stack. A coordinator puts and fetches a file at a
//! time, so a connection a request costs nothing that matters.

use http_body_util::BodyExt as _;
use hyper_util::rt::TokioIo;
use object_store::client::{
    HttpClient, HttpConnector, HttpError, HttpErrorKind, HttpRequest, HttpResponse,
    HttpResponseBody, HttpService,
};
use std::sync::{Arc, OnceLock};

/// Makes the object store's [`HttpClient`].
#[derive(Debug)]
pub struct Connector;

impl HttpConnector for Connector {
    fn connect(&self, _: &object_store::ClientOptions) -> object_store::Result<HttpClient> {
        Ok(HttpClient::new(Service))
    }
}

#[derive(Debug)]
struct Service;

fn failed(kind: HttpErrorKind, e: impl std::error::Error + Send + Sync + 'static) -> HttpError {
    HttpError::new(kind, e)
}

fn refused(message: String) -> HttpError {
    failed(HttpErrorKind::Request, std::io::Error::other(message))
}

/// The TLS client configuration: the system's authorities, ring.
fn tls() -> Arc<rustls::ClientConfig> {
    static CONFIG: OnceLock<Arc<rustls::ClientConfig>> = OnceLock::new();
    CONFIG
        .get_or_init(|| {
            let mut roots = rustls::RootCertStore::empty();
            for cert in rustls_native_certs::load_native_certs().certs {
                let _ = roots.add(cert);
            }
            let provider = Arc::new(rustls::crypto::ring::default_provider());
            let config = rustls::ClientConfig::builder_with_provider(provider)
                .with_safe_default_protocol_versions()
                .expect("ring supports the default versions")
                .with_root_certificates(roots)
                .with_no_client_auth();
            Arc::new(config)
        })
        .clone()
}

/// How long a connection may take to open, and a request to be answered (its body sent, the
/// answer's head received): a server that takes a connection and never answers must not hold
/// an upload, or an assembly, for ever. A timeout is retried as object_store retries any.
const CONNECT_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(10);
const ANSWER_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(120);

#[async_trait::async_trait]
impl HttpService for Service {
    async fn call(&self, request: HttpRequest) -> Result<HttpResponse, HttpError> {
        tokio::time::timeout(ANSWER_TIMEOUT, self.answer(request)).await.map_err(|_| {
            let limit = ANSWER_TIMEOUT.as_secs();
            let e = std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                format!("the object store did not answer within {limit} s"),
            );
            failed(HttpErrorKind::Timeout, e)
        })?
    }
}

impl Service {
    async fn answer(&self, request: HttpRequest) -> Result<HttpResponse, HttpError> {
        let uri = request.uri().clone();
        let host = uri.host().ok_or_else(|| refused(format!("no host in {uri}")))?.to_owned();
        let secure = uri.scheme_str() == Some("https");
        let port = uri.port_u16().unwrap_or(if secure { 443 } else { 80 });
        let connect = tokio::net::TcpStream::connect((host.trim_matches(['[', ']']), port));
        let tcp = tokio::time::timeout(CONNECT_TIMEOUT, connect)
            .await
            .map_err(|_| {
                let e = std::io::Error::new(
                    std::io::ErrorKind::TimedOut,
                    format!(
                        "{host}:{port} did not take a connection within {} s",
                        CONNECT_TIMEOUT.as_secs()
                    ),
                );
                failed(HttpErrorKind::Connect, e)
            })?
            .map_err(|e| failed(HttpErrorKind::Connect, e))?;
        let _ = tcp.set_nodelay(true);
        let response = if secure {
            let name = rustls::pki_types::ServerName::try_from(host.clone())
                .map_err(|e| refused(format!("`{host}` is not a host name ({e})")))?;
            let stream = tokio_rustls::TlsConnector::from(tls())
                .connect(name, tcp)
                .await
                .map_err(|e| failed(HttpErrorKind::Connect, e))?;
            send(TokioIo::new(stream), request).await?
        } else {
            send(TokioIo::new(tcp), request).await?
        };
        let (parts, body) = response.into_parts();
        let body = body.map_err(|e| failed(HttpErrorKind::Decode, e));
        Ok(HttpResponse::from_parts(parts, HttpResponseBody::new(body)))
    }
}

async fn send<T>(
    io: T,
    request: HttpRequest,
) -> Result<hyper::Response<hyper::body::Incoming>, HttpError>
where
    T: hyper::rt::Read + hyper::rt::Write + Unpin + Send + 'static,
{
    let (mut sender, connection) = hyper::client::conn::http1::handshake::<_, _>(io)
        .await
        .map_err(|e| failed(HttpErrorKind::Connect, e))?;
    tokio::spawn(connection);
    // The path and query only, as HTTP/1.1 asks; the host in its header.
    let (mut parts, body) = request.into_parts();
    if !parts.headers.contains_key(hyper::header::HOST)
        && let Some(authority) = parts.uri.authority()
    {
        let value = hyper::header::HeaderValue::from_str(authority.as_str())
            .map_err(|e| failed(HttpErrorKind::Request, e))?;
        parts.headers.insert(hyper::header::HOST, value);
    }
    if let Some(path) = parts.uri.path_and_query() {
        parts.uri = path.as_str().parse().map_err(|e| failed(HttpErrorKind::Request, e))?;
    }
    sender
        .send_request(hyper::Request::from_parts(parts, body))
        .await
        .map_err(|e| failed(HttpErrorKind::Request, e))
}
