//! The studio's live events, sent as Server-Sent Events (WHATWG HTML §9.2): `job` (a job's
//! status, at each change: state, tiles done), `job-gone`, `worker` (a worker registered or
//! changed what it does), `worker-gone`, and `snapshot` (every job and worker, sent first).
//!
//! One pump diffs the farm's jobs and workers at every change of a job and once a second (a
//! worker's heartbeat bumps nothing) and appends what changed to a ring of the last
//! [`KEPT`] events. Each event's id is `<epoch>-<seq>`, the epoch random per coordinator
//! process: a page that reconnects with `Last-Event-ID` is sent what it missed while that is still
//! in the ring and the coordinator is the same, else a fresh `snapshot`.

use super::views::WorkerView;
use restauro_farm::farm::Farm;
use restauro_farm::job::JobStatus;
use serde::Serialize;
use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::broadcast;

/// Events kept for reconnecting pages.
pub const KEPT: usize = 4096;

#[derive(Clone, Debug)]
pub struct Event {
    /// Its place in the log (none for a snapshot taken before any event).
    pub seq: Option<u64>,
    pub kind: &'static str,
    /// The event's JSON.
    pub data: String,
}

#[derive(Default)]
struct Log {
    ring: VecDeque<Arc<Event>>,
    next: u64,
    jobs: BTreeMap<String, JobStatus>,
    workers: BTreeMap<String, WorkerView>,
}

#[derive(Serialize)]
struct Snapshot<'a> {
    jobs: Vec<&'a JobStatus>,
    workers: Vec<&'a WorkerView>,
}

#[derive(Serialize)]
struct Gone<'a> {
    id: &'a str,
}

/// What a page is sent when it connects: `first`, then every event from `from_seq` on.
pub struct Start {
    pub first: Vec<Arc<Event>>,
    pub from_seq: u64,
}

pub struct Events {
    epoch: String,
    log: Mutex<Log>,
    tx: broadcast::Sender<Arc<Event>>,
}

impl Events {
    pub fn new() -> Arc<Self> {
        let epoch = uuid::Uuid::new_v4().simple().to_string()[..12].to_owned();
        Arc::new(Self { epoch, log: Mutex::new(Log::default()), tx: broadcast::channel(KEPT).0 })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Log> {
        self.log.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// An event's `id:` field (`<epoch>-none` before any event: no id a reconnect can use).
    pub fn id(&self, event: &Event) -> String {
        match event.seq {
            Some(seq) => format!("{}-{seq}", self.epoch),
            None => format!("{}-none", self.epoch),
        }
    }

    /// New events from now on; subscribe before [`Events::start`], so that nothing falls
    /// between the two (events up to the start's are skipped by sequence).
    pub fn subscribe(&self) -> broadcast::Receiver<Arc<Event>> {
        self.tx.subscribe()
    }

    /// What a page that last saw `last_event_id` needs first.
    pub fn start(&self, last_event_id: Option<&str>) -> Start {
        let log = self.lock();
        let from_seq = log.next;
        let seen = last_event_id
            .and_then(|id| id.strip_prefix(&self.epoch)?.strip_prefix('-')?.parse::<u64>().ok())
            .filter(|&seq| seq < from_seq);
        if let Some(seen) = seen {
            let oldest = log.ring.front().and_then(|e| e.seq).unwrap_or(from_seq);
            if seen + 1 >= oldest {
                let first = log.ring.iter().filter(|e| e.seq > Some(seen)).cloned().collect();
                return Start { first, from_seq };
            }
        }
        let snapshot =
            Snapshot { jobs: log.jobs.values().collect(), workers: log.workers.values().collect() };
        let data = serde_json::to_string(&snapshot).unwrap_or_default();
        // The snapshot stands for every event before `from_seq`: it takes the last one's id.
        let seq = from_seq.checked_sub(1);
        Start { first: vec![Arc::new(Event { seq, kind: "snapshot", data })], from_seq }
    }

    /// Brings the log up to date with the farm, appending an event for each change.
    pub fn update(&self, farm: &Farm) {
        let jobs: BTreeMap<String, JobStatus> =
            farm.jobs().into_iter().map(|s| (s.id.to_string(), s)).collect();
        let workers: BTreeMap<String, WorkerView> =
            farm.workers().into_iter().map(|w| (w.id.to_string(), WorkerView::from(w))).collect();
        let mut log = self.lock();
        let mut out: Vec<(&'static str, String)> = Vec::new();
        for (id, job) in &jobs {
            if log.jobs.get(id) != Some(job) {
                out.push(("job", serde_json::to_string(job).unwrap_or_default()));
            }
        }
        for id in log.jobs.keys().filter(|id| !jobs.contains_key(*id)) {
            out.push(("job-gone", serde_json::to_string(&Gone { id }).unwrap_or_default()));
        }
        for (id, w) in &workers {
            if !log.workers.get(id).is_some_and(|old| old.same_as(w)) {
                out.push(("worker", serde_json::to_string(w).unwrap_or_default()));
            }
        }
        for id in log.workers.keys().filter(|id| !workers.contains_key(*id)) {
            out.push(("worker-gone", serde_json::to_string(&Gone { id }).unwrap_or_default()));
        }
        log.jobs = jobs;
        log.workers = workers;
        for (kind, data) in out {
            let event = Arc::new(Event { seq: Some(log.next), kind, data });
            log.next += 1;
            if log.ring.len() == KEPT {
                log.ring.pop_front();
            }
            log.ring.push_back(event.clone());
            // No page listening is no error.
            let _ = self.tx.send(event);
        }
    }

    /// Keeps the log up to date until `stop` resolves.
    pub async fn pump(self: Arc<Self>, farm: Arc<Farm>, stop: impl Future<Output = ()>) {
        let mut changes = farm.changes();
        let mut tick = tokio::time::interval(Duration::from_secs(1));
        tokio::pin!(stop);
        loop {
            self.update(&farm);
            tokio::select! {
                _ = &mut stop => return,
                r = changes.changed() => if r.is_err() { return },
                _ = tick.tick() => {}
            }
        }
    }
}
