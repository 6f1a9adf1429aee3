//! Tile scheduler of the restauro coordinator: render jobs are split into tiles, and tiles are
//! leased to workers.
//!
//! The scheduler is pure, in-memory, synchronous and deterministic: it does no I/O, spawns
//! nothing and never reads a clock. Every method that depends on time takes `now` explicitly,
//! so the coordinator drives it from its event loop (calling [`Scheduler::expire`] when the
//! instant returned by [`Scheduler::next_deadline`] arrives) and tests can move time at will.
//!
//! # Scheduling policy
//!
//! * **Priority.** Running jobs of higher priority are always served before jobs of lower
//!   priority.
//! * **Fairness.** Among running jobs of equal priority, the next tile goes to the job with the
//!   fewest tiles currently leased; ties go to the older job (the one added first). The rule is
//!   applied tile by tile, so one [`Scheduler::lease`] call may spread its tiles over several
//!   jobs. This keeps equal-priority jobs progressing together instead of one starving the rest.
//! * **Order within a job.** Tiles go out in ascending index order, except that requeued tiles
//!   (expired, failed, handed back, or lost with a worker) go first, lowest index first: they are
//!   the ones holding up assembly of the final image.
//! * **Exclusion.** A worker that explicitly failed [`Config::max_worker_failures`] tiles of one
//!   job gets no more tiles of that job (it is probably missing an asset or a plugin). If only
//!   such jobs have queued tiles, it gets nothing; the tiles wait for another worker. The job is
//!   never failed merely because no current worker may take its tiles: a new worker may come.
//! * **Tile failure.** A tile that explicitly failed on [`Config::max_tile_failures`] *distinct*
//!   workers fails its whole job with `"tile N failed on K workers: <last reason>"`: the scene
//!   itself is broken, retrying elsewhere would waste the farm. The same worker failing a tile
//!   twice counts once for the tile. Expiry and worker loss never count as failures.
//! * **Staleness.** Only the current lease of a tile counts. Completing or failing a lease of an
//!   unknown, cancelled, failed or finished job, a lease whose attempt is not the tile's current
//!   one (e.g. a late result after expiry), a tile already done or being committed, or a lease
//!   held by another worker is answered `Stale` and changes nothing. This keeps the outcome
//!   independent of message races and trivially deterministic. The one exception is a result
//!   of a lease an earlier run of the coordinator granted ([`Scheduler::complete_inherited`]):
//!   no lease of this run names it, so it is taken for any tile not yet done or committing.
//! * **Commit.** An accepted result is not yet done: the tile is *committing* until the store
//!   has it ([`Scheduler::committed`]); meanwhile it takes no other result, has no deadline and
//!   is not leased. A commit that fails gives the lease back to its worker, which sends the same
//!   result again ([`Scheduler::commit_failed`]). A job is finished when every tile is done, so
//!   its assembly never finds a tile missing from the store.
//!
//! # Time
//!
//! A lease expires at `leased_at + lease_timeout`, a worker is lost at
//! `last_seen + heartbeat_timeout`; `expire(now)` acts on every deadline `<= now`. Any call made
//! on behalf of a worker (register, heartbeat, lease, complete, fail, give back) counts as
//! hearing from it. `now` values passed for a worker never move its `last_seen` backwards.
//!
//! # Cost
//!
//! The hot path (`lease` + `complete` + `committed`) is O(log n) per tile: queued tiles are a cursor over
//! never-leased tiles plus an ordered set of requeued ones, the current lease of every tile is
//! stored in the job's tile table, every worker keeps the set of its leases, and lease and
//! heartbeat deadlines live in ordered sets that are updated eagerly, so
//! [`Scheduler::next_deadline`] is exact and `expire` only touches what is due. Choosing the job
//! walks an ordered set of the running jobs that have queued tiles (only jobs excluding the
//! worker are skipped). Only the rare whole-job operations (`add_job`, `cancel`, a job failing,
//! `remove_job`) are O(tiles). Hashing uses a small Fx-style hasher: keys are either
//! scheduler-assigned integers or job ids chosen by the coordinator, so flooding resistance is
//! not needed and SipHash would be a large part of the per-tile cost.
//!
//! [`Lease::job`] is a [`JobId`] (an `Arc<str>` inside) rather than a `String` so handing out a lease costs a
//! reference-count increment instead of an allocation.

use std::cmp::Reverse;
use std::collections::{BTreeSet, HashMap, HashSet};
use std::fmt;
use std::hash::{BuildHasherDefault, Hasher};
use std::time::{Duration, Instant};

pub use crate::ids::{JobId, WorkerId};

/// Permission for one worker to render one tile.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Lease {
    /// The job id; shared with the scheduler (an `Arc<str>` inside) to keep leasing
    /// allocation-free.
    pub job: JobId,
    /// Tile index, `0..tiles`.
    pub tile: u32,
    /// 1 for a tile's first lease, one more on every re-lease of that tile. Only the latest
    /// attempt is accepted back.
    pub attempt: u32,
    /// The worker holding the lease.
    pub worker: WorkerId,
}

/// Timeouts and failure thresholds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Config {
    /// A lease not completed within this is expired and its tile requeued.
    pub lease_timeout: Duration,
    /// A worker not heard from within this is removed and its leases requeued.
    pub heartbeat_timeout: Duration,
    /// A tile that explicitly failed on this many distinct workers fails its job. 0 disables.
    pub max_tile_failures: u32,
    /// A worker that failed this many tiles of one job gets no more tiles of it. 0 disables.
    pub max_worker_failures: u32,
}

impl Default for Config {
    /// 30 s lease timeout, 15 s heartbeat timeout, 3 distinct workers per tile, 2 failures per
    /// worker and job.
    fn default() -> Self {
        Config {
            lease_timeout: Duration::from_secs(30),
            heartbeat_timeout: Duration::from_secs(15),
            max_tile_failures: 3,
            max_worker_failures: 2,
        }
    }
}

/// Outcome of [`Scheduler::complete`] and [`Scheduler::complete_inherited`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Completion {
    /// The result is the tile's: store it, then call [`Scheduler::committed`] (or
    /// [`Scheduler::commit_failed`]). No other result of the tile is accepted meanwhile.
    Accepted,
    /// The result must be dropped (see the module doc on staleness).
    Stale,
}

/// Outcome of [`Scheduler::fail`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Failure {
    /// The tile went back to the queue.
    Requeued,
    /// The tile reached its failure limit; the job is now failed with this reason.
    JobFailed { reason: String },
    /// The report was dropped (see the module doc on staleness).
    Stale,
}

/// Whether a job's tiles are still handed out. (The job's own lifecycle — queued, running,
/// assembling, … — is the coordinator's `job::JobState`; this is only the scheduler's part.)
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Dispatch {
    /// Tiles are leased and results accepted.
    Running,
    /// Every tile is done and committed.
    Finished,
    Failed(String),
    Cancelled,
}

