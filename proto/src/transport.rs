//! The dialling side of a connection to the coordinator, for clients and workers alike:
//! plaintext HTTP/2 for `http://` URLs, TLS (rustls) for `https://` ones, trusting the system's
//! certificate authorities and, when given, the authority in a PEM file (a site's own CA).
//!
//! Several coordinators (one leading, the others standing by on one PostgreSQL store) are given
//! as one list of URLs separated by commas: a [`Failover`] channel sends each call to the one
//! that answered last, and moves to the next when that one cannot be reached (a standby does
//! not listen; a leader that lost its lead stops). The caller's own retry of a failed call
//! (a worker registering again, a watch opened again) then reaches the new leader.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;
use tonic::body::Body;
use tonic::codegen::http;
use tonic::transport::{Certificate, Channel, ClientTlsConfig, Endpoint};

/// Why a connection to the coordinator cannot be set up: its URL, the CA certificate, or the
/// token sent with every call.
#[derive(Debug, thiserror::Error)]
pub enum DialError {
    #[error("coordinator URL `{url}`: {problem}")]
    Url { url: String, problem: String },
    #[error("the CA certificate {path}: {problem}")]
    Ca { path: String, problem: String },
    /// A bearer token that cannot travel in the `authorization` header ([`crate::Credentials`]).
    #[error("the token holds characters an HTTP header cannot carry")]
    Token,
}

/// An endpoint for `url`, ready to connect.
pub fn endpoint(url: &str, tls_ca: Option<&Path>) -> Result<Endpoint, DialError> {
    let bad = |problem: String| DialError::Url { url: url.to_owned(), problem };
    let tls = if url.starts_with("https://") {
        true
    } else if url.starts_with("http://") {
        if tls_ca.is_some() {
            return Err(bad("a CA certificate was given for a plaintext URL: use https://".into()));
        }
        false
    } else {
        return Err(bad("use http://HOST:PORT, or https://HOST:PORT for TLS".into()));
    };
    let mut endpoint = Endpoint::from_shared(url.to_owned())
        .map_err(|e| bad(e.to_string()))?
        .connect_timeout(Duration::from_secs(5))
        .tcp_nodelay(true);
    if tls {
        let mut config = ClientTlsConfig::new().with_native_roots();
        if let Some(path) = tls_ca {
            let ca_error =
                |problem: String| DialError::Ca { path: path.display().to_string(), problem };
            let pem = std::fs::read(path).map_err(|e| ca_error(e.to_string()))?;
            if !String::from_utf8_lossy(&pem).contains("-----BEGIN CERTIFICATE-----") {
                return Err(ca_error("not a PEM certificate (no BEGIN CERTIFICATE line)".into()));
            }
            config = config.ca_certificate(Certificate::from_pem(pem));
        }
        endpoint = endpoint.tls_config(config).map_err(|e| bad(e.to_string()))?;
    }
    Ok(endpoint)
}

/// The endpoints of a list of coordinator URLs separated by commas, each ready to connect.
pub fn endpoints(urls: &str, tls_ca: Option<&Path>) -> Result<Vec<(String, Endpoint)>, DialError> {
    let urls: Vec<&str> = urls.split(',').map(str::trim).filter(|u| !u.is_empty()).collect();
    if urls.is_empty() {
        return Err(DialError::Url { url: String::new(), problem: "no URL given".into() });
    }
    urls.into_iter().map(|url| Ok((url.to_owned(), endpoint(url, tls_ca)?))).collect()
}

/// Connects to the first of `endpoints` that answers (see [`Failover`]); the error of each
/// when none does.
pub async fn connect(
    endpoints: &[(String, Endpoint)],
) -> Result<Failover, (String, tonic::transport::Error)> {
    let mut first_error = None;
    for (index, (url, endpoint)) in endpoints.iter().enumerate() {
        match endpoint.connect().await {
            Ok(channel) => {
                let channels = endpoints
                    .iter()
                    .enumerate()
                    .map(|(i, (u, e))| {
                        (u.clone(), if i == index { channel.clone() } else { e.connect_lazy() })
                    })
                    .collect();
                return Ok(Failover { channels, current: Arc::new(AtomicUsize::new(index)) });
            }
            Err(e) => {
                first_error.get_or_insert((url.clone(), e));
            }
        }
    }
    Err(first_error.expect("at least one endpoint"))
}

