//! Why a worker could not render a tile, and whether that is the tile's fault or the
//! transport's. Only the coordinator may fail a job; it needs to know which failures say
//! something about the scene (a broken mesh fails on every worker) and which say only that the
//! network blinked (the coordinator restarting while this worker fetched an asset). That is
//! decided here, in one function, and sent as data (`FailRequest.retryable`).

use tonic::Code;

/// Why a job could not be made ready to render on this worker.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// A call to the coordinator failed.
    #[error("fetching {what}: {} ({:?})", status.message(), status.code())]
    Fetch { what: String, status: tonic::Status },
    /// An asset arrived with bytes that do not have its hash.
    #[error("asset {reference} arrived damaged (its hash differs)")]
    Damaged { reference: String },
    /// The coordinator's job does not load, plan or prepare here.
    #[error("{0}")]
    Scene(String),
    /// This worker's own trouble (its render threads stopped).
    #[error("{0}")]
    Local(String),
}

/// Whether a failure is the transport's (the tile goes back to the queue and counts against
/// nobody) rather than the tile's.
pub fn retryable(error: &JobError) -> bool {
    match error {
        JobError::Fetch { status, .. } => matches!(
            status.code(),
            Code::Unavailable
                | Code::DeadlineExceeded
                | Code::Cancelled
                // A coordinator restarted since the lease: this worker must register again.
                | Code::Aborted
                | Code::ResourceExhausted
                | Code::Unknown
                | Code::Internal
        ),
        // Bytes damaged on the way: another fetch will most likely be whole.
        JobError::Damaged { .. } => true,
        JobError::Scene(_) => false,
        // Not the tile's fault either: another worker may render it.
        JobError::Local(_) => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fetch(code: Code) -> JobError {
        JobError::Fetch { what: "job j".into(), status: tonic::Status::new(code, "x") }
    }

    #[test]
    fn transport_failures_are_retried_and_the_scenes_are_not() {
        for code in [
            Code::Unavailable,
            Code::DeadlineExceeded,
            Code::Cancelled,
            Code::Aborted,
            Code::ResourceExhausted,
            Code::Unknown,
            Code::Internal,
        ] {
            assert!(retryable(&fetch(code)), "{code:?}");
        }
        // An asset the coordinator does not have (FAILED_PRECONDITION), a job it does not know.
        for code in [
            Code::NotFound,
            Code::InvalidArgument,
            Code::PermissionDenied,
            Code::FailedPrecondition,
        ] {
            assert!(!retryable(&fetch(code)), "{code:?}");
        }
        assert!(retryable(&JobError::Damaged { reference: "blake3:00.obj".into() }));
        assert!(!retryable(&JobError::Scene("meshes/facade.obj:3: a face with 2 vertices".into())));
        assert!(retryable(&JobError::Local("the render thread stopped".into())));
        let message = fetch(Code::Unavailable).to_string();
        assert!(message.contains("fetching job j") && message.contains("Unavailable"), "{message}");
    }
}
