//! What the studio's JSON says of a job and a worker: converted once, here, from the domain's
//! types (the gRPC door converts the same types to its messages in `grpc.rs`).

use restauro_farm::farm::WorkerStatus;
use restauro_farm::job::JobStatus;
use serde::Serialize;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JobView {
    pub id: String,
    pub name: String,
    /// `queued`, `running`, `assembling`, `post-processing`, `done`, `failed` or `cancelled`.
    pub state: String,
    pub finished: bool,
    pub tiles_total: u32,
    pub tiles_done: u32,
    pub tiles_leased: u32,
    pub tiles_requeued: u32,
    pub error: String,
    pub priority: i32,
    pub width: u32,
    pub height: u32,
    pub elapsed_s: f64,
    pub results: Vec<String>,
}

impl From<JobStatus> for JobView {
    fn from(s: JobStatus) -> Self {
        Self {
            id: s.id.to_string(),
            name: s.name,
            state: s.state.to_string(),
            finished: s.state.is_final(),
            tiles_total: s.tiles_total,
            tiles_done: s.tiles_done,
            tiles_leased: s.tiles_leased,
            tiles_requeued: s.tiles_requeued,
            error: s.error,
            priority: s.priority,
            width: s.width,
            height: s.height,
            elapsed_s: s.elapsed_s,
            results: s.results,
        }
    }
}

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
