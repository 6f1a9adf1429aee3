//! What the studio's JSON says of a worker: converted once, here, from the domain's type (the
//! gRPC door converts the same type to its message in `grpc.rs`). A job needs no view: the
//! `JobStatus` (restauro-proto's, as the farm keeps it) is sent as it is: its `Serialize` is the
//! page's JSON.

use restauro_farm::farm::WorkerStatus;
use serde::Serialize;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorkerView {
    /// A string: JSON numbers lose integers above 2^53.
    pub id: String,
    pub name: String,
    pub capacity: u32,
    pub leases: u32,
    pub tiles_done: u64,
    pub tiles_failed: u64,
    pub last_seen_s: f64,
    pub build: String,
}

impl WorkerView {
    /// The same worker doing the same: what an event is sent for (not its heartbeat's age).
    pub fn same_as(&self, other: &WorkerView) -> bool {
        Self { last_seen_s: 0.0, ..self.clone() } == Self { last_seen_s: 0.0, ..other.clone() }
    }
}

impl From<WorkerStatus> for WorkerView {
    fn from(w: WorkerStatus) -> Self {
        Self {
            id: w.id.to_string(),
            name: w.name,
            capacity: w.capacity,
            leases: w.leases,
            tiles_done: w.done,
            tiles_failed: w.failed,
            last_seen_s: w.last_seen_s,
            build: w.build,
        }
    }
}
