//! The one error of the benchmarks: what was being measured when it failed.

use restauro_assets::AssetsError;
use restauro_cluster::ClusterError;
use restauro_render::prepared::TraceError;
use restauro_scene::error::SceneError;

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A file or process of this machine: what was being done, and the system's reason.
    #[error("{what}")]
    Io {
        what: String,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Assets(#[from] AssetsError),
    /// A scene that did not load, with the benchmark's name for it.
    #[error("{what}")]
    SceneNamed {
        what: String,
        #[source]
        source: AssetsError,
    },
    #[error(transparent)]
    JobSpec(#[from] restauro_scene::job::JobSpecError),
    #[error(transparent)]
    Trace(#[from] TraceError),
    #[error(transparent)]
    Seen(#[from] restauro_spectral::Error),
    #[error(transparent)]
    Cluster(#[from] ClusterError),
    #[error(transparent)]
    Threads(#[from] rayon::ThreadPoolBuildError),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    #[error(transparent)]
    Connect(#[from] tonic::transport::Error),
    #[error(transparent)]
    Task(#[from] tokio::task::JoinError),
    /// A call of a simulated worker that the coordinator refused.
    #[error("{what}: {message}")]
    Refused { what: &'static str, message: String },
    /// `restauro render`, run as a user runs it, failed.
    #[error("`restauro render` failed: {0}")]
    Render(String),
    /// The benchmark could not go on (a timeout, a forgotten worker).
    #[error("{0}")]
    Stopped(String),
}

/// An I/O failure while `what`.
pub(crate) fn io_doing(what: impl Into<String>) -> impl FnOnce(std::io::Error) -> BenchError {
    let what = what.into();
    move |source| BenchError::Io { what, source }
}
