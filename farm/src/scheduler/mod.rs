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
//! # Checks
//!
//! Every tile is bit-identical whichever worker renders it, so a second rendering proves the
//! first. The coordinator chooses which results to check (see `farm::checks`); the scheduler
//! keeps the tiles' part of it:
//!
//! * **Checking.** A result chosen for a check is stored like any other, and then waits for a
//!   rendering by a worker of another identity ([`Scheduler::committed_for_check`]); the tile is
//!   not done meanwhile, so no job finishes and no frame is written with a check pending.
//!   Checks go out before fresh tiles of their job, and never to a worker whose identity
//!   rendered the tile: a worker registering again keeps its identity, so it cannot check its
//!   own work.
//! * **Comparing.** A check's result comes back as [`Completion::Check`]; the coordinator
//!   compares bytes and says how it ended ([`Scheduler::check_settled`]): the two agree (done,
//!   checked); they differ, and a third worker, of neither identity, renders it again; or the
//!   third settles it.
//! * **Quarantine.** A worker found wrong leaves the farm ([`Scheduler::quarantine`]): its
//!   leases are revoked, and its tiles no check confirmed go back to the queue (except those the
//!   coordinator says to keep: a frame already written).
//! * **No checker left.** When the last worker that could make a check leaves (of another
//!   identity than the renderer's, or for a dispute, than both), the check is waived and the
//!   tile is done with its stored result ([`Scheduler::waive_checks_without_checkers`]), so a
//!   farm that shrinks still ends its jobs.
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

mod checks;

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
    /// The result of a check: compare it with the stored one (and, when `disputed_by` is set,
    /// with that worker's differing result), then call [`Scheduler::check_settled`]. No other
    /// result of the tile is accepted meanwhile.
    Check {
        /// The identity whose result is stored.
        renderer: u64,
        /// The identity of an earlier check that differed from it, if any.
        disputed_by: Option<u64>,
    },
}

/// How a check ended, for [`Scheduler::check_settled`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CheckOutcome {
    /// The check's bytes are the stored ones (or the stored ones now hold the result a third
    /// worker agreed with, from `renderer`): the tile is done, and checked.
    Agreed { renderer: u64 },
    /// They differ: a third worker, of neither identity, renders the tile again.
    Disputed { by: u64 },
    /// Three results that all differ: nothing can be settled; the stored one stands.
    Undecided,
    /// The comparison could not be made (the store could not be read): check it again.
    Retry,
}

/// What [`Scheduler::quarantine`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Quarantined {
    /// The leases its registrations held, now revoked.
    pub revoked: Vec<Lease>,
    /// Per running job, the tiles it rendered that no check had confirmed, back in the queue.
    pub redo: Vec<Redo>,
}

/// A running job's tiles that a quarantined worker rendered and no check confirmed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Redo {
    pub job: JobId,
    /// Those that were done.
    pub done: Vec<u32>,
    /// Those that were waiting for a check.
    pub checking: Vec<u32>,
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
    /// Tiles stored and waiting for a check, or being checked.
    pub checking: u32,
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
    /// Stored, and waiting for a worker of another identity to render it again.
    Checking,
    /// Leased for a check: holder and expiry.
    CheckLeased {
        worker: WorkerId,
        deadline: Instant,
    },
    /// A check's result is being compared with the stored one.
    Comparing,
    Done,
}

