//! TLS to PostgreSQL, as libpq's `sslmode` and `sslrootcert` say (PostgreSQL's documentation,
//! "SSL Support", table "SSL Mode Descriptions"), so that a site's usual database URL works:
//!
//! | `sslmode`          | encrypted                  | the server's certificate                  |
//! |--------------------|----------------------------|-------------------------------------------|
//! | `disable`          | never                      | —                                         |
//! | `prefer` (default) | when the server offers TLS | not checked                               |
//! | `require`          | always                     | not checked                               |
//! | `verify-ca`        | always                     | signed by an authority of `sslrootcert`   |
//! | `verify-full`      | always                     | that, and issued for the host connected to |
//!
//! `sslrootcert` is a PEM file of authorities, or `system` (the default here) for the system's.
//! `sslcert` and `sslkey` (PEM files, the key unencrypted) give a client certificate, for a
//! server that authenticates by certificate (`cert` in `pg_hba.conf`).
//! tokio-postgres knows the first three modes and no `sslrootcert`: the URL is rewritten for it
//! (the two checking modes become `require`) and the check is made by the verifier built here.
//! rustls with ring, as everywhere in the farm; channel binding (SCRAM-SHA-256-PLUS) comes with
//! `tokio-postgres-rustls`.

use rustls::DigitallySignedStruct;
use rustls::client::WebPkiServerVerifier;
use rustls::client::danger::{HandshakeSignatureValid, ServerCertVerified, ServerCertVerifier};
use rustls::crypto::CryptoProvider;
use rustls::pki_types::pem::PemObject as _;
use rustls::pki_types::{CertificateDer, PrivateKeyDer, ServerName, UnixTime};
use std::sync::Arc;
use tokio_postgres_rustls::MakeRustlsConnect;

/// What is checked of the server's certificate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Check {
    Nothing,
    Authority,
    AuthorityAndName,
}

/// The URL for tokio-postgres, and the TLS connector for its `sslmode`. An error is a sentence
/// naming the parameter and the fix.
pub fn settings(url: &str) -> Result<(String, MakeRustlsConnect), String> {
    let mut check = Check::Nothing;
    let mut roots = None;
    let (mut cert, mut cert_key) = (None, None);
    let mut kept = Vec::new();
    let (head, params, separator) = match url.split_once("://") {
        Some(_) => match url.split_once('?') {
            Some((head, query)) => (head, query.split('&').collect::<Vec<_>>(), "&"),
            None => (url, Vec::new(), "&"),
        },
        None => ("", url.split_whitespace().collect(), " "),
    };
    for param in params {
        let (key, value) = param.split_once('=').unwrap_or((param, ""));
        match (key, decoded(value).as_str()) {
            ("sslmode", "verify-ca") => check = Check::Authority,
            ("sslmode", "verify-full") => check = Check::AuthorityAndName,
            ("sslmode", "allow") => {
                return Err("sslmode=allow is not supported: give disable, prefer, require, \
                            verify-ca or verify-full"
                    .into());
            }
            ("sslrootcert", path) => roots = Some(path.to_owned()),
            ("sslcert", path) => cert = Some(path.to_owned()),
            ("sslkey", path) => cert_key = Some(path.to_owned()),
            _ => kept.push(param.to_owned()),
        }
    }
    if check != Check::Nothing {
        kept.push("sslmode=require".into());
    }
    let rewritten = match (head, kept.is_empty()) {
        ("", _) => kept.join(separator),
        (head, true) => head.to_owned(),
        (head, false) => format!("{head}?{}", kept.join(separator)),
    };
    let identity = match (cert, cert_key) {
        (None, None) => None,
        (Some(cert), Some(key)) => Some(client_identity(&cert, &key)?),
        _ => {
            return Err(
                "give sslcert and sslkey together (a client certificate and its key)".into()
            );
        }
    };
    Ok((rewritten, MakeRustlsConnect::new(client_config(check, roots.as_deref(), identity)?)))
}

/// A client certificate's chain and key, from `sslcert` and `sslkey`.
type Identity = (Vec<CertificateDer<'static>>, PrivateKeyDer<'static>);

fn client_identity(cert: &str, key: &str) -> Result<Identity, String> {
    let chain = CertificateDer::pem_file_iter(cert)
        .and_then(|certs| certs.collect::<Result<Vec<_>, _>>())
        .map_err(|e| format!("sslcert={cert}: {e}; give a PEM file of the client's certificate"))?;
    if chain.is_empty() {
        return Err(format!("sslcert={cert} holds no certificate: give a PEM file of it"));
    }
    let key = PrivateKeyDer::from_pem_file(key)
        .map_err(|e| format!("sslkey={key}: {e}; give the certificate's key, unencrypted PEM"))?;
    Ok((chain, key))
}

/// What to change when the server's certificate was refused, given the connection's error.
pub fn fix(message: &str) -> Option<&'static str> {
    if message.contains("not valid for name") {
        Some(
            "connect by a name the certificate gives, or check only its authority with sslmode=verify-ca",
        )
    } else if message.contains("invalid peer certificate") {
        Some(
            "trust the server's certificate authority with sslrootcert=PATH in the URL, or \
             encrypt without checking the certificate with sslmode=require",
        )
    } else {
        None
    }
}

/// `value` with its `%XX` escapes decoded, as tokio-postgres decodes a URL's parameters.
fn decoded(value: &str) -> String {
    percent_encoding::percent_decode_str(value).decode_utf8_lossy().into_owned()
}

