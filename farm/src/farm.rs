//! The farm: the coordinator's one domain layer. Everything the coordinator does — take assets
//! and jobs from clients, lease tiles to workers, accept their results, assemble, cancel, list —
//! is a method here on domain types; the gRPC services (`grpc`) only convert the wire to these
//! types and back, and any other door (the studio's HTTP API) calls the same methods.
//!
//! Locks: one `std::sync::Mutex` over the scheduler, the job table and the worker sessions,
//! never held across an `.await` or a store write. A tile result is decided under it (current
//! lease, running job) and queued for the store under it too, so the store sees tile writes
//! and a job's tile removal in the order the decisions were made; it is acknowledged only once
//! durable, and counts as done only then.
//!
//! Record writes go through `Farm::persist`, which writes the record as it is at the time of
//! writing, one write at a time: a slow write of an older state can never land after a newer one.
//!
//! Two parts of the farm live in modules of their own: `assembly`, which turns a job whose tiles
//! are all stored into its result files, and `scenes`, the studio's scenes and their revisions.

use crate::asset_store::{AssetStore, Upload, asset_hash};
use crate::auth::Tokens;
use crate::error::{FarmError, Result};
use crate::group_commit::TileCommits;
use crate::ids::{JobId, Session, SessionKey, WorkerId};
use crate::job::{IllegalTransition, JobRecord, JobState, JobStatus};
use crate::lease::{LeaseClaim, LeaseSigner};
use crate::metrics::Metrics;
use crate::objects::{Objects, result_key};
use crate::scheduler::{self, Completion, Failure, Scheduler};
use crate::store::Store;
use restauro_image::framebuffer::{TileLayout, check_tile};
use restauro_proto as pb;
use restauro_scene::bundle::Bundle;
use restauro_scene::job::{JobSpec, check_label, printable};
use restauro_scene::limits::Limits;
use restauro_scene::plan::{Plan, Rect, RenderOptions};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use tokio::sync::{Notify, mpsc, watch};
use tracing::{debug, info, warn};

mod assembly;
mod checks;
mod illuminance;
mod scenes;
mod sequence_frame;
pub use checks::{CheckPolicy, QuarantineRecord};
pub use scenes::{
    MAX_FOLDER_BYTES, PhotometryInfo, Revised, RevisionInfo, SceneEntry, scene_identity, sent_file,
};

/// How the coordinator runs.
#[derive(Clone)]
pub struct Config {
    /// The store (`store.redb`, unless `store` names another), the assets (`assets/`) and the
    /// results (`jobs/<id>/`).
    pub data_dir: PathBuf,
    /// A PostgreSQL database for the store (`postgres://…`) instead of `data_dir/store.redb`.
    pub store: Option<String>,
    /// An S3 bucket (`s3://BUCKET/PREFIX`) where assets and results are kept besides the data
    /// folder (`objects`).
    pub objects: Option<String>,
    pub tokens: Tokens,
    /// What a job's scene and render may ask; sent to workers with each job.
    pub limits: Limits,
    /// Unfinished jobs at once; more are refused.
    pub max_jobs: usize,
    /// Bytes of uploads in progress at once.
    pub max_upload_bytes: u64,
    /// Scenes loaded at once (to check a submission, to build a studio preview): each holds
    /// its whole scene in memory while it loads; more wait their turn.
    pub max_scene_loads: usize,
    pub scheduler: scheduler::Config,
    /// How many workers' results are rendered a second time on another worker (`checks`).
    pub checks: CheckPolicy,
    /// Run the Retinex stage and write its files.
    pub retinex: bool,
    /// Fault injection for tests: every store commit waits this long first (a slow disk).
    pub commit_delay: Duration,
    /// What one caller can hold (connections, streams, files sent, silence).
    pub callers: crate::callers::CallerLimits,
}

/// The plans [`Farm::submit`] keeps for submissions to come.
const KEPT_PLANS: usize = 16;

/// What a plan is made from: the scene (its manifest names every file by hash) and the
/// options of the render. (The limits are the coordinator's, the same for every plan.)
fn plan_key(manifest_json: &str, render: &RenderOptions) -> blake3::Hash {
    let mut hasher = blake3::Hasher::new();
    let options = format!("{render:?}");
    for part in [manifest_json.as_bytes(), options.as_bytes()] {
        hasher.update(&(part.len() as u64).to_le_bytes());
        hasher.update(part);
    }
    hasher.finalize()
}

pub struct Farm {
    pub(crate) config: Config,
    pub(crate) store: Arc<Store>,
    /// Where the assets and results are kept besides the data folder (`objects`).
    pub(crate) objects: Arc<Objects>,
    assets: AssetStore,
    commits: TileCommits,
    signer: LeaseSigner,
    /// Draws which results are checked (`checks`); this run's own, never sent.
    check_key: [u8; 32],
    state: Mutex<FarmState>,
    /// One record write at a time (see the module doc).
    persisting: Mutex<()>,
    /// Woken when tiles are queued (new job, requeue), for waiting pulls.
    work: Notify,
    /// Woken when a deadline may have come nearer, for the expiry timer.
    timer: Notify,
    /// One scene edit at a time: each applies to the revision the last one made.
    editing: tokio::sync::Mutex<()>,
    /// When the expiry timer will wake next (`None` while it is computing).
    timer_wakes: Mutex<Option<Instant>>,
    /// Bumped on every change of a job, for watchers.
    changed: watch::Sender<u64>,
    /// The files being sent (results, assets), within `--max-downloads`.
    pub(crate) downloads: crate::callers::Downloads,
    /// Within `--max-scene-loads`.
    scene_loads: tokio::sync::Semaphore,
    /// The plans of the latest submissions, by what they were made from: the same scene with
    /// the same options (fifty clients submitting one scene, a restorer's snapshots of one
    /// view) is planned once, not loaded again for each. Assets are never removed, so a plan's
    /// scene stays whole.
    plans: crate::recent::Recent<blake3::Hash, Plan>,
    pub metrics: Metrics,
}

struct FarmState {
    scheduler: Scheduler,
    jobs: BTreeMap<JobId, JobRecord>,
    workers: HashMap<WorkerId, WorkerEntry>,
    /// Submissions admitted and not yet recorded: they count towards `max_jobs`.
    admitting: usize,
    /// The studio's scenes: their revisions and which manifests are theirs.
    scenes: scenes::Scenes,
    /// Each running sequence's tiles done, frame by frame.
    frame_done: HashMap<JobId, Vec<u32>>,
    /// The sequences whose frames are being assembled now (one thread a job, frame after frame).
    assembling_frames: std::collections::HashSet<JobId>,
    /// Workers found wrong by a check, by identity key (`checks`).
    quarantine: HashMap<u64, QuarantineRecord>,
}

struct WorkerEntry {
    key: SessionKey,
    name: String,
    build: String,
    /// The digest of the identity it registered with: its leases are bound to it.
    identity: [u8; 32],
    /// Who it is across registrations (`checks::identity_key`).
    identity_key: u64,
    /// Its results that a check confirmed in this registration.
    confirmed: u32,
}

