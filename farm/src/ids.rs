//! The identities the coordinator hands out: jobs, workers, and the secret that binds a worker
//! to its registration.

use std::fmt;

/// A job's id lives with the wire types, which the command line shares.
pub use restauro_proto::job_status::JobId;

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