fn client_config(
    check: Check,
    roots: Option<&str>,
    identity: Option<Identity>,
) -> Result<rustls::ClientConfig, String> {
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let builder = rustls::ClientConfig::builder_with_provider(provider.clone())
        .with_safe_default_protocol_versions()
        .map_err(|e| format!("TLS: {e}"))?;
    let authorities = match check {
        Check::Nothing => None,
        Check::Authority | Check::AuthorityAndName => Some(
            WebPkiServerVerifier::builder_with_provider(
                Arc::new(authorities(roots)?),
                provider.clone(),
            )
            .build()
            .map_err(|e| format!("sslrootcert: {e}"))?,
        ),
    };
    let verifier = Verifier { check, authorities, provider };
    let builder = builder.dangerous().with_custom_certificate_verifier(Arc::new(verifier));
    match identity {
        None => Ok(builder.with_no_client_auth()),
        Some((chain, key)) => {
            builder.with_client_auth_cert(chain, key).map_err(|e| format!("sslcert, sslkey: {e}"))
        }
    }
}

/// The authorities `sslrootcert` names: a PEM file, or the system's (`system`, or none given).
fn authorities(roots: Option<&str>) -> Result<rustls::RootCertStore, String> {
    let mut store = rustls::RootCertStore::empty();
    match roots {
        None | Some("system") => {
            for cert in rustls_native_certs::load_native_certs().certs {
                let _ = store.add(cert);
            }
        }
        Some(path) => {
            let certs = CertificateDer::pem_file_iter(path)
                .and_then(|certs| certs.collect::<Result<Vec<_>, _>>())
                .map_err(|e| {
                    format!("sslrootcert={path}: {e}; give a PEM file of certificate authorities")
                })?;
            for cert in certs {
                store.add(cert).map_err(|e| format!("sslrootcert={path}: {e}"))?;
            }
        }
    }
    if store.is_empty() {
        let named = roots.unwrap_or("system");
        return Err(format!(
            "sslrootcert={named} holds no certificate authority: give a PEM file of them"
        ));
    }
    Ok(store)
}

/// The server's certificate checked as `check` says: not at all (`prefer`, `require`: libpq
/// takes it as it comes), its chain only (`verify-ca`: a name mismatch is forgiven), or chain
/// and name (`verify-full`). The handshake's signatures are checked in every mode.
#[derive(Debug)]
struct Verifier {
    check: Check,
    /// The chain's check (with `verify-ca` and `verify-full`).
    authorities: Option<Arc<WebPkiServerVerifier>>,
    provider: Arc<CryptoProvider>,
}

impl ServerCertVerifier for Verifier {
    fn verify_server_cert(
        &self,
        end_entity: &CertificateDer<'_>,
        intermediates: &[CertificateDer<'_>],
        server_name: &ServerName<'_>,
        ocsp_response: &[u8],
        now: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        use rustls::CertificateError::{NotValidForName, NotValidForNameContext};
        let Some(authorities) = &self.authorities else {
            return Ok(ServerCertVerified::assertion());
        };
        let checked = authorities.verify_server_cert(
            end_entity,
            intermediates,
            server_name,
            ocsp_response,
            now,
        );
        match checked {
            Err(rustls::Error::InvalidCertificate(
                NotValidForName | NotValidForNameContext { .. },
            )) if self.check == Check::Authority => Ok(ServerCertVerified::assertion()),
            checked => checked,
        }
    }

    fn verify_tls12_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        let algorithms = &self.provider.signature_verification_algorithms;
        rustls::crypto::verify_tls12_signature(message, cert, dss, algorithms)
    }

    fn verify_tls13_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        let algorithms = &self.provider.signature_verification_algorithms;
        rustls::crypto::verify_tls13_signature(message, cert, dss, algorithms)
    }

    fn supported_verify_schemes(&self) -> Vec<rustls::SignatureScheme> {
        self.provider.signature_verification_algorithms.supported_schemes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rewritten(url: &str) -> String {
        settings(url).map(|(url, _)| url).unwrap_or_else(|e| e)
    }

    #[test]
    fn the_checking_modes_reach_tokio_postgres_as_require_and_the_others_as_given() {
        let base = "postgres://u@h:5432/db";
        assert_eq!(rewritten(base), base);
        assert_eq!(rewritten(&format!("{base}?sslmode=prefer")), format!("{base}?sslmode=prefer"));
        assert_eq!(
            rewritten(&format!("{base}?application_name=x&sslmode=verify-full&sslrootcert=system")),
            format!("{base}?application_name=x&sslmode=require")
        );
        assert_eq!(
            rewritten("host=h sslmode=verify-ca sslrootcert=system dbname=db"),
            "host=h dbname=db sslmode=require"
        );
        assert!(rewritten(&format!("{base}?sslmode=allow")).contains("not supported"));
        assert!(
            rewritten(&format!("{base}?sslcert=c.pem")).contains("sslcert and sslkey together")
        );
    }

    #[test]
    fn an_authority_file_that_is_not_there_or_holds_none_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let absent = dir.path().join("absent.crt");
        let url = format!("postgres://u@h/db?sslmode=verify-full&sslrootcert={}", absent.display());
        let e = rewritten(&url);
        assert!(e.contains("absent.crt") && e.contains("PEM file"), "{e}");
        let empty = dir.path().join("empty.crt");
        std::fs::write(&empty, "no certificate here\n").unwrap();
        let url = format!("postgres://u@h/db?sslmode=verify-ca&sslrootcert={}", empty.display());
        let e = rewritten(&url);
        assert!(e.contains("empty.crt") && e.contains("no certificate authority"), "{e}");
    }
}