/// A registered worker, as `restauro workers` shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkerStatus {
    pub id: WorkerId,
    pub name: String,
    pub capacity: u32,
    pub leases: u32,
    pub done: u64,
    pub failed: u64,
    /// Its results that a check on another worker confirmed.
    pub confirmed: u64,
    pub last_seen_s: f64,
    pub build: String,
}

/// What a worker renders for a job: the scene, the plan resolved at submission, and the limits
/// the scene was checked against.
pub struct WorkerJob {
    pub manifest_json: String,
    pub plan: Plan,
    pub limits: Limits,
    /// The job's number of the frame's first tile (0 for a still).
    pub first_tile: u32,
}

/// How a tile report stands before its pixels are read.
pub enum Expected {
    /// The caller's session is not known: it must register again.
    UnknownSession,
    /// The lease is not the tile's current one (expired, job cancelled): drop the result.
    Stale,
    /// The tile's pixels, in this layout, are wanted.
    Tile { rect: Rect, layout: TileLayout },
}

/// How a tile report ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reported {
    UnknownSession,
    Stale,
    /// Stored: the tile is done.
    Accepted,
}

/// The store the configuration names: a PostgreSQL database, or the file in the data folder.
pub fn open_store(config: &Config) -> std::result::Result<Store, crate::store::StoreError> {
    match &config.store {
        Some(url) => Store::connect(url),
        None => {
            std::fs::create_dir_all(&config.data_dir).map_err(|e| {
                crate::store::StoreError::Store {
                    path: config.data_dir.clone(),
                    message: e.to_string(),
                }
            })?;
            Store::open(&config.data_dir.join("store.redb"))
        }
    }
}

/// What follows tiles becoming done ([`Farm::follow`]).
#[derive(Clone, Copy, Debug, Default)]
struct Next {
    /// The job's last tile: it is being assembled.
    finished: bool,
    /// A sequence with a frame whole (or done): its frame writer runs.
    frames: bool,
}

impl Next {
    fn or(self, other: Next) -> Next {
        Next { finished: self.finished || other.finished, frames: self.frames || other.frames }
    }
}

fn now_unix_ms() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64)
}

/// Counts a submission towards `max_jobs` from its admission until it is recorded or refused.
struct Admission<'a> {
    farm: &'a Farm,
    armed: bool,
}

impl Drop for Admission<'_> {
    fn drop(&mut self) {
        if self.armed {
            self.farm.lock().admitting -= 1;
        }
    }
}

impl Farm {
    /// Opens the store the configuration names and resumes every unfinished job in it.
    pub fn open(config: Config) -> Result<Arc<Farm>> {
        let store = Arc::new(open_store(&config).map_err(FarmError::StoreAtStart)?);
        Farm::open_on(config, store)
    }

    /// Resumes every unfinished job in `store`, opened already (and, on PostgreSQL, led by
    /// this coordinator: see `lead`).
    pub fn open_on(config: Config, store: Arc<Store>) -> Result<Arc<Farm>> {
        let jobs_dir = config.data_dir.join("jobs");
        std::fs::create_dir_all(&jobs_dir).map_err(|source| FarmError::CreateDir {
            path: jobs_dir.display().to_string(),
            source,
        })?;
        let (secret, epoch) =
            store.begin_run(crate::ids::random_secret()).map_err(FarmError::StoreAtStart)?;
        let objects = Arc::new(Objects::open(config.objects.as_deref())?);
        let assets = AssetStore::open(
            &config.data_dir.join("assets"),
            objects.clone(),
            config.limits.max_file_bytes,
            config.max_upload_bytes,
        )?;
        let moved = store
            .drain_legacy_assets(|hash, bytes| assets.keep(hash, bytes))
            .map_err(FarmError::StoreAtStart)?;
        if moved > 0 {
            info!(assets = moved, "moved the assets of an earlier release out of the store");
        }
        remove_leftover_results(&jobs_dir);
        let commits =
            TileCommits::start(store.clone(), config.commit_delay).map_err(FarmError::Committer)?;
        let farm = Arc::new(Farm {
            store,
            objects,
            assets,
            commits,
            signer: LeaseSigner::new(secret, epoch),
            check_key: crate::ids::random_secret(),
            downloads: crate::callers::Downloads::new(config.callers),
            scene_loads: tokio::sync::Semaphore::new(config.max_scene_loads.max(1)),
            plans: crate::recent::Recent::new(KEPT_PLANS),
            state: Mutex::new(FarmState {
                scheduler: Scheduler::new(config.scheduler.clone()),
                jobs: BTreeMap::new(),
                workers: HashMap::new(),
                admitting: 0,
                scenes: scenes::Scenes::default(),
                frame_done: HashMap::new(),
                assembling_frames: Default::default(),
                quarantine: HashMap::new(),
            }),
            config,
            persisting: Mutex::new(()),
            work: Notify::new(),
            timer: Notify::new(),
            editing: tokio::sync::Mutex::new(()),
            timer_wakes: Mutex::new(None),
            changed: watch::Sender::new(0),
            metrics: Metrics::new(),
        });
        farm.load_quarantine()?;
        let (to_assemble, sequences) = farm.resume()?;
        farm.resume_scenes()?;
        for id in to_assemble {
            let farm = farm.clone();
            std::thread::spawn(move || assembly::assemble(&farm, &id));
        }
        for id in sequences {
            farm.kick_frames(&id);
        }
        info!(epoch, "coordinator run started");
        Ok(farm)
    }

    /// Loads every job of the store; the unfinished ones go back to the scheduler with their
    /// finished tiles. The stills to assemble (every tile stored), and the sequences to resume.
    fn resume(&self) -> Result<(Vec<JobId>, Vec<JobId>)> {
        let store = |e| FarmError::StoreAtStart(e);
        let mut to_assemble = Vec::new();
        let mut sequences = Vec::new();
        for (id, bytes) in self.store.jobs().map_err(store)? {
            let mut record = JobRecord::from_bytes(&id, &bytes).map_err(|e| {
                FarmError::UnreadableRecord { job: id.clone(), problem: e.to_string() }
            })?;
            let id = record.id.clone();
            if record.format != crate::job::RECORD_FORMAT {
                // An earlier release's record: listed as failed, stored anew, its tiles dropped.
                record.format = crate::job::RECORD_FORMAT;
                self.store.remove_tiles(&id).map_err(store)?;
                self.store.put_job(&id, &record.to_bytes()).map_err(store)?;
            } else if record.state().is_final() {
                // Ended before its tiles were dropped (the coordinator stopped in between).
                if !self.store.finished_tiles(&id).map_err(store)?.is_empty() {
                    self.store.remove_tiles(&id).map_err(store)?;
                }
            } else {
                let mut done = self.store.finished_tiles(&id).map_err(store)?;
                // A ready frame's tiles left the store once its files were written.
                if record.frames_ready > 0 {
                    done.extend(0..record.frame_range(record.frames_ready - 1).end);
                    done.sort_unstable();
                    done.dedup();
                }
                let total = record.tile_count();
                info!(job = %id, done = done.len(), total, "resuming job");
                let mut st = self.lock();
                st.scheduler
                    .add_job(id.clone(), record.spec.priority, total, &done, Instant::now())
                    .map_err(|problem| FarmError::Resume { job: id.clone(), problem })?;
                let all_done = done.len() as u32 == total;
                if record.is_sequence() {
                    let mut per_frame = vec![0; record.frame_count() as usize];
                    for &tile in &done {
                        if let Some(place) = record.place(tile) {
                            per_frame[place.frame as usize] += 1;
                        }
                    }
                    st.frame_done.insert(id.clone(), per_frame);
                    if all_done {
                        record.resume_assembly(true);
                    }
                    sequences.push(id.clone());
                } else if record.resume_assembly(all_done) {
                    to_assemble.push(id.clone());
                }
            }
            self.lock().jobs.insert(id, record);
        }
        Ok((to_assemble, sequences))
    }

