//! The one error of a farm's client and of the embedded cluster, each message saying what was
//! being done and what the coordinator answered.

use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum ClusterError {
    /// The coordinator refused a call: what was being done, the refusal in the user's terms
    /// (`unauthenticated`, `over a limit`…) and the coordinator's own message.
    #[error("{what}: {code}: {message}")]
    Refused { what: String, code: &'static str, message: String },
    #[error("client token: {0}")]
    Token(String),
    #[error(transparent)]
    Dial(#[from] restauro_proto::transport::DialError),
    #[error("connecting to the coordinator at {url}: {chain}")]
    Connect { url: String, chain: String },
    #[error("bad reference {0}")]
    BadReference(String),
    #[error("{0} is not in the bundle")]
    NotInBundle(String),
    #[error("the coordinator named a result `{0}`, which is not a plain file name")]
    ResultName(String),
    #[error("{what}: the coordinator sent {sent} of the {announced} bytes it announced")]
    ShortFile { what: String, sent: usize, announced: u64 },
    /// A job status the coordinator sent that does not hold a job (an id that is no UUID, a
    /// state this client does not know): the field and what is wrong with it.
    #[error("the coordinator sent a job status this client cannot read: {0}")]
    Status(#[from] restauro_proto::convert::WireError),
    #[error("the embedded coordinator did not start: {0}")]
    CoordinatorDidNotStart(String),
    /// A file or process of this machine: what was being done, and the system's reason.
    #[error("{what}")]
    Io {
        what: String,
        #[source]
        source: std::io::Error,
    },
    #[error("progress template")]
    ProgressTemplate(#[source] indicatif::style::TemplateError),
    #[error("a download stopped: {0}")]
    Task(#[from] tokio::task::JoinError),
}

/// An I/O failure while `what` (e.g. `creating out/`), with its path.
pub(crate) fn io_error(what: &str, path: &Path) -> impl FnOnce(std::io::Error) -> ClusterError {
    let what = format!("{what} {}", path.display());
    move |source| ClusterError::Io { what, source }
}

/// An I/O failure while `what`, where no path names it.
pub(crate) fn io_doing(what: &str) -> impl FnOnce(std::io::Error) -> ClusterError {
    let what = what.to_owned();
    move |source| ClusterError::Io { what, source }
}
