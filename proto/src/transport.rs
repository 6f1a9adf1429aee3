//! The dialling side of a connection to the coordinator, for clients and workers alike:
//! plaintext HTTP/2 for `http://` URLs, TLS (rustls) for `https://` ones, trusting the system's
//! certificate authorities and, when given, the authority in a PEM file (a site's own CA).

use std::path::Path;
use std::time::Duration;
use tonic::transport::{Certificate, ClientTlsConfig, Endpoint};

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
