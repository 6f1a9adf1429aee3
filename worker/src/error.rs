//! The one error type at the worker's boundary ([`crate::process::run`]): what stops the worker
//! as a whole — it cannot start, the coordinator refuses it, or a failed tile cannot even be
//! reported. A tile that cannot be rendered is not one of these: it is a
//! [`crate::failure::JobError`], reported to the coordinator as data, and the worker goes on.
//!
//! A cause the operating system reports is kept as the error's `source`, so the binaries, which
//! print the chain (`anyhow`'s `{:#}`), show `what: why`.

use restauro_ops::OpsError;
use restauro_proto::transport::DialError;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum WorkerError {
    /// The token, the metrics endpoint's flags or its address.
    #[error(transparent)]
    Ops(#[from] OpsError),

    #[error("starting the render threads")]
    RenderThreads(#[source] rayon::ThreadPoolBuildError),

    #[error("creating {}", path.display())]
    Cache {
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },

    #[error("starting the async runtime")]
    Runtime(#[source] std::io::Error),

    /// Standard output, where the metrics address is printed, cannot be written.
    #[error(transparent)]
    Stdout(std::io::Error),

    /// A token that cannot travel in a header; the dial error's words follow `worker token:`.
    #[error("worker token: {0}")]
    Token(DialError),

    /// The coordinator's URL or the CA certificate.
    #[error(transparent)]
    Dial(#[from] DialError),

    /// A refusal that retrying does not cure (the wrong token, another protocol).
    #[error("the coordinator refused this worker: {}", .0.message())]
    Refused(tonic::Status),

    #[error("registered without a session")]
    NoSession,

    #[error("appending to {}", path.display())]
    TileLog {
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },

    #[error("reporting a failed tile: {}", .0.message())]
    ReportFailure(tonic::Status),
}

pub type Result<T, E = WorkerError> = std::result::Result<T, E>;