/// Snapshot of a job's progress.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JobProgress {
    pub total: u32,
    pub done: u32,
    /// Tiles currently leased (always 0 once the job is no longer running).
    pub leased: u32,
    /// Tiles neither done, being committed, nor leased.
    pub queued: u32,
    /// Times any tile went back to the queue (expiry, worker loss, failure, give back).
    pub requeued: u32,
    pub state: Dispatch,
}

/// Snapshot of a registered worker.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WorkerInfo {
    pub id: WorkerId,
    pub name: String,
    /// As reported at registration; informational, `lease`'s `max` is what limits a call.
    pub capacity: u32,
    /// Leases currently held.
    pub leases: u32,
    pub done: u64,
    pub failed: u64,
    pub last_seen: Instant,
}

/// Why [`Scheduler::add_job`] refused a job.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AddJobError {
    /// A job with this id is already known (running or not): ids must be unique.
    Duplicate(JobId),
    /// A `done` tile index is not below the job's tile count.
    TileOutOfRange { tile: u32, tiles: u32 },
}

impl fmt::Display for AddJobError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AddJobError::Duplicate(id) => write!(f, "job {id} already exists"),
            AddJobError::TileOutOfRange { tile, tiles } => {
                write!(f, "done tile {tile} out of range for a job of {tiles} tiles")
            }
        }
    }
}

impl std::error::Error for AddJobError {}

/// Fx-style multiplicative hasher (as used in rustc). See the module doc for why not SipHash.
#[derive(Default, Clone, Copy)]
struct FxHasher {
    hash: u64,
}

impl FxHasher {
    const SEED: u64 = 0x51_7c_c1_b7_27_22_0a_95;

    #[inline]
    fn add(&mut self, word: u64) {
        self.hash = (self.hash.rotate_left(5) ^ word).wrapping_mul(Self::SEED);
    }
}

impl Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for chunk in &mut chunks {
            let mut word = [0u8; 8];
            word.copy_from_slice(chunk);
            self.add(u64::from_le_bytes(word));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut word = [0u8; 8];
            word[..rest.len()].copy_from_slice(rest);
            self.add(u64::from_le_bytes(word));
        }
    }

    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.add(u64::from(i));
    }

    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.add(u64::from(i));
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }

    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.hash
    }
}

type FxBuild = BuildHasherDefault<FxHasher>;
type FxMap<K, V> = HashMap<K, V, FxBuild>;
type FxSet<K> = HashSet<K, FxBuild>;

/// Index of a job in `Scheduler::jobs`; reused after `remove_job`, never exposed.
type Slot = u32;

/// Order of running jobs with queued tiles: priority descending, then fewest leased, then oldest.
type ReadyKey = (Reverse<i32>, u32, u64, Slot);

/// One key for (job slot, tile) in a worker's lease set.
fn pack(slot: Slot, tile: u32) -> u64 {
    (u64::from(slot) << 32) | u64::from(tile)
}

fn unpack(key: u64) -> (Slot, u32) {
    ((key >> 32) as u32, key as u32)
}

/// A tile's life: queued → leased → committing → done; back to queued when a lease expires, is
/// failed or handed back, or its worker is lost, and when a commit fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TileState {
    Queued,
    /// The current lease: holder and expiry (the attempt is `Tile::attempt`).
    Leased {
        worker: WorkerId,
        deadline: Instant,
    },
    /// A result was accepted and is being written to the store; nothing else is accepted for
    /// the tile until the write ends.
    Committing,
    Done,
}

#[derive(Clone, Debug)]
struct Tile {
    state: TileState,
    /// Attempt number of the latest lease; 0 before the first one.
    attempt: u32,
    /// Distinct workers that explicitly failed this tile (usually empty, so no allocation).
    failed_on: Vec<WorkerId>,
}

struct Job {
    id: JobId,
    /// Order of addition, for the "older job first" tie-break.
    seq: u64,
    priority: i32,
    total: u32,
    /// Per-tile state while running; emptied once the job ends, to give the memory back.
    tiles: Vec<Tile>,
    /// Requeued tiles, served before fresh ones.
    requeue: BTreeSet<u32>,
    /// Every tile below the cursor has been leased at least once or was done at resume; above it
    /// tiles are fresh (queued) or done at resume. Only moves forward, so fresh-tile lookup is
    /// amortised O(1).
    cursor: u32,
    done: u32,
    /// Tiles accepted and being committed.
    committing: u32,
    leased: u32,
    queued: u32,
    requeued: u32,
    state: Dispatch,
    /// Explicit failures per worker, for exclusion.
    worker_failures: FxMap<WorkerId, u32>,
}

impl Job {
    /// Key in the ready set, if the job belongs there (running with queued tiles).
    fn ready_key(&self, slot: Slot) -> Option<ReadyKey> {
        (self.state == Dispatch::Running && self.queued > 0).then_some((
            Reverse(self.priority),
            self.leased,
            self.seq,
            slot,
        ))
    }

    fn excludes(&self, worker: WorkerId, max_worker_failures: u32) -> bool {
        max_worker_failures != 0
            && self.worker_failures.get(&worker).is_some_and(|&n| n >= max_worker_failures)
    }

    /// Next tile to lease: lowest requeued tile, else lowest fresh tile.
    fn pop_queued(&mut self) -> Option<u32> {
        if let Some(tile) = self.requeue.pop_first() {
            return Some(tile);
        }
        while self.cursor < self.total {
            let tile = self.cursor;
            self.cursor += 1;
            if self.tiles[tile as usize].state == TileState::Queued {
                return Some(tile);
            }
        }
        None
    }
}

struct Worker {
    name: String,
    capacity: u32,
    /// Current leases as `pack(slot, tile)`.
    leases: FxSet<u64>,
    done: u64,
    failed: u64,
    last_seen: Instant,
}

/// Moves a job within the ready set after its key changed.
fn reindex(ready: &mut BTreeSet<ReadyKey>, before: Option<ReadyKey>, after: Option<ReadyKey>) {
    if before != after {
        if let Some(key) = before {
            ready.remove(&key);
        }
        if let Some(key) = after {
            ready.insert(key);
        }
    }
}

/// Counts since the scheduler started, for the metrics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Totals {
    /// Leases granted.
    pub leased: u64,
    /// Tiles completed (current leases only; stale reports are not counted).
    pub done: u64,
    /// Tiles put back in their queue: expired, failed, handed back, or lost with a worker.
    pub requeued: u64,
    /// Leases that ran past the lease timeout.
    pub lease_expiries: u64,
    /// Workers dropped for silence past the heartbeat timeout.
    pub workers_lost: u64,
}

/// The scheduler's state at one instant, for the metrics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Gauges {
    /// Tiles waiting for a lease, over all running jobs.
    pub queued: u64,
    /// Tiles leased and not yet reported.
    pub leased: u64,
    pub workers: u64,
}

/// The coordinator's tile scheduler. See the module documentation for the policy.
pub struct Scheduler {
    config: Config,
    totals: Totals,
    jobs: Vec<Option<Job>>,
    free_slots: Vec<Slot>,
    by_id: FxMap<JobId, Slot>,
    next_seq: u64,
    /// Running jobs with queued tiles, in serving order.
    ready: BTreeSet<ReadyKey>,
    workers: FxMap<WorkerId, Worker>,
    next_worker: WorkerId,
    /// Deadline of every current lease.
    lease_deadlines: BTreeSet<(Instant, Slot, u32)>,
    /// `last_seen + heartbeat_timeout` of every registered worker.
    worker_deadlines: BTreeSet<(Instant, WorkerId)>,
}

