//! The one error type of restauro-ops: what stops a process from being operated as asked (its
//! metrics endpoint, its tokens). A cause the operating system reports is kept as the error's
//! `source`, so a binary that prints the chain (`anyhow`'s `{:#}`) shows `what: why`.

use std::net::SocketAddr;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum OpsError {
    /// The metrics address cannot be bound (taken, or not this machine's).
    #[error("listening for metrics on {addr}")]
    Listen {
        addr: SocketAddr,
        #[source]
        error: std::io::Error,
    },

    /// The bound listener cannot say its own address.
    #[error(transparent)]
    LocalAddr(std::io::Error),

    /// A token file that cannot be read.
    #[error("reading the token file {}", path.display())]
    TokenFile {
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },

    /// No token in the file nor in the environment; says which flag or variable to set.
    #[error("no token: give {flag} FILE or set {variable}")]
    NoToken { flag: String, variable: String },

    /// `/metrics` on an address other machines reach, with neither a token nor the operator's
    /// word that the network guards it.
    #[error(
        "--metrics-listen {at} can be reached from other machines, and /metrics tells them the \
         farm's jobs, workers and load: give --metrics-token-file FILE (Prometheus sends it with \
         `authorization: {{ credentials_file: FILE }}`), serve on 127.0.0.1, or give \
         --metrics-public if the network already guards the port"
    )]
    OpenMetrics { at: SocketAddr },
}

pub type Result<T, E = OpsError> = std::result::Result<T, E>;