/// A channel to one of several coordinators: each call goes to the one that answered last;
/// a call that cannot reach it fails (the caller retries, as for any unreachable coordinator)
/// and moves the next call to the next coordinator in the list.
#[derive(Clone, Debug)]
pub struct Failover {
    channels: Arc<[(String, Channel)]>,
    current: Arc<AtomicUsize>,
}

impl Failover {
    /// The URL calls go to now.
    pub fn url(&self) -> &str {
        &self.channels[self.current.load(Ordering::Relaxed) % self.channels.len()].0
    }
}

impl tower::Service<http::Request<Body>> for Failover {
    type Response = http::Response<Body>;
    type Error = tonic::transport::Error;
    type Future = std::pin::Pin<
        Box<dyn Future<Output = Result<Self::Response, Self::Error>> + Send + 'static>,
    >;

    /// Always ready: the channel chosen in [`Failover::call`] is made ready there.
    fn poll_ready(
        &mut self,
        _: &mut std::task::Context<'_>,
    ) -> std::task::Poll<Result<(), Self::Error>> {
        std::task::Poll::Ready(Ok(()))
    }

    fn call(&mut self, request: http::Request<Body>) -> Self::Future {
        let count = self.channels.len();
        let index = self.current.load(Ordering::Relaxed) % count;
        let channel = self.channels[index].1.clone();
        let current = self.current.clone();
        Box::pin(async move {
            let response = tower::ServiceExt::oneshot(channel, request).await;
            if response.is_err() && count > 1 {
                // Unless another call moved on already.
                let _ = current.compare_exchange(
                    index,
                    (index + 1) % count,
                    Ordering::Relaxed,
                    Ordering::Relaxed,
                );
            }
            response
        })
    }
}

/// An error and its sources on one line. Transport errors keep the useful part (a refused
/// connection, a certificate not trusted) in their sources; a source already quoted by the
/// text before it is not repeated.
pub fn error_chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut parts = vec![e.to_string()];
    let mut source = e.source();
    while let Some(s) = source {
        let text = s.to_string();
        if !parts.iter().any(|p| p.contains(&text)) {
            parts.push(text);
        }
        source = s.source();
    }
    parts.join(": ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_coordinators_are_one_list_separated_by_commas() {
        let list = endpoints("http://a:7878, http://b:7878,", None).unwrap();
        let urls: Vec<&str> = list.iter().map(|(url, _)| url.as_str()).collect();
        assert_eq!(urls, ["http://a:7878", "http://b:7878"]);
        let Err(DialError::Url { url, problem }) = endpoints("http://a:7878,b:7878", None) else {
            panic!("a URL without its scheme was taken")
        };
        assert_eq!(url, "b:7878");
        assert!(problem.contains("http://HOST:PORT"), "{problem}");
        assert!(endpoints(" , ", None).is_err(), "no URL was taken");
    }

    /// The first coordinator that answers is the one called; with none answering, the first
    /// one's error is given, naming it.
    #[tokio::test]
    async fn calls_go_to_the_coordinator_that_answers() {
        let closed = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap();
        let open = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let at = open.local_addr().unwrap();
        tokio::spawn(async move {
            // Accepts and holds connections: enough for the client's connect to succeed.
            let mut held = Vec::new();
            while let Ok((socket, _)) = open.accept().await {
                held.push(socket);
            }
        });
        let list = endpoints(&format!("http://{closed},http://{at}"), None).unwrap();
        let channel = connect(&list).await.unwrap();
        assert_eq!(channel.url(), format!("http://{at}"));
        let list = endpoints(&format!("http://{closed}"), None).unwrap();
        let (url, _) = connect(&list).await.unwrap_err();
        assert_eq!(url, format!("http://{closed}"));
    }
}