impl Scheduler {
    pub fn new(config: Config) -> Self {
        Scheduler {
            config,
            totals: Totals::default(),
            jobs: Vec::new(),
            free_slots: Vec::new(),
            by_id: FxMap::default(),
            next_seq: 0,
            ready: BTreeSet::new(),
            workers: FxMap::default(),
            next_worker: WorkerId(1),
            lease_deadlines: BTreeSet::new(),
            worker_deadlines: BTreeSet::new(),
        }
    }

    pub fn config(&self) -> &Config {
        &self.config
    }

    fn job(&self, slot: Slot) -> &Job {
        self.jobs[slot as usize].as_ref().expect("slot refers to a live job")
    }

    fn job_mut(&mut self, slot: Slot) -> &mut Job {
        self.jobs[slot as usize].as_mut().expect("slot refers to a live job")
    }

    /// Adds a job of `tiles` tiles numbered `0..tiles`, of which `done` are already finished (a
    /// restarted coordinator resumes a job; duplicates in `done` are ignored). A job with nothing
    /// left to do is `Finished` at once. `now` is accepted for symmetry with the other calls.
    pub fn add_job(
        &mut self,
        job: JobId,
        priority: i32,
        tiles: u32,
        done: &[u32],
        _now: Instant,
    ) -> Result<(), AddJobError> {
        if self.by_id.contains_key(&job) {
            return Err(AddJobError::Duplicate(job));
        }
        if let Some(&tile) = done.iter().find(|&&t| t >= tiles) {
            return Err(AddJobError::TileOutOfRange { tile, tiles });
        }
        let fresh = Tile { state: TileState::Queued, attempt: 0, failed_on: Vec::new() };
        let mut table = vec![fresh; tiles as usize];
        let mut done_count = 0;
        for &tile in done {
            let state = &mut table[tile as usize].state;
            if *state != TileState::Done {
                *state = TileState::Done;
                done_count += 1;
            }
        }
        let finished = done_count == tiles;
        let id = job;
        let slot = self.free_slots.pop().unwrap_or_else(|| {
            self.jobs.push(None);
            (self.jobs.len() - 1) as Slot
        });
        let entry = Job {
            id: id.clone(),
            seq: self.next_seq,
            priority,
            total: tiles,
            tiles: if finished { Vec::new() } else { table },
            requeue: BTreeSet::new(),
            cursor: 0,
            done: done_count,
            committing: 0,
            leased: 0,
            queued: tiles - done_count,
            requeued: 0,
            state: if finished { Dispatch::Finished } else { Dispatch::Running },
            worker_failures: FxMap::default(),
        };
        self.next_seq += 1;
        if let Some(key) = entry.ready_key(slot) {
            self.ready.insert(key);
        }
        self.jobs[slot as usize] = Some(entry);
        self.by_id.insert(id, slot);
        Ok(())
    }

    pub fn register_worker(&mut self, name: &str, capacity: u32, now: Instant) -> WorkerId {
        let id = self.next_worker;
        self.next_worker.0 += 1;
        self.workers.insert(
            id,
            Worker {
                name: name.to_owned(),
                capacity,
                leases: FxSet::default(),
                done: 0,
                failed: 0,
                last_seen: now,
            },
        );
        self.worker_deadlines.insert((now + self.config.heartbeat_timeout, id));
        id
    }

    /// Records that `worker` is alive. Returns false for an unknown (e.g. timed out) worker,
    /// which must register again.
    pub fn heartbeat(&mut self, worker: WorkerId, now: Instant) -> bool {
        self.touch(worker, now)
    }

    /// Marks the worker as heard from; false if unknown.
    fn touch(&mut self, worker: WorkerId, now: Instant) -> bool {
        let Some(w) = self.workers.get_mut(&worker) else {
            return false;
        };
        if now > w.last_seen {
            let timeout = self.config.heartbeat_timeout;
            self.worker_deadlines.remove(&(w.last_seen + timeout, worker));
            self.worker_deadlines.insert((now + timeout, worker));
            w.last_seen = now;
        }
        true
    }

    /// Removes a worker (disconnect); its leases go back to the queue and are returned, ordered
    /// by job slot and tile. Unknown workers yield nothing.
    pub fn remove_worker(&mut self, worker: WorkerId, _now: Instant) -> Vec<Lease> {
        let Some(w) = self.workers.remove(&worker) else {
            return Vec::new();
        };
        self.worker_deadlines.remove(&(w.last_seen + self.config.heartbeat_timeout, worker));
        let mut keys: Vec<u64> = w.leases.into_iter().collect();
        keys.sort_unstable();
        keys.into_iter()
            .map(|key| {
                let (slot, tile) = unpack(key);
                self.requeue(slot, tile)
            })
            .collect()
    }

    /// Up to `max` new leases for `worker`, chosen tile by tile by the policy in the module doc.
    /// Fewer or none when nothing it may take is queued; none for unknown workers.
    pub fn lease(&mut self, worker: WorkerId, max: u32, now: Instant) -> Vec<Lease> {
        if max == 0 || !self.touch(worker, now) {
            return Vec::new();
        }
        let deadline = now + self.config.lease_timeout;
        let max_worker_failures = self.config.max_worker_failures;
        let holder = self.workers.get_mut(&worker).expect("touched worker exists");
        let mut out = Vec::new();
        while (out.len() as u32) < max {
            let jobs = &self.jobs;
            let Some(key) = self
                .ready
                .iter()
                .find(|key| {
                    !jobs[key.3 as usize]
                        .as_ref()
                        .is_some_and(|job| job.excludes(worker, max_worker_failures))
                })
                .copied()
            else {
                break;
            };
            let slot = key.3;
            let job = self.jobs[slot as usize].as_mut().expect("ready job is live");
            let tile = job.pop_queued().expect("ready job has a queued tile");
            let entry = &mut job.tiles[tile as usize];
            entry.attempt += 1;
            entry.state = TileState::Leased { worker, deadline };
            let attempt = entry.attempt;
            job.queued -= 1;
            job.leased += 1;
            reindex(&mut self.ready, Some(key), job.ready_key(slot));
            self.lease_deadlines.insert((deadline, slot, tile));
            holder.leases.insert(pack(slot, tile));
            out.push(Lease { job: job.id.clone(), tile, attempt, worker });
        }
        self.totals.leased += out.len() as u64;
        out
    }

    /// The slot of the lease's job if `lease` is the current lease of a running job's tile.
    fn current(&self, lease: &Lease) -> Option<Slot> {
        let slot = *self.by_id.get(&*lease.job)?;
        let job = self.job(slot);
        if job.state != Dispatch::Running {
            return None;
        }
        let tile = job.tiles.get(lease.tile as usize)?;
        match tile.state {
            TileState::Leased { worker, .. }
                if worker == lease.worker && tile.attempt == lease.attempt =>
            {
                Some(slot)
            }
            _ => None,
        }
    }

