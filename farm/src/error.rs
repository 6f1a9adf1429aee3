//! The farm's one error type, [`FarmError`], and its one mapping to a gRPC status (the
//! studio maps the same codes to HTTP statuses in its own error type). Every refusal says what
//! was refused and what to do; the gRPC code tells a program whether to retry. The store's and
//! the scheduler's own errors ([`StoreError`], [`AddJobError`]) reach callers only inside it.

use crate::ids::JobId;
use crate::job::{IllegalTransition, JobState};
use crate::scheduler::AddJobError;
use crate::store::StoreError;
use restauro_proto::convert::WireError;
use restauro_scene::SceneError;

#[derive(Debug, thiserror::Error)]
pub enum FarmError {
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
    #[error("frame {index} ({label}): {problem}")]
    Frame { index: usize, label: String, problem: Box<SceneError> },

    #[error("job {job} has no frame {frame}")]
    NoSuchFrame { job: JobId, frame: u32 },

    #[error("job {job} has no result `{name}`")]
    NoSuchResult { job: JobId, name: String },

    #[error("job {job} is {state}, not done: its results are not written yet")]
    NotDone { job: JobId, state: JobState },

    /// A lifecycle move the job's state does not allow (e.g. finishing a cancelled job).
    #[error(transparent)]
    IllegalTransition(#[from] IllegalTransition),

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

    /// A worker whose rendering of a tile differed from two other workers' (`farm::checks`).
    #[error(
        "worker {name} is quarantined: {reason}. Its tiles are not taken. Find the fault on its \
         machine (memory, a different build of restauro-worker, an altered binary); a worker \
         process started again has a new identity and is checked closely until it is trusted"
    )]
    Quarantined { name: String, reason: String },

    /// A tile report whose pixels the job cannot use.
    #[error("tile {tile} of job {job}: {problem}")]
    TileData { job: JobId, tile: u32, problem: String },

    /// The store cannot be written (a full disk, a failing device): the request may be retried
    /// once it recovers.
    #[error("{0}; the coordinator retries the store and resumes when it can write again")]
    Store(#[from] StoreError),

    #[error("{path}: {source}")]
    Io { path: String, source: std::io::Error },

    /// The object store cannot be reached or written (`objects`): the request may be retried.
    #[error("{0}; try again once the object store answers and has room")]
    Objects(#[from] crate::objects::ObjectsError),

    /// A result file the farm wrote that it cannot read back or derive from.
    #[error("{0}")]
    Image(#[from] restauro_image::ImageError),

    /// An argument of the studio's scene calls (a revision, a file sent) the farm cannot take.
    #[error("invalid request: {0}")]
    Request(String),

    #[error("no scene {0}: the coordinator holds the scenes of its jobs")]
    NoSuchScene(String),

    #[error("internal error: {0}")]
    Internal(String),

    // What stops the farm from opening its data folder: the coordinator does not start. Each
    // says what it was doing, and keeps the failure beneath as its source, as the log shows it.
    #[error("creating {path}")]
    CreateDir { path: String, source: std::io::Error },

    /// The store cannot be opened or read at start (no retry: the coordinator stops).
    #[error(transparent)]
    StoreAtStart(StoreError),

    #[error("starting the store's committer")]
    Committer(#[source] std::io::Error),

    /// A job record in the store that is not JSON.
    #[error("job {job}: unreadable: {problem}")]
    UnreadableRecord { job: String, problem: String },

    /// A stored job the scheduler cannot take back.
    #[error("job {job}: {problem}")]
    Resume { job: JobId, problem: AddJobError },

    #[error("revision {number} of scene {scene} in the store: {problem}")]
    UnreadableRevision { scene: String, number: u32, problem: String },
}

pub type Result<T, E = FarmError> = std::result::Result<T, E>;

/// A scene folder or bundle the assets crate refuses: a scene error as the scene model words it
/// (an asset refusal is worded as an invalid file), mapped to a status as any scene error is.
impl From<restauro_assets::AssetsError> for FarmError {
    fn from(e: restauro_assets::AssetsError) -> Self {
        FarmError::Scene(e.into_scene_error())
    }
}

/// A blocking task that panicked or was cancelled: the coordinator's own fault, said as such.
impl From<tokio::task::JoinError> for FarmError {
    fn from(e: tokio::task::JoinError) -> Self {
        FarmError::Internal(e.to_string())
    }
}

impl FarmError {
    pub fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io { path: path.display().to_string(), source }
    }

    /// The gRPC code: what a client or worker should do about it.
    pub fn code(&self) -> tonic::Code {
        use FarmError as E;
        use tonic::Code;
        match self {
            E::ProtocolVersion { .. } | E::NotDone { .. } | E::IllegalTransition(_) => {
                Code::FailedPrecondition
            }
            E::AssetMissing { .. } => Code::FailedPrecondition,
            // "Retry at a higher level": register again, then call again.
            E::UnknownSession { .. } => Code::Aborted,
            E::NoToken { .. } | E::BadToken { .. } => Code::Unauthenticated,
            E::WrongRole { .. } | E::ForeignLease { .. } | E::Quarantined { .. } => {
                Code::PermissionDenied
            }
            E::Scene(SceneError::Limit { .. }) => Code::ResourceExhausted,
            E::Frame { problem, .. } if matches!(**problem, SceneError::Limit { .. }) => {
                Code::ResourceExhausted
            }
            E::Frame { .. } => Code::InvalidArgument,
            E::Wire(_) | E::Scene(_) | E::AssetReference { .. } | E::AssetUpload { .. } => {
                Code::InvalidArgument
            }
            E::TileData { .. } => Code::InvalidArgument,
            E::NoSuchJob(_) | E::NoSuchFrame { .. } | E::NoSuchResult { .. } => Code::NotFound,
            E::Limit { .. } | E::TooManyJobs { .. } => Code::ResourceExhausted,
            E::Stalled { .. } => Code::DeadlineExceeded,
            E::Store(_) | E::Objects(_) => Code::Unavailable,
            E::Io { .. } | E::Internal(_) | E::Image(_) => Code::Internal,
            E::Request(_) => Code::InvalidArgument,
            E::NoSuchScene(_) => Code::NotFound,
            E::CreateDir { .. }
            | E::StoreAtStart(_)
            | E::Committer(_)
            | E::UnreadableRecord { .. }
            | E::Resume { .. }
            | E::UnreadableRevision { .. } => Code::Internal,
        }
    }
}

/// The one conversion to a gRPC status.
impl From<FarmError> for tonic::Status {
    fn from(e: FarmError) -> Self {
        tonic::Status::new(e.code(), e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_error_maps_to_the_code_that_tells_the_caller_what_to_do() {
        let status = |e: FarmError| tonic::Status::from(e);
        let s = status(FarmError::TooManyJobs { open: 3 });
        assert_eq!(s.code(), tonic::Code::ResourceExhausted);
        assert!(s.message().contains("--max-jobs"), "{}", s.message());
        let s = status(FarmError::Store(StoreError::Store {
            path: "/x/store.redb".into(),
            message: "No space left on device".into(),
        }));
        assert_eq!(s.code(), tonic::Code::Unavailable);
        assert!(s.message().contains("No space left") && s.message().contains("/x/store.redb"));
        let s = status(FarmError::UnknownSession { worker: 7 });
        assert_eq!(s.code(), tonic::Code::Aborted);
        assert!(s.message().contains("register again"));
    }
}