    fn lock(&self) -> MutexGuard<'_, FarmState> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn bump(&self) {
        self.changed.send_modify(|v| *v += 1);
    }

    /// Writes the job's record as it is now (see the module doc).
    pub(crate) fn persist(&self, id: &JobId) {
        let _one_at_a_time = self.persisting.lock().unwrap_or_else(|p| p.into_inner());
        let Some(bytes) = self.lock().jobs.get(id).map(JobRecord::to_bytes) else { return };
        if let Err(e) = self.store.put_job(id, &bytes) {
            warn!(job = %id, "could not store the job record: {e}");
        }
    }

    fn status(st: &FarmState, r: &JobRecord) -> JobStatus {
        let progress = st.scheduler.progress(&r.id);
        let total = r.tile_count();
        let done = match r.state() {
            JobState::Done | JobState::Assembling | JobState::PostProcessing => total,
            JobState::Failed | JobState::Cancelled => r.tiles_done_at_end,
            JobState::Queued | JobState::Running => progress.as_ref().map_or(0, |p| p.done),
        };
        JobStatus {
            id: r.id.clone(),
            name: r.spec.name.as_str().to_owned(),
            state: r.state(),
            tiles_total: total,
            tiles_done: done,
            tiles_leased: progress.as_ref().map_or(0, |p| p.leased),
            tiles_requeued: progress.as_ref().map_or(r.tiles_requeued_at_end, |p| p.requeued),
            error: r.error.clone(),
            priority: r.spec.priority,
            width: r.plan.width,
            height: r.plan.height,
            elapsed_s: now_unix_ms().saturating_sub(r.submitted_unix_ms) as f64 / 1e3,
            // A running sequence's list grows with its frames: sent once, when it is done.
            results: match r.is_sequence() && r.state() != JobState::Done {
                true => Vec::new(),
                false => r.results.clone(),
            },
            frames_total: r.frame_count(),
            frames_ready: r.frames_ready,
            frames: Self::frames_begun(st, r),
        }
    }

    /// The frames of sequence `r` begun and not ready. Tiles are leased in order, so these are
    /// the frames from the first not ready to the one the scheduler's cursor is in: a few.
    fn frames_begun(st: &FarmState, r: &JobRecord) -> Vec<crate::job::FrameProgress> {
        let Some(done) = st.frame_done.get(&r.id) else { return Vec::new() };
        let cursor = st.scheduler.cursor(&r.id).unwrap_or(0);
        (r.frames_ready..r.frame_count())
            .map_while(|f| {
                let range = r.frame_range(f);
                let tiles_done = done.get(f as usize).copied().unwrap_or(0);
                (range.start < cursor || tiles_done > 0).then(|| crate::job::FrameProgress {
                    index: f,
                    label: r
                        .spec
                        .frames
                        .get(f as usize)
                        .map(|x| x.label.clone())
                        .unwrap_or_default(),
                    tiles_done,
                    tiles_total: range.len() as u32,
                })
            })
            .collect()
    }

    /// The limits the coordinator keeps every job within (`--max-frames`, …): the studio
    /// expands a sequence within them, as the command line does within its own.
    pub fn limits(&self) -> &Limits {
        &self.config.limits
    }

    /// A copy of job `id`'s record.
    /// The record of job `id`: its spec, plan and state.
    pub fn jobs_record(&self, id: &JobId) -> Option<JobRecord> {
        self.lock().jobs.get(id).cloned()
    }

    /// The bytes of tile `index` of job `id` as the store holds them, while the job keeps its
    /// tiles (until it is assembled or cancelled).
    pub fn stored_tile(&self, id: &JobId, index: u32) -> crate::error::Result<Option<Vec<u8>>> {
        Ok(self.store.tile(id, index)?)
    }

    fn snapshot(&self, id: &JobId) -> Option<JobStatus> {
        let st = self.lock();
        st.jobs.get(id).map(|r| Self::status(&st, r))
    }

    /// Changes a job's record by `change` under the lock, then stores it and tells watchers.
    pub(crate) fn transition<T>(
        &self,
        id: &JobId,
        change: impl FnOnce(&mut JobRecord) -> Result<T, IllegalTransition>,
    ) -> Result<(T, JobRecord)> {
        let (value, record) = {
            let mut st = self.lock();
            let r = st.jobs.get_mut(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
            (change(r)?, r.clone())
        };
        self.persist(id);
        self.bump();
        Ok((value, record))
    }

    /// Ends a job that has not ended (failed or cancelled): its tiles leave the scheduler and
    /// the store. Returns what `end` returned; an ended job is left as it is.
    fn end_job(
        &self,
        st: &mut FarmState,
        id: &JobId,
        end: impl FnOnce(&mut JobRecord, u32) -> Result<(), IllegalTransition>,
    ) -> Result<()> {
        let progress = st.scheduler.progress(id);
        let r = st.jobs.get_mut(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
        end(r, progress.as_ref().map_or(0, |p| p.done))?;
        r.tiles_requeued_at_end = progress.map_or(0, |p| p.requeued);
        st.scheduler.remove_job(id);
        st.frame_done.remove(id);
        // Queued under the lock: after every tile of the job accepted before. (The committer
        // logs a removal that fails; nothing waits for it.)
        drop(self.commits.remove_job(id.clone()));
        Ok(())
    }

    /// Fails a job with `reason` (a tile failed on several workers; an output could not be
    /// written). Nothing happens to a job that has ended already.
    pub(crate) fn fail_job(&self, id: &JobId, reason: String) {
        let ended = {
            let mut st = self.lock();
            self.end_job(&mut st, id, |r, done| r.fail(reason.clone(), done))
        };
        if ended.is_ok() {
            warn!(job = %id, "job failed: {reason}");
            self.persist(id);
            self.bump();
        }
    }

    /// A job whose results are written: done, and its tiles dropped. Refused when the job
    /// ended meanwhile (cancelled while its files were written).
    pub(crate) fn finish_job(&self, id: &JobId, files: Vec<String>) -> Result<()> {
        {
            let mut st = self.lock();
            let requeued = st.scheduler.progress(id).map_or(0, |p| p.requeued);
            let r = st.jobs.get_mut(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
            r.finish(files)?;
            r.tiles_requeued_at_end = requeued;
            st.scheduler.remove_job(id);
            st.frame_done.remove(id);
            drop(self.commits.remove_job(id.clone()));
        }
        self.persist(id);
        self.bump();
        Ok(())
    }

    /// Where a job's result files go.
    pub(crate) fn results_dir(&self, id: &JobId) -> PathBuf {
        self.config.data_dir.join("jobs").join(id.as_str())
    }

    /// Every asset a manifest names, from the asset store; refuses the manifest when one is
    /// missing.
    fn bundle(&self, manifest_json: &str) -> Result<Bundle> {
        let scene = Bundle::parse_manifest(manifest_json).map_err(|e| {
            FarmError::Wire(pb::convert::WireError::new(
                "manifest_json",
                format!("not a scene bundle: {e}"),
            ))
        })?;
        let skeleton = Bundle { scene, files: BTreeMap::new() };
        let mut files = BTreeMap::new();
        for reference in skeleton.references() {
            let hash = asset_hash(&reference)?;
            let bytes = self
                .assets
                .read(hash)?
                .ok_or_else(|| FarmError::AssetMissing { reference: reference.clone() })?;
            files.insert(hash.to_owned(), bytes);
        }
        Ok(Bundle::from_parts(manifest_json, files)?)
    }

    // ------------------------------------------------------------------ clients

    /// Which of `references` the coordinator does not have.
    pub fn missing_assets(&self, references: Vec<String>) -> Result<Vec<String>> {
        let mut missing = Vec::new();
        for reference in references {
            if !self.assets.has(asset_hash(&reference)?) {
                missing.push(reference);
            }
        }
        Ok(missing)
    }

    /// Starts an upload of `reference`, announced as `declared_bytes`.
    pub async fn begin_upload(&self, reference: &str, declared_bytes: u64) -> Result<Upload> {
        self.assets.begin(reference, declared_bytes).await
    }

    fn admit(&self) -> Result<Admission<'_>> {
        let mut st = self.lock();
        let open = st.jobs.values().filter(|r| !r.state().is_final()).count() + st.admitting;
        if open >= self.config.max_jobs {
            return Err(FarmError::TooManyJobs { open });
        }
        st.admitting += 1;
        Ok(Admission { farm: self, armed: true })
    }

    /// Runs `load`, which loads a whole scene, on the blocking threads once one of the
    /// `--max-scene-loads` places is free: 200 snapshots at once would otherwise hold 200
    /// scenes in memory together.
    pub(crate) async fn loading_scene<T: Send + 'static>(
        &self,
        load: impl FnOnce() -> Result<T> + Send + 'static,
    ) -> Result<T> {
        let _place = self
            .scene_loads
            .acquire()
            .await
            .map_err(|e| FarmError::Internal(format!("the scene loads: {e}")))?;
        tokio::task::spawn_blocking(load).await?
    }

    /// Takes a job: its scene (every asset uploaded) loaded and planned within the limits,
    /// its record stored, its tiles queued.
    pub async fn submit(
        self: &Arc<Self>,
        manifest_json: String,
        spec: JobSpec,
    ) -> Result<JobStatus> {
        let mut admission = self.admit()?;
        if !spec.frames.is_empty() {
            let farm = self.clone();
            let (spec, frames) = self
                .loading_scene(move || {
                    let frames = farm.plan_frames(&manifest_json, &spec)?;
                    Ok((spec, (manifest_json, frames)))
                })
                .await?;
            let (manifest, frames) = frames;
            let plan = frames.plans[0].clone();
            let mut record = JobRecord::new(JobId::random(), spec, manifest, plan, now_unix_ms());
            record.frame_plans = frames.plans;
            record.frame_tiles = frames.tiles;
            return self.record_job(record, &mut admission).await;
        }
        let farm = self.clone();
        let (render, name, manifest) = (spec.render.clone(), spec.name.to_string(), manifest_json);
        let key = plan_key(&manifest, &render);
        let (plan, manifest) = match self.plans.get(&key) {
            Some(plan) => (plan, manifest),
            None => {
                let (plan, manifest) = self
                    .loading_scene(move || -> Result<(Plan, String)> {
                        let bundle = farm.bundle(&manifest)?;
                        let limits = farm.config.limits;
                        let scene = bundle.load(&limits)?;
                        let label = format!("scene {name}");
                        let plan = Plan::new(&scene, &render, &limits, Path::new(&label))?;
                        Ok((plan, manifest))
                    })
                    .await?;
                self.plans.keep(key, plan.clone());
                (plan, manifest)
            }
        };
        let record = JobRecord::new(JobId::random(), spec, manifest, plan, now_unix_ms());
        self.record_job(record, &mut admission).await
    }

    /// Stores a new job's record and queues its tiles.
    async fn record_job(
        self: &Arc<Self>,
        record: JobRecord,
        admission: &mut Admission<'_>,
    ) -> Result<JobStatus> {
        let id = record.id.clone();
        let tiles = record.tile_count();
        let (store, key, bytes) = (self.store.clone(), id.clone(), record.to_bytes());
        tokio::task::spawn_blocking(move || store.put_job(&key, &bytes)).await??;
        let status = {
            let mut st = self.lock();
            admission.armed = false;
            st.admitting -= 1;
            st.scheduler
                .add_job(id.clone(), record.spec.priority, tiles, &[], Instant::now())
                .map_err(|e| FarmError::Internal(e.to_string()))?;
            if record.is_sequence() {
                st.frame_done.insert(id.clone(), vec![0; record.frame_count() as usize]);
            }
            let status = Self::status(&st, &record);
            st.jobs.insert(id.clone(), record);
            status
        };
        info!(job = %id, name = %status.name, tiles, "job submitted");
        self.work.notify_waiters();
        self.bump();
        Ok(status)
    }

    /// The job's status now and at every change until it ends. Subscribed before the first
    /// status is taken, so no change between the two is lost.
    pub fn watch(self: &Arc<Self>, id: &JobId) -> Result<mpsc::Receiver<JobStatus>> {
        let mut changes = self.changed.subscribe();
        let first = self.snapshot(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
        let (tx, rx) = mpsc::channel(16);
        let (farm, id) = (self.clone(), id.clone());
        tokio::spawn(async move {
            let mut last = first;
            if tx.send(last.clone()).await.is_err() {
                return;
            }
            while !last.state.is_final() {
                if changes.changed().await.is_err() {
                    return;
                }
                let Some(now) = farm.snapshot(&id) else { return };
                if now != last {
                    if tx.send(now.clone()).await.is_err() {
                        return;
                    }
                    last = now;
                }
            }
        });
        Ok(rx)
    }

    /// Wakes at every change of a job (the studio's event stream diffs its snapshots).
    pub fn changes(&self) -> watch::Receiver<u64> {
        self.changed.subscribe()
    }

    /// The path of one result file of a finished job.
    pub fn result_path(&self, id: &JobId, name: &str) -> Result<PathBuf> {
        let st = self.lock();
        let r = st.jobs.get(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
        // A sequence's frames are fetched as they are ready.
        if r.state() != JobState::Done && !r.is_sequence() {
            return Err(FarmError::NotDone { job: id.clone(), state: r.state() });
        }
        if !r.results.iter().any(|f| f == name) {
            return Err(FarmError::NoSuchResult { job: id.clone(), name: name.to_owned() });
        }
        drop(st);
        let path = self.results_dir(id).join(name);
        // Written by another coordinator (the lead passed): fetched from the object store.
        if self.objects.is_shared() && !path.is_file() {
            self.objects.fetch(&result_key(id.as_str(), name), &path)?;
        }
        Ok(path)
    }

    /// Cancels a job that has not ended; an ended job is left as it is. Its status.
    pub fn cancel(&self, id: &JobId) -> Result<JobStatus> {
        let status = {
            let mut st = self.lock();
            let state = st.jobs.get(id).map(JobRecord::state);
            match state {
                None => return Err(FarmError::NoSuchJob(id.clone())),
                Some(s) if !s.is_final() => self.end_job(&mut st, id, |r, done| r.cancel(done))?,
                Some(_) => {}
            }
            Self::status(&st, &st.jobs[id])
        };
        info!(job = %id, state = %status.state, "cancel");
        self.persist(id);
        self.work.notify_waiters();
        self.bump();
        Ok(status)
    }

    /// The coordinator's own trouble, when it has any (the store or the object store cannot be
    /// written).
    pub fn problem(&self) -> Option<String> {
        match (self.store.problem(), self.objects.problem()) {
            (Some(store), Some(objects)) => Some(format!("{store}; {objects}")),
            (store, objects) => store.or(objects),
        }
    }

    /// Job `id` as a client sees it.
    pub fn job(&self, id: &JobId) -> Result<JobStatus> {
        self.snapshot(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))
    }

    pub fn jobs(&self) -> Vec<JobStatus> {
        let st = self.lock();
        st.jobs.values().map(|r| Self::status(&st, r)).collect()
    }

    pub fn workers(&self) -> Vec<WorkerStatus> {
        let st = self.lock();
        let now = Instant::now();
        st.scheduler
            .workers()
            .into_iter()
            .map(|w| WorkerStatus {
                id: w.id,
                name: w.name,
                capacity: w.capacity,
                leases: w.leases,
                done: w.done,
                failed: w.failed,
                confirmed: st.workers.get(&w.id).map_or(0, |e| u64::from(e.confirmed)),
                last_seen_s: now.saturating_duration_since(w.last_seen).as_secs_f64(),
                build: st.workers.get(&w.id).map(|e| e.build.clone()).unwrap_or_default(),
            })
            .collect()
    }

    // ------------------------------------------------------------------ workers

    /// Registers a worker: its session, and how often it should heartbeat.
    pub fn register(
        &self,
        name: &str,
        capacity: u32,
        build: &str,
        identity: &[u8],
    ) -> Result<(Session, Duration)> {
        check_label("name", name, 128).map_err(pb::convert::WireError::from)?;
        check_label("build", build, 256).map_err(pb::convert::WireError::from)?;
        let identity = <[u8; 32]>::try_from(identity).map_err(|_| {
            pb::convert::WireError::new(
                "identity",
                "a worker registers with 32 random bytes it keeps for its whole life",
            )
        })?;
        let key = SessionKey::random();
        let identity = crate::lease::identity_digest(&identity);
        let identity_key = checks::identity_key(&identity);
        self.check_not_quarantined(identity_key)?;
        let worker = {
            let mut st = self.lock();
            let capacity = capacity.clamp(1, 1024);
            let id = st.scheduler.register_worker(name, capacity, identity_key, Instant::now());
            let entry = WorkerEntry {
                key,
                name: name.to_owned(),
                build: build.to_owned(),
                identity,
                identity_key,
                confirmed: 0,
            };
            st.workers.insert(id, entry);
            id
        };
        self.deadline_added();
        info!(worker = %worker, %name, capacity, %build, "worker registered");
        let heartbeat =
            (self.config.scheduler.heartbeat_timeout / 3).max(Duration::from_millis(50));
        Ok((Session { worker, key }, heartbeat))
    }

    /// Whether `session` is a registered worker's, heard from now.
    fn known(st: &mut FarmState, session: &Session) -> bool {
        st.workers.get(&session.worker).is_some_and(|e| e.key == session.key)
            && st.scheduler.heartbeat(session.worker, Instant::now())
    }

    /// False: the session is unknown (register again).
    pub fn heartbeat(&self, session: &Session) -> bool {
        Self::known(&mut self.lock(), session)
    }

    /// Up to `max` leases, waiting at most `wait` for work; `None` for an unknown session.
    pub async fn pull(
        &self,
        session: &Session,
        max: u32,
        wait: Duration,
    ) -> Option<Vec<pb::Lease>> {
        let deadline = tokio::time::Instant::now() + wait.min(Duration::from_secs(30));
        loop {
            let notified = self.work.notified();
            tokio::pin!(notified);
            notified.as_mut().enable();
            {
                let mut st = self.lock();
                if !Self::known(&mut st, session) {
                    return None;
                }
                let leases = self.grant(st, session.worker, max);
                if !leases.is_empty() {
                    return Some(leases);
                }
            }
            if tokio::time::timeout_at(deadline, notified).await.is_err() {
                return Some(Vec::new());
            }
        }
    }

    /// Up to `max` new leases for `worker`, signed for the wire; a queued job whose first tile
    /// goes out starts running.
    fn grant(
        &self,
        mut st: MutexGuard<'_, FarmState>,
        worker: WorkerId,
        max: u32,
    ) -> Vec<pb::Lease> {
        let leases = st.scheduler.lease(worker, max.clamp(1, 64), Instant::now());
        let Some(identity) = st.workers.get(&worker).map(|w| w.identity) else { return Vec::new() };
        let mut out = Vec::with_capacity(leases.len());
        let mut started = Vec::new();
        for l in leases {
            let Some(record) = st.jobs.get_mut(&l.job) else { continue };
            if record.start() {
                started.push(l.job.clone());
            }
            let Some(place) = record.place(l.tile) else { continue };
            let Some(rect) = place.plan.tile_rect(place.tile) else { continue };
            out.push(self.signer.grant(&l, rect, place.frame, &identity));
        }
        drop(st);
        self.deadline_added();
        for id in &started {
            self.persist(id);
        }
        if !started.is_empty() {
            self.bump();
        }
        out
    }

    /// Checks that `claim` is a lease this store granted to `session`'s worker: its ticket
    /// verifies with the identity the session registered with (so an earlier run's lease is
    /// deliverable by its own worker, registered again, and by nobody else), and in this run it
    /// names the session's worker id.
    fn check_claim(&self, st: &FarmState, session: &Session, claim: &LeaseClaim) -> Result<()> {
        let foreign = |problem| FarmError::ForeignLease {
            job: claim.job.to_string(),
            tile: claim.tile,
            problem,
        };
        if claim.epoch > self.signer.epoch() {
            return Err(foreign("it names a run of the coordinator that has not happened"));
        }
        if claim.epoch == self.signer.epoch() && claim.holder != session.worker {
            return Err(foreign("it was granted to another worker"));
        }
        let identity = st.workers.get(&session.worker).map_or([0; 32], |w| w.identity);
        if !self.signer.verify(claim, &identity) {
            return Err(foreign(
                "its ticket is not one this coordinator gave out to this worker (a lease is bound \
                 to the identity of the worker it was granted to)",
            ));
        }
        Ok(())
    }

    /// How a report of `claim` stands, before its pixels are read.
    pub fn expect_report(&self, session: &Session, claim: &LeaseClaim) -> Result<Expected> {
        let mut st = self.lock();
        if !Self::known(&mut st, session) {
            return Ok(Expected::UnknownSession);
        }
        self.check_claim(&st, session, claim)?;
        let Some(r) = st.jobs.get(&claim.job) else { return Ok(Expected::Stale) };
        if !matches!(r.state(), JobState::Queued | JobState::Running) {
            return Ok(Expected::Stale);
        }
        let Some(place) = r.place(claim.tile) else { return Ok(Expected::Stale) };
        match place.plan.tile_rect(place.tile) {
            Some(rect) => Ok(Expected::Tile { rect, layout: TileLayout::from(place.plan) }),
            None => Ok(Expected::Stale),
        }
    }

    /// A worker's result for `claim`: its pixels checked (a value no tracer produces counts as
    /// the worker's failure of the tile), then decided (only the tile's current lease, or an
    /// earlier run's lease of a tile not yet done, is accepted), then stored; the tile is done
    /// once the store has it.
    pub async fn report(
        self: &Arc<Self>,
        session: &Session,
        claim: &LeaseClaim,
        render_s: f64,
        data: Vec<u8>,
    ) -> Result<Reported> {
        let (rect, layout) = match self.expect_report(session, claim)? {
            Expected::UnknownSession => return Ok(Reported::UnknownSession),
            Expected::Stale => return Ok(Reported::Stale),
            Expected::Tile { rect, layout } => (rect, layout),
        };
        let tile = claim.tile;
        // A large tile (spectral layers) is checked on the blocking pool, a small one here.
        let (checked, data) = if data.len() < 1 << 20 {
            (check_tile(tile, &rect, layout, &data), data)
        } else {
            tokio::task::spawn_blocking(move || (check_tile(tile, &rect, layout, &data), data))
                .await?
        };
        if let Err(e) = checked {
            let reason = format!("sent pixels no tracer produces: {e}");
            warn!(job = %claim.job, tile, worker = %session.worker, "{reason}");
            self.fail(session, claim, &reason, false)?;
            return Err(FarmError::TileData { job: claim.job.clone(), tile, problem: e.problem });
        }
        self.metrics.tile_bytes_received.inc_by(data.len() as u64);
        if render_s.is_finite() && render_s >= 0.0 {
            self.metrics.tile_render_seconds.observe(render_s);
        }
        // Either the result is to be stored (and whether to check it), or it is a check's.
        let decided = {
            let mut st = self.lock();
            if !Self::known(&mut st, session) {
                return Ok(Reported::UnknownSession);
            }
            let current = claim.epoch == self.signer.epoch();
            let completion = if current {
                st.scheduler.complete(&self.signer.lease(claim), Instant::now())
            } else {
                st.scheduler.complete_inherited(&claim.job, tile)
            };
            match completion {
                Completion::Stale => return Ok(Reported::Stale),
                Completion::Check { renderer, disputed_by } => {
                    let checker = st.workers.get(&session.worker).map_or(0, |w| w.identity_key);
                    let claim = claim.clone();
                    Err(checks::CheckReport { claim, checker, renderer, disputed_by, data })
                }
                Completion::Accepted => {
                    let check = current && self.wants_check(&st, session.worker, claim);
                    let identity = st.workers.get(&session.worker).map_or(0, |w| w.identity_key);
                    // Queued under the lock: ordered before any later removal of the job's tiles.
                    Ok((self.commits.put(claim.job.clone(), tile, data), check, identity))
                }
            }
        };
        let (committed, check, identity) = match decided {
            Ok(stored) => stored,
            Err(report) => {
                // Runs on its own for the reason given below.
                let farm = self.clone();
                return tokio::spawn(async move { farm.compare(report).await })
                    .await
                    .map_err(|e| FarmError::Internal(format!("comparing a check: {e}")))?;
            }
        };
        // From here the tile is the scheduler's "committing" and only `settle` moves it on. The
        // caller's future may be dropped at any await (tonic drops a call whose worker hung up,
        // as a killed worker does mid-report), so the rest runs as a task of its own: otherwise
        // the tile would stay committing, never done nor requeued, and its job never end.
        let (farm, claim, worker) = (self.clone(), claim.clone(), session.worker);
        let by = (worker, identity);
        tokio::spawn(async move { farm.settle(committed, &claim, by, render_s, check).await })
            .await
            .map_err(|e| FarmError::Internal(format!("settling a tile: {e}")))?
    }

    /// The end of a report: once the store has the tile (or could not take it), the scheduler
    /// hears of it: the tile is done (and the last tile of a job starts its assembly), or, to be
    /// `check`ed, waits for another worker's rendering. A result of a worker (`by`: its id and
    /// identity key) quarantined while it was being stored is not kept.
    async fn settle(
        self: &Arc<Self>,
        committed: crate::group_commit::Committed,
        claim: &LeaseClaim,
        (worker, identity): (WorkerId, u64),
        render_s: f64,
        check: bool,
    ) -> Result<Reported> {
        let tile = claim.tile;
        let stored = committed.wait().await;
        let quarantined = self.lock().quarantine.contains_key(&identity);
        match stored {
            Ok(()) if quarantined => {
                let mut st = self.lock();
                if let Err(e) = self.store.remove_tile_list(&claim.job, &[tile]) {
                    warn!(job = %claim.job, tile, "could not forget a quarantined worker's tile: {e}");
                }
                st.scheduler.commit_failed(&claim.job, tile, None, Instant::now());
                drop(st);
                self.work.notify_waiters();
                Ok(Reported::Stale)
            }
            Ok(()) if check => {
                self.lock().scheduler.committed_for_check(&claim.job, tile);
                debug!(job = %claim.job, tile, %worker, render_s, "tile stored; to be checked");
                self.work.notify_waiters();
                self.bump();
                Ok(Reported::Accepted)
            }
            Ok(()) => {
                let next = {
                    let mut st = self.lock();
                    let last = st.scheduler.committed(&claim.job, tile);
                    Self::tile_done(&mut st, &claim.job, tile, last)
                };
                debug!(job = %claim.job, tile, %worker, render_s, "tile done");
                self.follow(&claim.job, next);
                Ok(Reported::Accepted)
            }
            Err(e) => {
                warn!(job = %claim.job, tile, "could not store the tile: {e}; its worker may send it again");
                let lease = (claim.epoch == self.signer.epoch()).then(|| self.signer.lease(claim));
                let mut st = self.lock();
                st.scheduler.commit_failed(&claim.job, tile, lease.as_ref(), Instant::now());
                drop(st);
                self.work.notify_waiters();
                self.bump();
                Err(e.into())
            }
        }
    }

    /// A tile of `job` is done (`last`: the job's last): counted towards its frame, and the
    /// job's assembly begun when it was the last. What follows, for [`Farm::follow`].
    fn tile_done(st: &mut FarmState, job: &JobId, tile: u32, last: bool) -> Next {
        let frame_whole = Self::count_frame_tile(st, job, tile);
        let finished = last && st.jobs.get_mut(job).is_some_and(|r| r.begin_assembly().is_ok());
        let sequence = st.jobs.get(job).is_some_and(JobRecord::is_sequence);
        Next { finished, frames: sequence && (finished || frame_whole) }
    }

    /// What follows tiles becoming done: the record kept, the frames written, the still
    /// assembled.
    fn follow(self: &Arc<Self>, job: &JobId, next: Next) {
        if next.finished {
            self.persist(job);
        }
        if next.frames {
            self.kick_frames(job);
        } else if next.finished {
            let (farm, id) = (self.clone(), job.clone());
            tokio::task::spawn_blocking(move || assembly::assemble(&farm, &id));
        }
        self.bump();
    }

    /// A worker could not render its tile. A `retryable` failure (the transport's, not the
    /// tile's) hands the tile back; any other counts against the worker and the tile, and may
    /// fail the job. `None` for an unknown session; else whether the lease was current.
    pub fn fail(
        &self,
        session: &Session,
        claim: &LeaseClaim,
        reason: &str,
        retryable: bool,
    ) -> Result<Option<bool>> {
        let reason = printable(reason, 2000);
        let outcome = {
            let mut st = self.lock();
            if !Self::known(&mut st, session) {
                return Ok(None);
            }
            self.check_claim(&st, session, claim)?;
            if claim.epoch != self.signer.epoch() {
                return Ok(Some(false));
            }
            let lease = self.signer.lease(claim);
            warn!(job = %claim.job, tile = claim.tile, worker = %session.worker, retryable, "tile failed: {reason}");
            if retryable {
                if st.scheduler.give_back(&lease, Instant::now()) {
                    Failure::Requeued
                } else {
                    Failure::Stale
                }
            } else {
                let outcome = st.scheduler.fail(&lease, &reason, Instant::now());
                if let Failure::JobFailed { reason } = &outcome {
                    let reason = reason.clone();
                    let _ = self.end_job(&mut st, &claim.job, |r, done| r.fail(reason, done));
                }
                outcome
            }
        };
        match outcome {
            Failure::Requeued => {
                self.work.notify_waiters();
                self.bump();
                Ok(Some(true))
            }
            Failure::JobFailed { reason } => {
                warn!(job = %claim.job, "job failed: {reason}");
                self.persist(&claim.job);
                self.bump();
                Ok(Some(true))
            }
            Failure::Stale => Ok(Some(false)),
        }
    }

    /// A worker hands back leases it will not finish, and, `leaving`, every other lease it
    /// holds and its session. `None` for an unknown session; else whether any tile went back.
    pub fn return_leases(
        self: &Arc<Self>,
        session: &Session,
        claims: &[LeaseClaim],
        leaving: bool,
    ) -> Result<Option<bool>> {
        let any = {
            let mut st = self.lock();
            if !Self::known(&mut st, session) {
                return Ok(None);
            }
            let mut any = false;
            for claim in claims {
                self.check_claim(&st, session, claim)?;
                if claim.epoch == self.signer.epoch() {
                    any |= st.scheduler.give_back(&self.signer.lease(claim), Instant::now());
                }
            }
            if leaving {
                let returned = st.scheduler.remove_worker(session.worker, Instant::now());
                st.workers.remove(&session.worker);
                info!(worker = %session.worker, returned = returned.len(), "worker left");
                any |= !returned.is_empty();
            }
            any
        };
        if leaving {
            self.waive_checks();
        }
        if any {
            self.work.notify_waiters();
            self.bump();
        }
        Ok(Some(any))
    }

    /// What a worker renders for frame `frame` of job `id` (frame 0 of a still): for a
    /// sequence, the job's scene with the frame's changes.
    pub fn worker_job(&self, session: &Session, id: &JobId, frame: u32) -> Result<WorkerJob> {
        let (manifest, plan, first_tile, change) = {
            let mut st = self.lock();
            if !Self::known(&mut st, session) {
                return Err(FarmError::UnknownSession { worker: session.worker.0 });
            }
            let r = st.jobs.get(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
            let no_frame = || FarmError::NoSuchFrame { job: id.clone(), frame };
            let plan = r.frame_plan(frame).ok_or_else(no_frame)?.clone();
            let change = r.spec.frames.get(frame as usize).cloned();
            (r.manifest_json.clone(), plan, r.frame_range(frame).start, change)
        };
        let manifest_json = match change {
            None => manifest,
            Some(change) => sequence_frame::frame_manifest(&manifest, &change)?,
        };
        Ok(WorkerJob { manifest_json, plan, limits: self.config.limits, first_tile })
    }

    /// The file of an asset, for a worker.
    pub fn asset_path(&self, session: &Session, reference: &str) -> Result<PathBuf> {
        if !Self::known(&mut self.lock(), session) {
            return Err(FarmError::UnknownSession { worker: session.worker.0 });
        }
        let hash = asset_hash(reference)?;
        if !self.assets.has(hash) {
            return Err(FarmError::AssetMissing { reference: reference.to_owned() });
        }
        Ok(self.assets.path(hash))
    }

    // ------------------------------------------------------------------ time

    /// Expires overdue leases and silent workers.
    pub fn expire(self: &Arc<Self>) {
        let mut st = self.lock();
        let before = st.scheduler.totals();
        let expired = st.scheduler.expire(Instant::now());
        let after = st.scheduler.totals();
        let lost = after.workers_lost - before.workers_lost;
        if lost > 0 {
            warn!(workers = lost, "dropped worker(s) silent past the heartbeat timeout");
            let known: std::collections::HashSet<WorkerId> =
                st.scheduler.workers().iter().map(|w| w.id).collect();
            st.workers.retain(|id, _| known.contains(id));
            drop(st);
            self.waive_checks();
            st = self.lock();
        }
        if !expired.is_empty() {
            // The first ones ran past the lease timeout; the rest were held by dropped workers.
            let timed_out = (after.lease_expiries - before.lease_expiries) as usize;
            for (i, l) in expired.iter().enumerate() {
                let why = if i < timed_out { "lease expired" } else { "worker dropped" };
                info!(job = %l.job, tile = l.tile, attempt = l.attempt, worker = %l.worker, "{why}; tile requeued");
            }
            drop(st);
            self.work.notify_waiters();
            self.bump();
        }
    }

    /// A lease was granted or a worker registered: wakes the timer if the new deadline may
    /// come before the one it sleeps towards (new deadlines are at least the shorter timeout
    /// away, so usually it need not wake).
    fn deadline_added(&self) {
        let c = &self.config.scheduler;
        let soonest = Instant::now() + c.lease_timeout.min(c.heartbeat_timeout);
        let wakes = *self.timer_wakes.lock().unwrap_or_else(|p| p.into_inner());
        if wakes.is_none_or(|at| soonest < at) {
            self.timer.notify_one();
        }
    }

    /// Expires leases and workers as their deadlines come, from the scheduler's own next
    /// deadline (woken early when a new one may be nearer). Runs until the runtime stops.
    pub async fn run_timer(self: Arc<Self>) {
        loop {
            *self.timer_wakes.lock().unwrap_or_else(|p| p.into_inner()) = None;
            let next = self.lock().scheduler.next_deadline();
            let at = next.unwrap_or_else(|| Instant::now() + Duration::from_secs(60));
            *self.timer_wakes.lock().unwrap_or_else(|p| p.into_inner()) = Some(at);
            let until = tokio::time::Instant::from_std(at);
            tokio::select! {
                () = tokio::time::sleep_until(until) => self.expire(),
                () = self.timer.notified() => {}
            }
        }
    }
}

/// Removes the temporary files that a coordinator killed while writing results left behind.
fn remove_leftover_results(jobs_dir: &Path) {
    let Ok(entries) = std::fs::read_dir(jobs_dir) else { return };
    for entry in entries.flatten() {
        let dir = entry.path();
        if dir.is_dir() {
            match restauro_image::atomic_file::remove_leftovers(&dir) {
                Ok(0) => {}
                Ok(n) => info!(dir = %dir.display(), files = n, "removed unfinished result files"),
                Err(e) => warn!(dir = %dir.display(), "could not clean up: {e}"),
            }
        }
    }
}

/// What the operations endpoint reports for the coordinator.
impl restauro_ops::endpoint::Probe for Farm {
    fn refresh(&self) {
        let st = self.lock();
        let unfinished = st.jobs.values().filter(|r| !r.state().is_final()).count() as u64;
        self.metrics.update(st.scheduler.gauges(), st.scheduler.totals(), unfinished);
        self.metrics.store_failing.set(i64::from(self.store.problem().is_some()));
        self.metrics.objects_failing.set(i64::from(self.objects.problem().is_some()));
    }

    fn registry(&self) -> &prometheus_client::registry::Registry {
        self.metrics.registry()
    }

    /// Not ready while the store or the object store cannot be written: new work would only
    /// fail.
    fn ready(&self) -> std::result::Result<(), restauro_ops::endpoint::NotReady> {
        self.problem().map_or(Ok(()), |why| Err(restauro_ops::endpoint::NotReady(why)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn farm(dir: &Path) -> Arc<Farm> {
        Farm::open(Config {
            data_dir: dir.to_owned(),
            store: None,
            objects: None,
            tokens: Tokens::new("c", "w"),
            limits: Limits::default(),
            max_jobs: 4,
            max_upload_bytes: 1 << 20,
            max_scene_loads: 2,
            scheduler: scheduler::Config::default(),
            checks: CheckPolicy::default(),
            retinex: false,
            commit_delay: Duration::ZERO,
            callers: Default::default(),
        })
        .unwrap()
    }

    /// Defect 5: ids were packed into 16 bits, so the 65 536th registration aliased the first.
    /// Every registration is its own worker, and a session is only its own with its key.
    #[test]
    fn seventy_thousand_registrations_are_seventy_thousand_workers() {
        let dir = tempfile::tempdir().unwrap();
        let farm = farm(dir.path());
        let sessions: Vec<Session> = (0..70_000)
            .map(|i| farm.register(&format!("w{i}"), 1, "b", &[0; 32]).unwrap().0)
            .collect();
        let ids: std::collections::HashSet<WorkerId> = sessions.iter().map(|s| s.worker).collect();
        assert_eq!(ids.len(), 70_000);
        assert!(farm.heartbeat(&sessions[0]) && farm.heartbeat(&sessions[69_999]));
        let posing = Session { worker: sessions[0].worker, key: sessions[1].key };
        assert!(!farm.heartbeat(&posing));
        assert_eq!(farm.return_leases(&posing, &[], true).unwrap(), None);
        assert!(farm.heartbeat(&sessions[0]), "a forged leave changed nothing");
        assert_eq!(farm.workers().len(), 70_000);
    }

    /// A quarantined worker is refused when it registers again, also by the coordinator
    /// restarted on the same store, and is listed with the reason; another identity is not.
    #[test]
    fn a_quarantine_outlives_the_coordinator() {
        let dir = tempfile::tempdir().unwrap();
        let (liar, honest) = ([1u8; 32], [2u8; 32]);
        {
            let farm = farm(dir.path());
            let (session, _) = farm.register("liar", 1, "b", &liar).unwrap();
            let key = checks::identity_key(&crate::lease::identity_digest(&liar));
            farm.quarantine(key, "its rendering of tile 3 differed".into());
            assert!(!farm.heartbeat(&session), "its session outlived the quarantine");
            assert!(farm.workers().is_empty());
        }
        let farm = farm(dir.path());
        let e = farm.register("liar", 1, "b", &liar).unwrap_err();
        assert_eq!(tonic::Status::from(e).code(), tonic::Code::PermissionDenied);
        let e = farm.register("renamed", 1, "b", &liar).unwrap_err().to_string();
        assert!(e.contains("worker liar is quarantined: its rendering of tile 3 differed"), "{e}");
        let listed = farm.quarantined();
        assert_eq!(listed.len(), 1);
        assert_eq!(
            (listed[0].name.as_str(), listed[0].reason.as_str()),
            ("liar", "its rendering of tile 3 differed")
        );
        assert!(farm.register("honest", 1, "b", &honest).is_ok());
    }

    /// A worker's name and build are shown to others: control characters are refused.
    #[test]
    fn a_worker_named_with_control_characters_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let farm = farm(dir.path());
        let e = farm.register("w\u{1b}[2J", 1, "b", &[0; 32]).unwrap_err();
        assert!(e.to_string().contains("name: character"), "{e}");
        assert!(farm.register("w", 1, &"b".repeat(300), &[0; 32]).is_err());
    }

    /// A store written by protocol 1: its job is listed as failed with the reason, and its tiles
    /// and assets do not stay in the store.
    #[test]
    fn an_earlier_releases_store_opens_with_its_jobs_listed_as_failed() {
        let dir = tempfile::tempdir().unwrap();
        {
            let store = Store::open(&dir.path().join("store.redb")).unwrap();
            let old = br#"{"id":"o","name":"aosta","state":"running","options":{}}"#;
            store.put_job("o", old).unwrap();
            store.put_tiles(&[("o", 0, &[1u8, 2, 3][..])]).unwrap();
        }
        let farm = farm(dir.path());
        let jobs = farm.jobs();
        assert_eq!(jobs.len(), 1);
        assert_eq!((jobs[0].state, jobs[0].name.as_str()), (JobState::Failed, "aosta"));
        assert!(jobs[0].error.contains("earlier restauro release"), "{}", jobs[0].error);
        assert!(farm.store.finished_tiles("o").unwrap().is_empty());
        let (_, bytes) = farm.store.jobs().unwrap().remove(0);
        assert_eq!(JobRecord::from_bytes("o", &bytes).unwrap().format, crate::job::RECORD_FORMAT);
    }
}