    /// Accepts the lease's result: the tile is being committed, and no other result of it is
    /// accepted meanwhile. `Stale` (and nothing changes) unless it is the tile's current lease
    /// in a running job. The tile counts as done once [`Scheduler::committed`] is called.
    pub fn complete(&mut self, lease: &Lease, now: Instant) -> Completion {
        let Some(slot) = self.current(lease) else {
            return Completion::Stale;
        };
        self.touch(lease.worker, now);
        let before = self.job(slot).ready_key(slot);
        self.revoke(slot, lease.tile);
        let job = self.job_mut(slot);
        job.committing += 1;
        job.tiles[lease.tile as usize].state = TileState::Committing;
        let after = job.ready_key(slot);
        reindex(&mut self.ready, before, after);
        if let Some(w) = self.workers.get_mut(&lease.worker) {
            w.done += 1;
        }
        Completion::Accepted
    }

    /// Accepts a result whose lease a previous run of the coordinator granted (it cannot be
    /// checked against this run's leases, only against the store's signature; see the
    /// coordinator's `lease_ticket`): the tile is taken if it is neither done nor being
    /// committed, revoking this run's lease of it, if any (that result would be the same bytes:
    /// tiles are deterministic). `Stale` otherwise, or when the job is not running.
    pub fn complete_inherited(&mut self, job: &str, tile: u32) -> Completion {
        let Some(&slot) = self.by_id.get(job) else {
            return Completion::Stale;
        };
        let entry = self.job(slot);
        if entry.state != Dispatch::Running {
            return Completion::Stale;
        }
        let before = entry.ready_key(slot);
        match entry.tiles.get(tile as usize).map(|t| t.state) {
            Some(TileState::Leased { .. }) => {
                self.revoke(slot, tile);
            }
            Some(TileState::Queued) => {
                let job = self.job_mut(slot);
                job.requeue.remove(&tile);
                job.queued -= 1;
            }
            _ => return Completion::Stale,
        }
        let job = self.job_mut(slot);
        job.committing += 1;
        job.tiles[tile as usize].state = TileState::Committing;
        let after = job.ready_key(slot);
        reindex(&mut self.ready, before, after);
        Completion::Accepted
    }

    /// The accepted result of `tile` is durable: the tile is done. True when it was the job's
    /// last tile (the job is then `Finished`). False, and nothing changes, when the tile is not
    /// being committed (the job was cancelled or failed meanwhile).
    pub fn committed(&mut self, job: &str, tile: u32) -> bool {
        let Some(slot) = self.committing(job, tile) else {
            return false;
        };
        self.totals.done += 1;
        let job = self.job_mut(slot);
        job.tiles[tile as usize].state = TileState::Done;
        job.committing -= 1;
        job.done += 1;
        let finished = job.done == job.total;
        if finished {
            job.state = Dispatch::Finished;
            job.tiles = Vec::new();
            job.requeue = BTreeSet::new();
            job.worker_failures = FxMap::default();
        }
        finished
    }

    /// The accepted result of `tile` could not be stored. With the `lease` it came with (and
    /// its worker still registered), the lease is given back to that worker with a new
    /// deadline, so the same result can be sent again once the store recovers; without (an
    /// earlier run's lease), the tile goes back to the queue. Either way it counts against
    /// nobody.
    pub fn commit_failed(&mut self, job: &str, tile: u32, lease: Option<&Lease>, now: Instant) {
        let Some(slot) = self.committing(job, tile) else {
            return;
        };
        let before = self.job(slot).ready_key(slot);
        let holder = lease.filter(|l| self.workers.contains_key(&l.worker));
        let deadline = now + self.config.lease_timeout;
        let job = self.jobs[slot as usize].as_mut().expect("committing job is live");
        job.committing -= 1;
        match holder {
            Some(l) if job.tiles[tile as usize].attempt == l.attempt => {
                job.tiles[tile as usize].state = TileState::Leased { worker: l.worker, deadline };
                job.leased += 1;
                self.lease_deadlines.insert((deadline, slot, tile));
                let w = self.workers.get_mut(&l.worker).expect("checked above");
                w.leases.insert(pack(slot, tile));
                w.done = w.done.saturating_sub(1);
            }
            _ => {
                job.tiles[tile as usize].state = TileState::Queued;
                job.queued += 1;
                job.requeued += 1;
                job.requeue.insert(tile);
                self.totals.requeued += 1;
            }
        }
        let after = self.job(slot).ready_key(slot);
        reindex(&mut self.ready, before, after);
    }

    /// The slot of a running job whose `tile` is being committed.
    fn committing(&self, job: &str, tile: u32) -> Option<Slot> {
        let slot = *self.by_id.get(job)?;
        let entry = self.job(slot);
        let state = entry.tiles.get(tile as usize)?.state;
        (entry.state == Dispatch::Running && state == TileState::Committing).then_some(slot)
    }

    /// Ends the current lease of a leased tile (its deadline and its holder's record of it),
    /// leaving the tile's state and the job's place in the ready set to the caller, which
    /// takes the job's ready key before and reindexes after. The revoked lease.
    fn revoke(&mut self, slot: Slot, tile: u32) -> Lease {
        let job = self.jobs[slot as usize].as_mut().expect("leased job is live");
        let entry = &mut job.tiles[tile as usize];
        let TileState::Leased { worker, deadline } = entry.state else {
            unreachable!("only leased tiles are revoked");
        };
        let attempt = entry.attempt;
        job.leased -= 1;
        self.lease_deadlines.remove(&(deadline, slot, tile));
        if let Some(w) = self.workers.get_mut(&worker) {
            w.leases.remove(&pack(slot, tile));
        }
        Lease { job: job.id.clone(), tile, attempt, worker }
    }

    /// Reports that the worker could not render the tile. The tile is requeued and counted
    /// against the worker (for exclusion) and the tile (for failing the job); see the module
    /// doc. `Stale` unless it is the tile's current lease in a running job.
    pub fn fail(&mut self, lease: &Lease, reason: &str, now: Instant) -> Failure {
        let Some(slot) = self.current(lease) else {
            return Failure::Stale;
        };
        self.touch(lease.worker, now);
        if let Some(w) = self.workers.get_mut(&lease.worker) {
            w.failed += 1;
        }
        self.requeue(slot, lease.tile);
        let max_tile_failures = self.config.max_tile_failures;
        let job = self.job_mut(slot);
        *job.worker_failures.entry(lease.worker).or_insert(0) += 1;
        let failed_on = &mut job.tiles[lease.tile as usize].failed_on;
        if !failed_on.contains(&lease.worker) {
            failed_on.push(lease.worker);
        }
        let distinct = failed_on.len() as u32;
        if max_tile_failures != 0 && distinct >= max_tile_failures {
            let reason = format!("tile {} failed on {distinct} workers: {reason}", lease.tile);
            self.abort_job(slot, Dispatch::Failed(reason.clone()));
            return Failure::JobFailed { reason };
        }
        Failure::Requeued
    }

