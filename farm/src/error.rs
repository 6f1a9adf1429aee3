//! The coordinator's one error type, and its one mapping to a gRPC status. Every refusal says
//! what was refused and what to do; the gRPC code tells a program whether to retry.

use crate::ids::JobId;
use crate::job::JobState;
use crate::store::StoreError;
use restauro_proto::convert::WireError;
use restauro_scene::SceneError;

#[derive(Debug, thiserror::Error)]
pub enum CoordinatorError {
    /// A caller of another protocol version.
    #[error(
        "protocol version {theirs} refused: this coordinator speaks protocol {ours}; run a \
         {role} of the same restauro release"
    )]
    ProtocolVersion { theirs: String, ours: u32, role: &'static str },

    #[error("no bearer token: a {role} must send `authorization: Bearer <token>`")]
    NoToken { role: &'static str },

    #[error("the {role} token is not valid")]
    BadToken { role: &'static str },

    #[error("forbidden: this is a {held} token, and only a {needed} token may call this service")]
    WrongRole { held: &'static str, needed: &'static str },

    /// A request field the domain cannot hold.
    #[error("invalid request: {0}")]
    Wire(#[from] WireError),

    /// The scene of a submission does not load or plan.
    #[error("{0}")]
    Scene(#[from] SceneError),

    #[error("asset reference `{reference}`: expected `blake3:<64 hex digits>.<extension>`")]
    AssetReference { reference: String },

    #[error("asset {reference} has not been uploaded; upload it before submitting")]
    AssetMissing { reference: String },

    #[error("asset {reference}: {problem}")]
    AssetUpload { reference: String, problem: String },

    #[error("no job {0}")]
    NoSuchJob(JobId),

    #[error("job {job} has no result `{name}`")]
    NoSuchResult { job: JobId, name: String },

    #[error("job {job} is {state}, not done: its results are not written yet")]
    NotDone { job: JobId, state: JobState },

    /// A lifecycle move the job's state does not allow (e.g. finishing a cancelled job).
    #[error("job {job} is {from}; it cannot become {to}")]
    IllegalTransition { job: JobId, from: JobState, to: JobState },

    /// A limit of the coordinator's, with the flag that raises it.
    #[error("{what} is {value}, over the limit of {limit} ({flag}); {fix}")]
    Limit { what: String, value: u64, limit: u64, flag: &'static str, fix: &'static str },

    #[error(
        "{open} jobs are unfinished, the most this coordinator takes (--max-jobs); wait for one \
         to finish or cancel one"
    )]
    TooManyJobs { open: usize },

    /// A caller that stopped sending or reading: what it held is given back.
    #[error("{what} stalled: nothing moved for {seconds} s ({flag}); {fix}")]
    Stalled { what: String, seconds: u64, flag: &'static str, fix: &'static str },

    /// A worker's session the coordinator does not know: it restarted, or dropped the worker.
    #[error("worker session {worker} is not known to this coordinator: register again")]
    UnknownSession { worker: u64 },

    /// A lease the coordinator did not grant (its ticket does not verify), or one granted to
    /// another worker.
    #[error("lease of tile {tile} of job {job}: {problem}")]
    ForeignLease { job: String, tile: u32, problem: &'static str },

    /// A tile report whose pixels the job cannot use.
    #[error("tile {tile} of job {job}: {problem}")]
    TileData { job: JobId, tile: u32, problem: String },

    /// The store cannot be written (a full disk, a failing device): the request may be retried
    /// once it recovers.
    #[error("{0}; the coordinator retries the store and resumes when it can write again")]
    Store(#[from] StoreError),

    #[error("{path}: {source}")]
    Io { path: String, source: std::io::Error },

    /// A studio request without a valid client token or session.
    #[error(
        "not signed in: give the client token (the page asks for it; a program sends \
         `authorization: Bearer <token>`)"
    )]
    NotSignedIn,

    /// A change sent to the studio from another site's page (cross-site request forgery).
    #[error(
        "refused: this change comes from a page at {origin}, not from the studio at {expected}; \
         open the studio's own address"
    )]
    CrossOrigin { origin: String, expected: String },

    /// A studio request whose body or path does not say what it must.
    #[error("invalid request: {0}")]
    Request(String),

    #[error("no scene {0}: the coordinator holds the scenes of its jobs")]
    NoSuchScene(String),

    #[error("no such page `{0}` in the studio")]
    NoSuchPage(String),

    #[error("no image {0} is kept by this coordinator; attach it to the note again")]
    NoSuchImage(String),

    #[error("internal error: {0}")]
    Internal(String),
}

pub type Result<T, E = CoordinatorError> = std::result::Result<T, E>;

