//! The identities the coordinator hands out: jobs, workers, and the secret that binds a worker
//! to its registration.

use serde::{Deserialize, Serialize};
use std::borrow::Borrow;
use std::fmt;
use std::ops::Deref;
use std::sync::Arc;

/// A job's id: a UUID chosen by the coordinator. Cheap to clone (an `Arc<str>` inside), so a
/// lease carries it without allocating.
#[derive(Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(from = "String", into = "String")]
pub struct JobId(Arc<str>);

impl JobId {
    /// A new, random id.
    pub fn random() -> Self {
        Self::from(uuid::Uuid::new_v4().to_string())
    }

    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// A job id from a caller: the coordinator's ids are UUIDs, and nothing else names a job.
    pub fn parse(text: &str) -> Result<Self, restauro_proto::convert::WireError> {
        if uuid::Uuid::parse_str(text).is_err() {
            let problem = format!("`{}` is not a job id", text.escape_debug());
            return Err(restauro_proto::convert::WireError::new("job_id", problem));
        }
        Ok(JobId::from(text))
    }
}

impl From<&str> for JobId {
    fn from(s: &str) -> Self {
        Self(Arc::from(s))
    }
}

impl From<String> for JobId {
    fn from(s: String) -> Self {
        Self(Arc::from(s))
    }
}

impl From<JobId> for String {
    fn from(id: JobId) -> String {
        id.0.to_string()
    }
}

impl Deref for JobId {
    type Target = str;
    fn deref(&self) -> &str {
        &self.0
    }
}

impl Borrow<str> for JobId {
    fn borrow(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for JobId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl fmt::Debug for JobId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&*self.0, f)
    }
}

/// A worker's id, assigned at registration from 1 up and never reused within a run of the
/// coordinator (64 bits: no run registers enough workers to wrap).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct WorkerId(pub u64);

impl fmt::Display for WorkerId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// The secret a worker is told when it registers and shows on every later call, so that no
/// other holder of the worker token can act in its name. 256 bits from the operating system's
/// random source; compared in constant time.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct SessionKey(blake3::Hash);

/// 256 bits from the operating system's random source (UUID v4 draws them).
pub fn random_secret() -> [u8; 32] {
    let mut bytes = [0u8; 32];
    bytes[..16].copy_from_slice(uuid::Uuid::new_v4().as_bytes());
    bytes[16..].copy_from_slice(uuid::Uuid::new_v4().as_bytes());
    bytes
}

impl SessionKey {
    pub fn random() -> Self {
        Self(blake3::Hash::from(random_secret()))
    }

    /// The key a worker sent; `None` unless it is 32 bytes.
    pub fn from_wire(bytes: &[u8]) -> Option<Self> {
        let bytes: [u8; 32] = bytes.try_into().ok()?;
        Some(Self(blake3::Hash::from(bytes)))
    }

    pub fn to_wire(self) -> Vec<u8> {
        self.0.as_bytes().to_vec()
    }
}

impl fmt::Debug for SessionKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("SessionKey(…)")
    }
}

/// A worker's session: its id and the secret it was told at registration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Session {
    pub worker: WorkerId,
    pub key: SessionKey,
}

impl TryFrom<Option<&restauro_proto::WorkerSession>> for Session {
    type Error = restauro_proto::convert::WireError;
    fn try_from(s: Option<&restauro_proto::WorkerSession>) -> Result<Self, Self::Error> {
        use restauro_proto::convert::WireError;
        let s = s.ok_or_else(|| WireError::missing("session"))?;
        let key = SessionKey::from_wire(&s.key)
            .ok_or_else(|| WireError::new("session.key", "not the 32 bytes registration gave"))?;
        Ok(Session { worker: WorkerId(s.worker_id), key })
    }
}

impl From<Session> for restauro_proto::WorkerSession {
    fn from(s: Session) -> Self {
        restauro_proto::WorkerSession { worker_id: s.worker.0, key: s.key.to_wire() }
    }
}