    /// A draining worker hands back a lease it will not finish: the tile is requeued without
    /// counting as a failure. False (nothing changes) unless it is the tile's current lease.
    pub fn give_back(&mut self, lease: &Lease, now: Instant) -> bool {
        let Some(slot) = self.current(lease) else {
            return false;
        };
        self.touch(lease.worker, now);
        self.requeue(slot, lease.tile);
        true
    }

    /// Takes the current lease of a tile away and puts the tile at the head of its job's queue.
    /// Returns the revoked lease.
    fn requeue(&mut self, slot: Slot, tile: u32) -> Lease {
        let before = self.job(slot).ready_key(slot);
        let lease = self.revoke(slot, tile);
        let job = self.job_mut(slot);
        job.tiles[tile as usize].state = TileState::Queued;
        job.requeue.insert(tile);
        job.queued += 1;
        job.requeued += 1;
        let after = job.ready_key(slot);
        self.totals.requeued += 1;
        reindex(&mut self.ready, before, after);
        lease
    }

    /// Ends a running job: drops its outstanding leases (making them stale), leaves every
    /// unfinished tile counted as queued, and frees the tile table. O(tiles), once per job.
    fn abort_job(&mut self, slot: Slot, state: Dispatch) {
        let job = self.jobs[slot as usize].as_mut().expect("aborted job is live");
        if let Some(key) = job.ready_key(slot) {
            self.ready.remove(&key);
        }
        for (index, tile) in job.tiles.iter().enumerate() {
            if let TileState::Leased { worker, deadline } = tile.state {
                let index = index as u32;
                self.lease_deadlines.remove(&(deadline, slot, index));
                if let Some(w) = self.workers.get_mut(&worker) {
                    w.leases.remove(&pack(slot, index));
                }
            }
        }
        job.leased = 0;
        job.committing = 0;
        job.queued = job.total - job.done;
        job.tiles = Vec::new();
        job.requeue = BTreeSet::new();
        job.worker_failures = FxMap::default();
        job.state = state;
    }

    /// Expires leases past `lease_timeout` (requeueing their tiles) and then removes workers past
    /// `heartbeat_timeout` (requeueing their leases). Returns every lease revoked by this call:
    /// expired ones first, in deadline order, then those of lost workers.
    pub fn expire(&mut self, now: Instant) -> Vec<Lease> {
        let mut revoked = Vec::new();
        while let Some(&(deadline, slot, tile)) = self.lease_deadlines.first() {
            if deadline > now {
                break;
            }
            self.totals.lease_expiries += 1;
            revoked.push(self.requeue(slot, tile));
        }
        while let Some(&(deadline, worker)) = self.worker_deadlines.first() {
            if deadline > now {
                break;
            }
            self.totals.workers_lost += 1;
            revoked.extend(self.remove_worker(worker, now));
        }
        revoked
    }

    /// Cancels a running job: no more of its tiles are leased and its outstanding leases become
    /// stale. False if the job is unknown or not running.
    pub fn cancel(&mut self, job: &str) -> bool {
        match self.by_id.get(job) {
            Some(&slot) if self.job(slot).state == Dispatch::Running => {
                self.abort_job(slot, Dispatch::Cancelled);
                true
            }
            _ => false,
        }
    }

    /// Forgets a job entirely (cancelling it first if it is still running); its id may be
    /// reused afterwards.
    pub fn remove_job(&mut self, job: &str) {
        let Some(&slot) = self.by_id.get(job) else {
            return;
        };
        if self.job(slot).state == Dispatch::Running {
            self.abort_job(slot, Dispatch::Cancelled);
        }
        self.by_id.remove(job);
        self.jobs[slot as usize] = None;
        self.free_slots.push(slot);
    }

    /// Every tile of `job` below this has been leased at least once (or was done at resume).
    pub fn cursor(&self, job: &str) -> Option<u32> {
        Some(self.job(*self.by_id.get(job)?).cursor)
    }

    pub fn progress(&self, job: &str) -> Option<JobProgress> {
        let job = self.job(*self.by_id.get(job)?);
        Some(JobProgress {
            total: job.total,
            done: job.done,
            leased: job.leased,
            queued: job.queued,
            requeued: job.requeued,
            state: job.state.clone(),
        })
    }

    /// All registered workers, by id.
    pub fn workers(&self) -> Vec<WorkerInfo> {
        let mut out: Vec<WorkerInfo> = self
            .workers
            .iter()
            .map(|(&id, w)| WorkerInfo {
                id,
                name: w.name.clone(),
                capacity: w.capacity,
                leases: w.leases.len() as u32,
                done: w.done,
                failed: w.failed,
                last_seen: w.last_seen,
            })
            .collect();
        out.sort_unstable_by_key(|w| w.id);
        out
    }

    /// Counts since the scheduler started.
    pub fn totals(&self) -> Totals {
        self.totals
    }

    /// Tiles queued and leased, and workers registered, now.
    pub fn gauges(&self) -> Gauges {
        Gauges {
            queued: self.pending_tiles(),
            leased: self.lease_deadlines.len() as u64,
            workers: self.workers.len() as u64,
        }
    }

    /// Queued tiles over all running jobs (including tiles only excluded workers could take).
    pub fn pending_tiles(&self) -> u64 {
        self.ready.iter().map(|key| u64::from(self.job(key.3).queued)).sum()
    }