/// A scene folder or bundle the assets crate refuses: a scene error as the scene model words it
/// (an asset refusal is worded as an invalid file), mapped to a status as any scene error is.
impl From<restauro_assets::AssetsError> for CoordinatorError {
    fn from(e: restauro_assets::AssetsError) -> Self {
        CoordinatorError::Scene(e.into_scene_error())
    }
}

/// A blocking task that panicked or was cancelled: the coordinator's own fault, said as such.
impl From<tokio::task::JoinError> for CoordinatorError {
    fn from(e: tokio::task::JoinError) -> Self {
        CoordinatorError::Internal(e.to_string())
    }
}

impl CoordinatorError {
    pub fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io { path: path.display().to_string(), source }
    }

    /// The gRPC code: what a client or worker should do about it.
    pub fn code(&self) -> tonic::Code {
        use CoordinatorError as E;
        use tonic::Code;
        match self {
            E::ProtocolVersion { .. } | E::NotDone { .. } | E::IllegalTransition { .. } => {
                Code::FailedPrecondition
            }
            E::AssetMissing { .. } => Code::FailedPrecondition,
            // "Retry at a higher level": register again, then call again.
            E::UnknownSession { .. } => Code::Aborted,
            E::NoToken { .. } | E::BadToken { .. } => Code::Unauthenticated,
            E::WrongRole { .. } | E::ForeignLease { .. } => Code::PermissionDenied,
            E::Scene(SceneError::Limit { .. }) => Code::ResourceExhausted,
            E::Wire(_) | E::Scene(_) | E::AssetReference { .. } | E::AssetUpload { .. } => {
                Code::InvalidArgument
            }
            E::TileData { .. } => Code::InvalidArgument,
            E::NoSuchJob(_) | E::NoSuchResult { .. } => Code::NotFound,
            E::Limit { .. } | E::TooManyJobs { .. } => Code::ResourceExhausted,
            E::Stalled { .. } => Code::DeadlineExceeded,
            E::Store(_) => Code::Unavailable,
            E::Io { .. } | E::Internal(_) => Code::Internal,
            E::NotSignedIn => Code::Unauthenticated,
            E::CrossOrigin { .. } => Code::PermissionDenied,
            E::Request(_) => Code::InvalidArgument,
            E::NoSuchPage(_) | E::NoSuchScene(_) | E::NoSuchImage(_) => Code::NotFound,
        }
    }

    /// The HTTP status of the studio's answer: the gRPC code's counterpart (as in Google's
    /// HTTP mapping of gRPC codes), so both doors refuse the same thing the same way.
    pub fn http_status(&self) -> axum::http::StatusCode {
        use axum::http::StatusCode as S;
        use tonic::Code;
        match self.code() {
            // A job that is not done yet has no result to give: that is a conflict of state.
            Code::FailedPrecondition => S::CONFLICT,
            Code::Aborted => S::CONFLICT,
            Code::Unauthenticated => S::UNAUTHORIZED,
            Code::PermissionDenied => S::FORBIDDEN,
            Code::InvalidArgument => S::BAD_REQUEST,
            Code::NotFound => S::NOT_FOUND,
            Code::ResourceExhausted => S::TOO_MANY_REQUESTS,
            Code::Unavailable => S::SERVICE_UNAVAILABLE,
            Code::DeadlineExceeded => S::REQUEST_TIMEOUT,
            _ => S::INTERNAL_SERVER_ERROR,
        }
    }
}

/// The one conversion to a gRPC status.
impl From<CoordinatorError> for tonic::Status {
    fn from(e: CoordinatorError) -> Self {
        tonic::Status::new(e.code(), e.to_string())
    }
}

/// The one conversion of the coordinator's errors to an HTTP answer (the studio's): the status
/// of [`CoordinatorError::http_status`] and the message as `{"error": "…"}`.
impl axum::response::IntoResponse for CoordinatorError {
    fn into_response(self) -> axum::response::Response {
        #[derive(serde::Serialize)]
        struct Body {
            error: String,
        }
        (self.http_status(), axum::Json(Body { error: self.to_string() })).into_response()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_error_maps_to_the_code_that_tells_the_caller_what_to_do() {
        let status = |e: CoordinatorError| tonic::Status::from(e);
        let s = status(CoordinatorError::TooManyJobs { open: 3 });
        assert_eq!(s.code(), tonic::Code::ResourceExhausted);
        assert!(s.message().contains("--max-jobs"), "{}", s.message());
        let s = status(CoordinatorError::Store(StoreError::Store {
            path: "/x/store.redb".into(),
            message: "No space left on device".into(),
        }));
        assert_eq!(s.code(), tonic::Code::Unavailable);
        assert!(s.message().contains("No space left") && s.message().contains("/x/store.redb"));
        let s = status(CoordinatorError::UnknownSession { worker: 7 });
        assert_eq!(s.code(), tonic::Code::Aborted);
        assert!(s.message().contains("register again"));
    }
}