#[derive(Clone, Debug)]
struct Tile {
    state: TileState,
    /// Attempt number of the latest lease; 0 before the first one.
    attempt: u32,
    /// Distinct workers that explicitly failed this tile (usually empty, so no allocation).
    failed_on: Vec<WorkerId>,
    /// The identity of the worker whose result is stored (0 before there is one).
    renderer: u64,
    /// The identity of a check whose result differed from the stored one (0: none).
    disputed_by: u64,
    /// A check confirmed the stored result.
    checked: bool,
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
    /// Tiles waiting for a check, lowest first (served before fresh tiles).
    checks: BTreeSet<u32>,
    /// Tiles waiting for a check, leased for one, or being compared.
    checking: u32,
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
        (self.state == Dispatch::Running && (self.queued > 0 || !self.checks.is_empty()))
            .then_some((Reverse(self.priority), self.leased, self.seq, slot))
    }

    fn excludes(&self, worker: WorkerId, max_worker_failures: u32) -> bool {
        max_worker_failures != 0
            && self.worker_failures.get(&worker).is_some_and(|&n| n >= max_worker_failures)
    }

    /// Whether the job has work a worker of `identity` may take: a tile to render, or a check
    /// of a tile no worker of that identity rendered.
    fn offers(&self, identity: u64) -> bool {
        self.queued > 0 || self.check_for(identity).is_some()
    }

    /// The lowest tile waiting for a check that `identity` may render.
    fn check_for(&self, identity: u64) -> Option<u32> {
        self.checks.iter().copied().find(|&t| {
            let tile = &self.tiles[t as usize];
            tile.renderer != identity && tile.disputed_by != identity
        })
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
    /// Who it is across registrations (from the identity it registered with): checks never
    /// go to the identity that rendered the tile.
    identity: u64,
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
        let fresh = Tile {
            state: TileState::Queued,
            attempt: 0,
            failed_on: Vec::new(),
            renderer: 0,
            disputed_by: 0,
            checked: false,
        };
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
            checks: BTreeSet::new(),
            checking: 0,
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

    /// Registers a worker; `identity` is who it is across registrations (see [`Worker`]).
    pub fn register_worker(
        &mut self,
        name: &str,
        capacity: u32,
        identity: u64,
        now: Instant,
    ) -> WorkerId {
        let id = self.next_worker;
        self.next_worker.0 += 1;
        self.workers.insert(
            id,
            Worker {
                name: name.to_owned(),
                identity,
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
        let identity = holder.identity;
        let mut out = Vec::new();
        while (out.len() as u32) < max {
            let jobs = &self.jobs;
            let Some(key) = self
                .ready
                .iter()
                .find(|key| {
                    jobs[key.3 as usize].as_ref().is_some_and(|job| {
                        !job.excludes(worker, max_worker_failures) && job.offers(identity)
                    })
                })
                .copied()
            else {
                break;
            };
            let slot = key.3;
            let job = self.jobs[slot as usize].as_mut().expect("ready job is live");
            // A check first: it holds up the end of its job, as a requeued tile does.
            let (tile, state) = match job.check_for(identity) {
                Some(tile) => {
                    job.checks.remove(&tile);
                    (tile, TileState::CheckLeased { worker, deadline })
                }
                None => {
                    job.queued -= 1;
                    let tile = job.pop_queued().expect("a job offering no check has a queued tile");
                    (tile, TileState::Leased { worker, deadline })
                }
            };
            let entry = &mut job.tiles[tile as usize];
            entry.attempt += 1;
            entry.state = state;
            let attempt = entry.attempt;
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
            TileState::Leased { worker, .. } | TileState::CheckLeased { worker, .. }
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
        let check = matches!(
            self.job(slot).tiles[lease.tile as usize].state,
            TileState::CheckLeased { .. }
        );
        self.revoke(slot, lease.tile);
        let identity = self.workers.get_mut(&lease.worker).map_or(0, |w| {
            w.done += 1;
            w.identity
        });
        let job = self.job_mut(slot);
        let entry = &mut job.tiles[lease.tile as usize];
        let completion = if check {
            entry.state = TileState::Comparing;
            let disputed_by = (entry.disputed_by != 0).then_some(entry.disputed_by);
            Completion::Check { renderer: entry.renderer, disputed_by }
        } else {
            entry.state = TileState::Committing;
            entry.renderer = identity;
            job.committing += 1;
            Completion::Accepted
        };
        let after = job.ready_key(slot);
        reindex(&mut self.ready, before, after);
        completion
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
        self.job_mut(slot).committing -= 1;
        self.mark_done(slot, tile)
    }

    /// The tile is done (its result stored, and checked if it was to be). True when it was the
    /// job's last tile: the job is then `Finished` and its tile table freed.
    fn mark_done(&mut self, slot: Slot, tile: u32) -> bool {
        self.totals.done += 1;
        let job = self.job_mut(slot);
        job.tiles[tile as usize].state = TileState::Done;
        job.done += 1;
        let finished = job.done == job.total;
        if finished {
            job.state = Dispatch::Finished;
            job.tiles = Vec::new();
            job.requeue = BTreeSet::new();
            job.checks = BTreeSet::new();
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
        self.tile_in(job, tile, TileState::Committing)
    }

    /// The slot of a running job whose `tile` is in `state`.
    fn tile_in(&self, job: &str, tile: u32, state: TileState) -> Option<Slot> {
        let slot = *self.by_id.get(job)?;
        let entry = self.job(slot);
        let now = entry.tiles.get(tile as usize)?.state;
        (entry.state == Dispatch::Running && now == state).then_some(slot)
    }

    /// Ends the current lease of a leased tile (its deadline and its holder's record of it),
    /// leaving the tile's state and the job's place in the ready set to the caller, which
    /// takes the job's ready key before and reindexes after. The revoked lease.
    fn revoke(&mut self, slot: Slot, tile: u32) -> Lease {
        let job = self.jobs[slot as usize].as_mut().expect("leased job is live");
        let entry = &mut job.tiles[tile as usize];
        let (TileState::Leased { worker, deadline } | TileState::CheckLeased { worker, deadline }) =
            entry.state
        else {
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
        let check = matches!(
            self.job(slot).tiles[lease.tile as usize].state,
            TileState::CheckLeased { .. }
        );
        self.requeue(slot, lease.tile);
        if check {
            // Another worker rendered the tile: the scene is not at fault, this worker may be.
            *self.job_mut(slot).worker_failures.entry(lease.worker).or_insert(0) += 1;
            return Failure::Requeued;
        }
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

    /// Takes the current lease of a tile away and puts the tile at the head of its job's queue
    /// (a check's, back among the checks). Returns the revoked lease.
    fn requeue(&mut self, slot: Slot, tile: u32) -> Lease {
        let before = self.job(slot).ready_key(slot);
        let lease = self.revoke(slot, tile);
        let job = self.job_mut(slot);
        if matches!(job.tiles[tile as usize].state, TileState::CheckLeased { .. }) {
            job.tiles[tile as usize].state = TileState::Checking;
            job.checks.insert(tile);
            let after = job.ready_key(slot);
            reindex(&mut self.ready, before, after);
            return lease;
        }
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
            if let TileState::Leased { worker, deadline }
            | TileState::CheckLeased { worker, deadline } = tile.state
            {
                let index = index as u32;
                self.lease_deadlines.remove(&(deadline, slot, index));
                if let Some(w) = self.workers.get_mut(&worker) {
                    w.leases.remove(&pack(slot, index));
                }
            }
        }
        job.leased = 0;
        job.committing = 0;
        job.checking = 0;
        job.queued = job.total - job.done;
        job.tiles = Vec::new();
        job.requeue = BTreeSet::new();
        job.checks = BTreeSet::new();
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
            checking: job.checking,
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
        self.ready
            .iter()
            .map(|key| {
                let job = self.job(key.3);
                u64::from(job.queued) + job.checks.len() as u64
            })
            .sum()
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
mod tests;