    /// The earliest instant at which [`Scheduler::expire`] would do something, if any: the
    /// next lease expiry or worker heartbeat timeout. Exact, because deadlines are kept eagerly.
    pub fn next_deadline(&self) -> Option<Instant> {
        let lease = self.lease_deadlines.first().map(|d| d.0);
        let worker = self.worker_deadlines.first().map(|d| d.0);
        match (lease, worker) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn secs(n: u64) -> Duration {
        Duration::from_secs(n)
    }

    fn setup() -> (Scheduler, Instant) {
        (Scheduler::new(Config::default()), Instant::now())
    }

    fn add(s: &mut Scheduler, id: &str, priority: i32, tiles: u32, now: Instant) {
        s.add_job(id.into(), priority, tiles, &[], now).unwrap();
    }

    /// Completes and commits a lease; true when it finished its job.
    fn finish(s: &mut Scheduler, l: &Lease, now: Instant) -> bool {
        assert_eq!(s.complete(l, now), Completion::Accepted, "{l:?}");
        s.committed(&l.job, l.tile)
    }

    fn tiles_of(leases: &[Lease]) -> Vec<(String, u32)> {
        leases.iter().map(|l| (l.job.to_string(), l.tile)).collect()
    }

    #[test]
    fn every_tile_leased_once_then_finished() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 10, t0);
        let w1 = s.register_worker("w1", 4, t0);
        let w2 = s.register_worker("w2", 4, t0);
        assert_eq!((w1, w2), (WorkerId(1), WorkerId(2)));
        let mut seen = HashSet::new();
        let mut finished = 0;
        let mut completions = 0;
        loop {
            let mut batch = s.lease(w1, 3, t0);
            batch.extend(s.lease(w2, 3, t0));
            if batch.is_empty() {
                break;
            }
            for l in &batch {
                assert_eq!(l.attempt, 1);
                assert!(seen.insert(l.tile), "tile {} leased twice", l.tile);
            }
            for l in &batch {
                completions += 1;
                if finish(&mut s, l, t0) {
                    finished += 1;
                    assert_eq!(completions, 10);
                }
            }
        }
        assert_eq!(seen, (0..10).collect());
        assert_eq!(finished, 1);
        let p = s.progress("a").unwrap();
        assert_eq!((p.done, p.leased, p.queued, p.requeued), (10, 0, 0, 0));
        assert_eq!(p.state, Dispatch::Finished);
        assert_eq!(s.pending_tiles(), 0);
        let done: u64 = s.workers().iter().map(|w| w.done).sum();
        assert_eq!(done, 10);
    }

    /// The metrics' totals and gauges follow leases, completions, expiries and lost workers.
    #[test]
    fn totals_and_gauges_count_what_happened() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 5, t0);
        let w1 = s.register_worker("w1", 8, t0);
        let w2 = s.register_worker("w2", 8, t0);
        let first = s.lease(w1, 2, t0);
        let second = s.lease(w2, 1, t0);
        assert_eq!(s.gauges(), Gauges { queued: 2, leased: 3, workers: 2 });
        finish(&mut s, &first[0], t0);
        // Past the lease timeout: w1's other lease and w2's lease expire, and w1, silent since
        // the start, is dropped; w2 heartbeats just before.
        let later = t0 + s.config().lease_timeout.max(s.config().heartbeat_timeout) + secs(1);
        s.heartbeat(w2, later);
        assert_eq!(s.expire(later).len(), 2);
        let t = s.totals();
        let counts = (t.leased, t.done, t.lease_expiries, t.requeued, t.workers_lost);
        assert_eq!(counts, (3, 1, 2, 2, 1));
        assert_eq!(s.gauges(), Gauges { queued: 4, leased: 0, workers: 1 });
        // A late report of an expired lease is stale and not counted as done.
        assert_eq!(s.complete(&second[0], later), Completion::Stale);
        assert_eq!(s.totals().done, 1);
    }

    #[test]
    fn higher_priority_first() {
        let (mut s, t0) = setup();
        add(&mut s, "low", 0, 3, t0);
        add(&mut s, "high", 5, 2, t0);
        let w = s.register_worker("w", 8, t0);
        let got = tiles_of(&s.lease(w, 3, t0));
        assert_eq!(got, vec![("high".into(), 0), ("high".into(), 1), ("low".into(), 0)]);
    }

    #[test]
    fn equal_priority_jobs_interleave() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 1, 10, t0);
        add(&mut s, "b", 1, 10, t0);
        let w1 = s.register_worker("w1", 8, t0);
        let w2 = s.register_worker("w2", 8, t0);
        let got = tiles_of(&s.lease(w1, 4, t0));
        assert_eq!(got, vec![("a".into(), 0), ("b".into(), 0), ("a".into(), 1), ("b".into(), 1)]);
        // Completing two of a's tiles makes it the job with fewer leased tiles.
        let first = s.lease(w2, 1, t0);
        assert_eq!(tiles_of(&first), vec![("a".into(), 2)]);
        s.complete(&first[0], t0);
        let more = s.lease(w2, 2, t0);
        assert_eq!(tiles_of(&more), vec![("a".into(), 3), ("b".into(), 2)]);
    }

    #[test]
    fn expired_lease_is_requeued_and_old_completion_is_stale() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 2, t0);
        let w = s.register_worker("w", 1, t0);
        let old = s.lease(w, 1, t0).remove(0);
        assert_eq!((old.tile, old.attempt), (0, 1));
        assert!(s.heartbeat(w, t0 + secs(10)));
        assert!(s.heartbeat(w, t0 + secs(20)));
        assert!(s.expire(t0 + secs(29)).is_empty());
        assert_eq!(s.expire(t0 + secs(30)), vec![old.clone()]);
        let p = s.progress("a").unwrap();
        assert_eq!((p.leased, p.queued, p.requeued), (0, 2, 1));
        // The requeued tile goes before the fresh tile 1.
        let new = s.lease(w, 1, t0 + secs(30)).remove(0);
        assert_eq!((new.tile, new.attempt), (0, 2));
        assert_eq!(s.complete(&old, t0 + secs(31)), Completion::Stale);
        assert_eq!(s.complete(&new, t0 + secs(31)), Completion::Accepted);
        assert!(!s.committed(&new.job, new.tile));
        assert_eq!(s.progress("a").unwrap().done, 1);
    }

    #[test]
    fn heartbeat_timeout_removes_worker_and_requeues() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 1, t0);
        let w1 = s.register_worker("w1", 1, t0);
        let lost = s.lease(w1, 1, t0 + secs(1)).remove(0);
        let w2 = s.register_worker("w2", 1, t0 + secs(10));
        assert!(s.expire(t0 + secs(15)).is_empty());
        assert_eq!(s.expire(t0 + secs(16)), vec![lost.clone()]);
        assert!(!s.heartbeat(w1, t0 + secs(17)));
        assert!(s.lease(w1, 1, t0 + secs(17)).is_empty());
        assert_eq!(s.workers().iter().map(|w| w.id).collect::<Vec<_>>(), [w2]);
        let again = s.lease(w2, 1, t0 + secs(17)).remove(0);
        assert_eq!((again.tile, again.attempt, again.worker), (0, 2, w2));
        assert_eq!(s.complete(&lost, t0 + secs(18)), Completion::Stale);
        assert_eq!(s.progress("a").unwrap().requeued, 1);
    }

    #[test]
    fn duplicate_completion_is_stale() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 2, t0);
        let w = s.register_worker("w", 1, t0);
        let l = s.lease(w, 1, t0).remove(0);
        assert!(!finish(&mut s, &l, t0));
        assert_eq!(s.complete(&l, t0), Completion::Stale);
        assert_eq!(s.progress("a").unwrap().done, 1);
        assert_eq!(s.workers()[0].done, 1);
        // Someone else's lease, or an unknown job, is stale too.
        let l2 = s.lease(w, 1, t0).remove(0);
        let forged = Lease { worker: WorkerId(99), ..l2.clone() };
        assert_eq!(s.complete(&forged, t0), Completion::Stale);
        let unknown = Lease { job: "zz".into(), ..l2 };
        assert_eq!(s.complete(&unknown, t0), Completion::Stale);
    }

    #[test]
    fn tile_failing_on_three_distinct_workers_fails_job() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 2, t0);
        let w1 = s.register_worker("w1", 1, t0);
        let w2 = s.register_worker("w2", 1, t0);
        let w3 = s.register_worker("w3", 1, t0);
        let w4 = s.register_worker("w4", 1, t0);
        let l = s.lease(w1, 1, t0).remove(0);
        assert_eq!(l.tile, 0);
        assert_eq!(s.fail(&l, "boom", t0), Failure::Requeued);
        // Same worker, same tile again: counts once for the tile.
        let l = s.lease(w1, 1, t0).remove(0);
        assert_eq!((l.tile, l.attempt), (0, 2));
        assert_eq!(s.fail(&l, "boom", t0), Failure::Requeued);
        assert_eq!(s.fail(&l, "boom", t0), Failure::Stale);
        let l = s.lease(w2, 1, t0).remove(0);
        assert_eq!((l.tile, l.attempt), (0, 3));
        assert_eq!(s.fail(&l, "bad", t0), Failure::Requeued);
        let other = s.lease(w4, 1, t0).remove(0);
        assert_eq!(other.tile, 0);
        assert!(s.give_back(&other, t0));
        let other = s.lease(w4, 2, t0);
        assert_eq!(other.iter().map(|l| l.tile).collect::<Vec<_>>(), [0, 1]);
        // Tile 0 has now failed on w1, w2 and w4 -> the job fails, with the last reason.
        let reason = "tile 0 failed on 3 workers: meh".to_owned();
        assert_eq!(s.fail(&other[0], "meh", t0), Failure::JobFailed { reason: reason.clone() });
        let p = s.progress("a").unwrap();
        assert_eq!(p.state, Dispatch::Failed(reason));
        assert_eq!(s.complete(&other[1], t0), Completion::Stale);
        assert!(s.lease(w3, 1, t0).is_empty());
        assert_eq!(s.pending_tiles(), 0);
        assert!(s.workers().iter().all(|w| w.leases == 0));
        assert_eq!(s.workers()[0].failed, 2);
    }

    #[test]
    fn failure_reason_reported_on_the_failing_call() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 1, t0);
        let ws: Vec<_> = (0..3).map(|i| s.register_worker(&format!("w{i}"), 1, t0)).collect();
        let mut results = Vec::new();
        for &w in &ws {
            let l = s.lease(w, 1, t0).remove(0);
            results.push(s.fail(&l, &format!("err{w}"), t0));
        }
        assert_eq!(
            results,
            vec![
                Failure::Requeued,
                Failure::Requeued,
                Failure::JobFailed { reason: "tile 0 failed on 3 workers: err3".into() }
            ]
        );
        assert_eq!(s.next_deadline(), Some(t0 + secs(15)));
    }

    #[test]
    fn excluded_worker_still_gets_other_jobs() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 1, 10, t0);
        add(&mut s, "b", 0, 10, t0);
        let w1 = s.register_worker("w1", 4, t0);
        let w2 = s.register_worker("w2", 4, t0);
        let ls = s.lease(w1, 2, t0);
        assert_eq!(tiles_of(&ls), vec![("a".into(), 0), ("a".into(), 1)]);
        assert_eq!(s.fail(&ls[0], "missing texture", t0), Failure::Requeued);
        assert_eq!(s.fail(&ls[1], "missing texture", t0), Failure::Requeued);
        // w1 is excluded from a: it gets b's tiles although a has higher priority.
        assert_eq!(tiles_of(&s.lease(w1, 2, t0)), vec![("b".into(), 0), ("b".into(), 1)]);
        // w2 is not: it gets a's requeued tiles first.
        assert_eq!(tiles_of(&s.lease(w2, 2, t0)), vec![("a".into(), 0), ("a".into(), 1)]);
        s.cancel("b");
        // Only a has queued tiles now: w1 gets nothing, and a keeps waiting, not failed.
        assert!(s.lease(w1, 2, t0).is_empty());
        let p = s.progress("a").unwrap();
        assert_eq!((p.state, p.queued, p.leased), (Dispatch::Running, 8, 2));
        assert_eq!(s.pending_tiles(), 8);
    }

    #[test]
    fn cancel_stales_leases_and_stops_leasing() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 5, t0);
        let w = s.register_worker("w", 2, t0);
        let ls = s.lease(w, 2, t0);
        assert!(s.cancel("a"));
        assert!(!s.cancel("a"));
        assert!(!s.cancel("nope"));
        assert_eq!(s.complete(&ls[0], t0), Completion::Stale);
        assert_eq!(s.fail(&ls[1], "x", t0), Failure::Stale);
        assert!(!s.give_back(&ls[1], t0));
        assert!(s.lease(w, 2, t0).is_empty());
        assert_eq!(s.pending_tiles(), 0);
        assert_eq!(s.workers()[0].leases, 0);
        let p = s.progress("a").unwrap();
        assert_eq!((p.state, p.done, p.leased, p.queued), (Dispatch::Cancelled, 0, 0, 5));
        // No lease deadline is left behind; only the worker's heartbeat.
        assert_eq!(s.next_deadline(), Some(t0 + secs(15)));
        s.remove_job("a");
        assert_eq!(s.progress("a"), None);
        // The id may be used again once forgotten.
        add(&mut s, "a", 0, 1, t0);
        assert_eq!(s.lease(w, 2, t0).len(), 1);
    }

    #[test]
    fn resume_leases_only_remaining_tiles() {
        let (mut s, t0) = setup();
        s.add_job("a".into(), 0, 5, &[0, 2, 4, 2], t0).unwrap();
        let p = s.progress("a").unwrap();
        assert_eq!((p.done, p.queued), (3, 2));
        assert_eq!(s.pending_tiles(), 2);
        let w = s.register_worker("w", 8, t0);
        let ls = s.lease(w, 8, t0);
        assert_eq!(ls.iter().map(|l| l.tile).collect::<Vec<_>>(), [1, 3]);
        assert!(!finish(&mut s, &ls[0], t0));
        assert!(finish(&mut s, &ls[1], t0));
        s.add_job("b".into(), 0, 2, &[1, 0], t0).unwrap();
        assert_eq!(s.progress("b").unwrap().state, Dispatch::Finished);
        assert_eq!(
            s.add_job("c".into(), 0, 2, &[2], t0),
            Err(AddJobError::TileOutOfRange { tile: 2, tiles: 2 })
        );
        assert_eq!(s.add_job("a".into(), 0, 2, &[], t0), Err(AddJobError::Duplicate("a".into())));
    }

    #[test]
    fn give_back_requeues_without_failure() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 5, t0);
        let w = s.register_worker("w", 3, t0);
        let ls = s.lease(w, 3, t0);
        assert!(s.give_back(&ls[1], t0));
        assert!(!s.give_back(&ls[1], t0));
        let p = s.progress("a").unwrap();
        assert_eq!((p.leased, p.queued, p.requeued), (2, 3, 1));
        // The handed-back tile goes first, with the next attempt.
        let again = s.lease(w, 2, t0);
        assert_eq!(again.iter().map(|l| (l.tile, l.attempt)).collect::<Vec<_>>(), [(1, 2), (3, 1)]);
        // Two more give backs by the same worker would exclude it if they counted as failures.
        assert!(s.give_back(&again[0], t0));
        assert!(s.give_back(&again[1], t0));
        assert_eq!(s.lease(w, 1, t0)[0].tile, 1);
        assert_eq!(s.workers()[0].failed, 0);
        assert_eq!(s.progress("a").unwrap().state, Dispatch::Running);
    }

    #[test]
    fn next_deadline_tracks_leases_and_heartbeats() {
        let mut s = Scheduler::new(Config { heartbeat_timeout: secs(60), ..Config::default() });
        let t0 = Instant::now();
        assert_eq!(s.next_deadline(), None);
        add(&mut s, "a", 0, 2, t0);
        let w = s.register_worker("w", 2, t0);
        assert_eq!(s.next_deadline(), Some(t0 + secs(60)));
        let ls = s.lease(w, 2, t0 + secs(1));
        assert_eq!(s.next_deadline(), Some(t0 + secs(31)));
        s.complete(&ls[0], t0 + secs(2));
        assert_eq!(s.next_deadline(), Some(t0 + secs(31)));
        assert_eq!(s.expire(t0 + secs(31)), vec![ls[1].clone()]);
        assert_eq!(s.next_deadline(), Some(t0 + secs(62)));
        assert!(s.expire(t0 + secs(61)).is_empty());
        assert!(s.expire(t0 + secs(62)).is_empty());
        assert!(s.workers().is_empty());
        assert_eq!(s.next_deadline(), None);
    }

    #[test]
    fn remove_worker_returns_and_requeues_its_leases() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 4, t0);
        let w1 = s.register_worker("w1", 2, t0);
        let w2 = s.register_worker("w2", 2, t0);
        let ls = s.lease(w1, 2, t0);
        assert_eq!(s.remove_worker(w1, t0), ls);
        assert!(s.remove_worker(w1, t0).is_empty());
        let p = s.progress("a").unwrap();
        assert_eq!((p.leased, p.queued, p.requeued), (0, 4, 2));
        let again = s.lease(w2, 4, t0);
        assert_eq!(
            again.iter().map(|l| (l.tile, l.attempt)).collect::<Vec<_>>(),
            [(0, 2), (1, 2), (2, 1), (3, 1)]
        );
        assert_eq!(s.register_worker("w3", 1, t0), WorkerId(3));
    }

    /// Between acceptance and the store's commit a tile takes no other result, expires with no
    /// lease and is not re-leased; it is done only once committed.
    #[test]
    fn an_accepted_tile_is_done_only_once_committed() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 2, t0);
        let w1 = s.register_worker("w1", 2, t0);
        let w2 = s.register_worker("w2", 2, t0);
        let l = s.lease(w1, 1, t0).remove(0);
        assert_eq!(s.complete(&l, t0), Completion::Accepted);
        assert_eq!(s.complete(&l, t0), Completion::Stale);
        assert_eq!(s.complete_inherited("a", l.tile), Completion::Stale);
        let p = s.progress("a").unwrap();
        assert_eq!((p.done, p.leased, p.queued), (0, 0, 1));
        // Past every timeout: nothing of the committing tile expires, and only tile 1 is leased.
        let later = t0 + secs(100);
        s.heartbeat(w2, later);
        assert!(s.expire(later).is_empty());
        assert_eq!(tiles_of(&s.lease(w2, 2, later)), vec![("a".into(), 1)]);
        assert!(!s.committed("a", l.tile));
        assert!(!s.committed("a", l.tile), "committed twice");
        assert_eq!(s.progress("a").unwrap().done, 1);
    }

    /// A commit that fails gives the lease back to its worker (its result may be sent again),
    /// or, for an earlier run's lease, puts the tile back at the head of the queue; against
    /// nobody either way.
    #[test]
    fn a_failed_commit_gives_the_lease_back_or_requeues_the_tile() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 3, t0);
        let w = s.register_worker("w", 3, t0);
        let ls = s.lease(w, 2, t0);
        assert_eq!(s.complete(&ls[1], t0), Completion::Accepted);
        s.commit_failed("a", 1, Some(&ls[1]), t0 + secs(1));
        let p = s.progress("a").unwrap();
        assert_eq!((p.done, p.leased, p.queued, p.requeued), (0, 2, 1, 0));
        assert_eq!(s.workers()[0].done, 0);
        // The same result, sent again, is accepted; the lease has a new deadline.
        assert!(s.heartbeat(w, t0 + secs(29)));
        assert_eq!(s.expire(t0 + secs(30)).len(), 1, "only the other lease expired");
        assert!(!finish(&mut s, &ls[1], t0 + secs(30)));
        // An inherited result that fails to commit puts its tile back in the queue.
        assert_eq!(s.complete_inherited("a", 2), Completion::Accepted);
        s.commit_failed("a", 2, None, t0 + secs(30));
        let p = s.progress("a").unwrap();
        assert_eq!((p.done, p.leased, p.queued, p.requeued), (1, 0, 2, 2));
        let again = s.lease(w, 2, t0 + secs(30));
        assert_eq!(again.iter().map(|l| (l.tile, l.attempt)).collect::<Vec<_>>(), [(0, 2), (2, 1)]);
        assert_eq!(s.workers()[0].failed, 0);
    }

    /// A job cancelled while a tile commits: the commit's end changes nothing.
    #[test]
    fn a_commit_ending_after_a_cancel_changes_nothing() {
        let (mut s, t0) = setup();
        add(&mut s, "a", 0, 1, t0);
        let w = s.register_worker("w", 1, t0);
        let l = s.lease(w, 1, t0).remove(0);
        assert_eq!(s.complete(&l, t0), Completion::Accepted);
        assert!(s.cancel("a"));
        assert!(!s.committed("a", 0));
        s.commit_failed("a", 0, Some(&l), t0);
        let p = s.progress("a").unwrap();
        assert_eq!((p.state, p.done), (Dispatch::Cancelled, 0));
        assert_eq!(s.pending_tiles(), 0);
    }

    /// A result of a lease from a previous run of the coordinator takes a tile that is queued or
    /// leased in this run (revoking that lease), never one done or committing.
    #[test]
    fn an_inherited_result_takes_a_tile_not_yet_done() {
        let (mut s, t0) = setup();
        s.add_job("a".into(), 0, 4, &[3], t0).unwrap();
        let w = s.register_worker("w", 4, t0);
        let leased = s.lease(w, 1, t0).remove(0);
        assert_eq!(leased.tile, 0);
        // Tile 0 is leased in this run, tile 1 queued, tile 3 done at resume.
        assert_eq!(s.complete_inherited("a", 0), Completion::Accepted);
        assert_eq!(s.complete(&leased, t0), Completion::Stale, "the revoked lease");
        assert_eq!(s.complete_inherited("a", 1), Completion::Accepted);
        assert_eq!(s.complete_inherited("a", 1), Completion::Stale);
        assert_eq!(s.complete_inherited("a", 3), Completion::Stale);
        assert_eq!(s.complete_inherited("a", 9), Completion::Stale);
        assert_eq!(s.complete_inherited("zz", 0), Completion::Stale);
        let p = s.progress("a").unwrap();
        assert_eq!((p.done, p.leased, p.queued), (1, 0, 1));
        assert_eq!(s.workers()[0].leases, 0);
        assert_eq!(tiles_of(&s.lease(w, 4, t0)), vec![("a".into(), 2)]);
        assert!(!s.committed("a", 0));
        assert!(!s.committed("a", 1));
        let last = Lease { job: "a".into(), tile: 2, attempt: 1, worker: w };
        assert!(finish(&mut s, &last, t0));
    }
}
