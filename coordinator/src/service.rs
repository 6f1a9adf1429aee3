//! The coordinator's two gRPC services over one shared state: `Render` for clients (assets,
//! jobs, results) and `Work` for workers (registration, leases, results, assets).
//!
//! Locks: one `std::sync::Mutex` over the scheduler and the job table, never held across an
//! `.await` or a store write; store writes and image work run on tokio's blocking pool.

use crate::auth::Tokens;
use crate::group_commit::TileCommits;
use crate::jobs::{Options, Record, State};
use crate::metrics::Metrics;
use crate::scheduler::{self, Completion, Failure, Lease, Scheduler};
use crate::store::Store;
use restauro_image::framebuffer::{Framebuffer, tile_sizes};
use restauro_image::results::{ResultOptions, parse_exposure, write_results};
use restauro_proto::{self as pb, CHUNK_BYTES, PROTOCOL_VERSION};
use restauro_scene::bundle::Bundle;
use restauro_scene::load::Limits;
use restauro_scene::plan::Plan;
use restauro_spectral::retinex::RetinexParams;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::pin::Pin;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use tokio::sync::{Notify, mpsc, watch};
use tokio_stream::wrappers::ReceiverStream;
use tokio_stream::{Stream, StreamExt};
use tonic::{Request, Response, Status, Streaming};
use tracing::{debug, info, warn};

type Stream2<T> = Pin<Box<dyn Stream<Item = Result<T, Status>> + Send + 'static>>;

/// How the coordinator runs.
#[derive(Clone)]
pub struct Config {
    /// The store (`store.redb`) and the results (`jobs/<id>/`).
    pub data_dir: PathBuf,
    pub tokens: Tokens,
    pub limits: Limits,
    /// Unfinished jobs at once; more are refused (RESOURCE_EXHAUSTED).
    pub max_jobs: usize,
    pub scheduler: scheduler::Config,
    /// Run the Retinex stage and write its files.
    pub retinex: bool,
}

pub struct Shared {
    config: Config,
    store: Arc<Store>,
    /// Finished tiles on their way into the store, committed in groups.
    tile_commits: TileCommits,
    state: Mutex<State2>,
    /// Woken when tiles are queued (new job, requeue), for waiting `PullLeases` calls.
    work: Notify,
    /// Bumped on every change of a job, for `WatchJob` streams.
    changed: watch::Sender<u64>,
    /// High bits of every worker id this run hands out: a worker registered with an earlier run
    /// of the coordinator is unknown to this one, never mistaken for another worker.
    epoch: u64,
    pub metrics: Metrics,
}

struct State2 {
    scheduler: Scheduler,
    jobs: BTreeMap<String, Record>,
    /// Each worker's build, as it registered.
    builds: HashMap<u64, String>,
    /// When each job's tiles started and the time of the last finished tile.
    started: HashMap<String, Instant>,
}

fn now_unix_ms() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64)
}

fn internal(status: impl std::fmt::Display) -> Status {
    Status::internal(status.to_string())
}

/// Parses `blake3:<64 hex>.<ext>` into its hash, refusing anything else.
fn asset_hash(reference: &str) -> Result<&str, Status> {
    let hash = reference
        .strip_prefix("blake3:")
        .and_then(|r| r.split_once('.').map(|(h, _)| h))
        .filter(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()));
    hash.ok_or_else(|| {
        Status::invalid_argument(format!(
            "asset reference `{reference}`: expected `blake3:<64 hex digits>.<extension>`"
        ))
    })
}

/// What the operations endpoint reports for the coordinator.
impl restauro_ops::endpoint::Probe for Shared {
    fn refresh(&self) {
        let st = self.lock();
        let unfinished = st.jobs.values().filter(|r| !r.state.is_final()).count() as u64;
        self.metrics.update(st.scheduler.gauges(), st.scheduler.totals(), unfinished);
    }

    fn registry(&self) -> &prometheus_client::registry::Registry {
        self.metrics.registry()
    }

    /// The store is open once `Shared` exists; the coordinator is ready while it serves.
    fn ready(&self) -> Result<(), String> {
        Ok(())
    }
}

impl Shared {
    /// Opens the store in `config.data_dir` and resumes every unfinished job in it.
    pub fn open(config: Config) -> anyhow::Result<Arc<Shared>> {
        use anyhow::Context;
        std::fs::create_dir_all(config.data_dir.join("jobs"))
            .with_context(|| format!("creating {}", config.data_dir.display()))?;
        let store = Arc::new(Store::open(&config.data_dir.join("store.redb"))?);
        let tile_commits =
            TileCommits::start(store.clone()).context("starting the store's committer")?;
        let epoch =
            (now_unix_ms() & 0x7fff_ffff) << 32 | u64::from(std::process::id() & 0xffff) << 16;
        let shared = Arc::new(Shared {
            store,
            tile_commits,
            state: Mutex::new(State2 {
                scheduler: Scheduler::new(config.scheduler.clone()),
                jobs: BTreeMap::new(),
                builds: HashMap::new(),
                started: HashMap::new(),
            }),
            config,
            work: Notify::new(),
            changed: watch::Sender::new(0),
            epoch,
            metrics: Metrics::new(),
        });
        let mut to_assemble = Vec::new();
        for (id, bytes) in shared.store.jobs()? {
            let mut record = Record::from_bytes(&bytes)
                .with_context(|| format!("job {id} in the store is unreadable"))?;
            let mut st = shared.lock();
            if !record.state.is_final() {
                let done = shared.store.finished_tiles(&id)?;
                let total = record.tile_count();
                info!(job = %id, done = done.len(), total, "resuming job");
                if matches!(record.state, State::Assembling | State::PostProcessing)
                    || done.len() as u32 == total
                {
                    record.state = State::Assembling;
                    to_assemble.push(id.clone());
                }
                st.scheduler
                    .add_job(id.clone(), record.priority, total, &done, Instant::now())
                    .map_err(|e| anyhow::anyhow!("job {id}: {e:?}"))?;
                st.started.insert(id.clone(), Instant::now());
            }
            st.jobs.insert(id, record);
        }
        for id in to_assemble {
            let s = shared.clone();
            std::thread::spawn(move || s.assemble(&id));
        }
        Ok(shared)
    }

    fn lock(&self) -> MutexGuard<'_, State2> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn bump(&self) {
        self.changed.send_modify(|v| *v += 1);
    }

    fn worker_id(&self, external: u64) -> u64 {
        if external & !0xffff == self.epoch { external & 0xffff } else { 0 }
    }

    fn persist(&self, record: &Record) {
        if let Err(e) = self.store.put_job(&record.id, &record.to_bytes()) {
            warn!(job = %record.id, "could not store the job record: {e}");
        }
    }

    fn status(&self, st: &State2, record: &Record) -> pb::JobStatus {
        let progress = st.scheduler.progress(&record.id);
        let total = record.tile_count();
        let done =
            if matches!(record.state, State::Done | State::Assembling | State::PostProcessing) {
                total
            } else {
                progress.as_ref().map_or(0, |p| p.done)
            };
        pb::JobStatus {
            job_id: record.id.clone(),
            name: record.name.clone(),
            state: record.state.to_proto() as i32,
            tiles_total: total,
            tiles_done: done,
            tiles_leased: progress.as_ref().map_or(0, |p| p.leased),
            tiles_requeued: progress.as_ref().map_or(0, |p| p.requeued),
            error: record.error.clone(),
            priority: record.priority,
            width: record.width,
            height: record.height,
            elapsed_s: now_unix_ms().saturating_sub(record.submitted_unix_ms) as f64 / 1e3,
            results: record.results.clone(),
        }
    }

    /// Expires overdue leases and silent workers; called on a timer.
    pub fn expire(&self) {
        let mut st = self.lock();
        let before = st.scheduler.totals();
        let expired = st.scheduler.expire(Instant::now());
        let after = st.scheduler.totals();
        let lost = after.workers_lost - before.workers_lost;
        if lost > 0 {
            warn!(workers = lost, "dropped worker(s) silent past the heartbeat timeout");
        }
        if !expired.is_empty() {
            // The first ones ran past the lease timeout; the rest were held by dropped workers.
            let timed_out = (after.lease_expiries - before.lease_expiries) as usize;
            for (i, l) in expired.iter().enumerate() {
                let why = if i < timed_out { "lease expired" } else { "worker dropped" };
                info!(job = %l.job, tile = l.tile, attempt = l.attempt, worker = l.worker, "{why}; tile requeued");
            }
            drop(st);
            self.work.notify_waiters();
            self.bump();
        }
    }

    /// Marks a job failed, with the reason.
    fn fail_job(&self, id: &str, reason: String) {
        let mut st = self.lock();
        st.scheduler.cancel(id);
        if let Some(r) = st.jobs.get_mut(id) {
            r.state = State::Failed;
            r.error = reason;
            let r = r.clone();
            drop(st);
            warn!(job = %id, "job failed: {}", r.error);
            self.persist(&r);
            self.bump();
        }
    }

    fn set_state(&self, id: &str, state: State) -> Option<Record> {
        let mut st = self.lock();
        let r = st.jobs.get_mut(id)?;
        r.state = state;
        let r = r.clone();
        drop(st);
        self.persist(&r);
        self.bump();
        Some(r)
    }

    /// Assembles a job whose tiles are all stored, runs the Retinex and writes the results.
    /// Runs on a blocking thread.
    fn assemble(&self, id: &str) {
        let _span = tracing::info_span!("assemble", job = %id).entered();
        let Some(record) = self.set_state(id, State::Assembling) else { return };
        let started = Instant::now();
        let outcome = (|| -> Result<Vec<String>, String> {
            let mut frame =
                Framebuffer::new(record.width, record.height, record.options.spectral, record.sky);
            for (index, rect) in record.tiles().iter().enumerate() {
                let data = self
                    .store
                    .tile(id, index as u32)
                    .map_err(|e| e.to_string())?
                    .ok_or_else(|| format!("tile {index} is missing from the store"))?;
                frame.place(index as u32, rect, &data).map_err(|e| e.to_string())?;
            }
            self.set_state(id, State::PostProcessing);
            let dir = self.config.data_dir.join("jobs").join(id);
            std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            let exposure = parse_exposure(&record.options.exposure)?;
            let retinex = self.config.retinex.then(|| RetinexParams {
                paths: if record.options.retinex_paths == 0 {
                    RetinexParams::default().paths
                } else {
                    record.options.retinex_paths
                },
                seed: record.options.retinex_seed,
                ..RetinexParams::default()
            });
            let stem = record.file_stem();
            let options = ResultOptions { name: &stem, info: &record.info, exposure, retinex };
            let written = write_results(&dir, frame, &options).map_err(|e| e.to_string())?;
            info!(job = %id, retinex_s = written.retinex_s, "results written");
            if self.config.retinex {
                self.metrics.retinex_seconds.observe(written.retinex_s);
            }
            Ok(written.files)
        })();
        match outcome {
            Ok(files) => {
                let mut st = self.lock();
                st.scheduler.remove_job(id);
                if let Some(r) = st.jobs.get_mut(id) {
                    r.state = State::Done;
                    r.results = files;
                    let r = r.clone();
                    drop(st);
                    self.persist(&r);
                    if let Err(e) = self.store.remove_tiles(id) {
                        warn!(job = %id, "could not drop the finished tiles: {e}");
                    }
                    info!(job = %id, seconds = started.elapsed().as_secs_f64(), "job done");
                    self.bump();
                }
            }
            Err(reason) => self.fail_job(id, reason),
        }
    }

    /// Up to `max` new leases for worker `id` (known to the scheduler), as sent on the wire; a
    /// queued job whose first tile goes out becomes running (stored after the lock is released).
    fn grant(&self, mut st: MutexGuard<'_, State2>, id: u64, max: u32) -> Vec<pb::Lease> {
        let leases = st.scheduler.lease(id, max.clamp(1, 64), Instant::now());
        let mut out = Vec::with_capacity(leases.len());
        let mut started = Vec::new();
        for l in leases {
            let Some(record) = st.jobs.get_mut(&*l.job) else { continue };
            if record.state == State::Queued {
                record.state = State::Running;
                started.push(record.clone());
            }
            let Some(rect) = record.tile(l.tile) else { continue };
            out.push(pb::Lease {
                job_id: l.job.to_string(),
                tile: l.tile,
                attempt: l.attempt,
                rect: Some(pb::Rect {
                    x: rect.x,
                    y: rect.y,
                    width: rect.width,
                    height: rect.height,
                }),
            });
        }
        drop(st);
        for record in &started {
            self.persist(record);
        }
        if !started.is_empty() {
            self.bump();
        }
        out
    }

    /// Every asset a manifest names, from the store; refuses the manifest when one is missing.
    fn bundle(&self, manifest_json: &str) -> Result<Bundle, Status> {
        let scene = Bundle::parse_manifest(manifest_json).map_err(|e| {
            Status::invalid_argument(format!("the scene manifest is not a scene bundle: {e}"))
        })?;
        let skeleton = Bundle { scene, files: BTreeMap::new() };
        let mut files = BTreeMap::new();
        for reference in skeleton.references() {
            let hash = asset_hash(&reference)?;
            let bytes = self.store.asset(hash).map_err(internal)?.ok_or_else(|| {
                Status::failed_precondition(format!(
                    "asset {reference} has not been uploaded; upload it before submitting"
                ))
            })?;
            files.insert(hash.to_owned(), bytes);
        }
        Bundle::from_parts(manifest_json, files)
            .map_err(|e| Status::invalid_argument(e.to_string()))
    }
}

/// The client-facing service.
pub struct RenderService(pub Arc<Shared>);
/// The worker-facing service.
pub struct WorkService(pub Arc<Shared>);

fn chunk_stream(name: String, data: Vec<u8>) -> Stream2<pb::Chunk> {
    let total = data.len() as u64;
    let chunks: Vec<Result<pb::Chunk, Status>> = if data.is_empty() {
        vec![Ok(pb::Chunk { name, total_bytes: 0, data: Vec::new() })]
    } else {
        data.chunks(CHUNK_BYTES)
            .enumerate()
            .map(|(i, c)| {
                Ok(pb::Chunk {
                    name: if i == 0 { name.clone() } else { String::new() },
                    total_bytes: total,
                    data: c.to_vec(),
                })
            })
            .collect()
    };
    Box::pin(tokio_stream::iter(chunks))
}

async fn blocking<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Result<T, Status> {
    tokio::task::spawn_blocking(f).await.map_err(internal)
}

#[tonic::async_trait]
impl pb::render_server::Render for RenderService {
    async fn missing_assets(
        &self,
        request: Request<pb::AssetList>,
    ) -> Result<Response<pb::AssetList>, Status> {
        let mut missing = Vec::new();
        for reference in request.into_inner().references {
            if !self.0.store.has_asset(asset_hash(&reference)?).map_err(internal)? {
                missing.push(reference);
            }
        }
        Ok(Response::new(pb::AssetList { references: missing }))
    }

    async fn upload_asset(
        &self,
        request: Request<Streaming<pb::Chunk>>,
    ) -> Result<Response<pb::AssetList>, Status> {
        let mut stream = request.into_inner();
        let first = stream
            .message()
            .await?
            .ok_or_else(|| Status::invalid_argument("an upload needs at least one chunk"))?;
        let reference = first.name.clone();
        let hash = asset_hash(&reference)?.to_owned();
        let max = self.0.config.limits.max_file_bytes;
        if first.total_bytes > max {
            return Err(Status::resource_exhausted(format!(
                "asset {reference} is {} bytes, over the limit of {max} (--max-file-bytes)",
                first.total_bytes
            )));
        }
        let mut data = first.data;
        while let Some(chunk) = stream.message().await? {
            if (data.len() + chunk.data.len()) as u64 > max {
                return Err(Status::resource_exhausted(format!(
                    "asset {reference} exceeds the limit of {max} bytes (--max-file-bytes)"
                )));
            }
            data.extend_from_slice(&chunk.data);
        }
        if blake3::hash(&data).to_hex().as_str() != hash {
            return Err(Status::invalid_argument(format!(
                "asset {reference}: the bytes received do not have this hash; upload it again"
            )));
        }
        self.0.metrics.asset_bytes_received.inc_by(data.len() as u64);
        let shared = self.0.clone();
        blocking(move || shared.store.put_asset(&hash, &data)).await?.map_err(internal)?;
        Ok(Response::new(pb::AssetList { references: vec![reference] }))
    }

    async fn submit_job(
        &self,
        request: Request<pb::SubmitJobRequest>,
    ) -> Result<Response<pb::JobStatus>, Status> {
        let req = request.into_inner();
        if req.protocol_version != PROTOCOL_VERSION {
            return Err(Status::failed_precondition(format!(
                "protocol version {} refused: this coordinator speaks protocol {PROTOCOL_VERSION}",
                req.protocol_version
            )));
        }
        {
            let st = self.0.lock();
            let open = st.jobs.values().filter(|r| !r.state.is_final()).count();
            if open >= self.0.config.max_jobs {
                return Err(Status::resource_exhausted(format!(
                    "{open} jobs are unfinished, the most this coordinator takes \
                     (--max-jobs); wait for one to finish or cancel one"
                )));
            }
        }
        let options = Options::from_proto(&req.options.unwrap_or_default());
        let render_options = options.render_options().map_err(Status::invalid_argument)?;
        parse_exposure(&options.exposure).map_err(Status::invalid_argument)?;
        let shared = self.0.clone();
        let manifest = req.manifest_json.clone();
        let name = req.name.clone();
        let plan = blocking(move || -> Result<Plan, Status> {
            let bundle = shared.bundle(&manifest)?;
            let limits = shared.config.limits;
            let scene =
                bundle.load(&limits).map_err(|e| Status::invalid_argument(e.to_string()))?;
            Plan::new(&scene, &render_options, &limits, Path::new(&format!("scene {name}")))
                .map_err(|e| Status::invalid_argument(e.to_string()))
        })
        .await??;
        let id = uuid::Uuid::new_v4().to_string();
        let integrator = format!("{:?}", plan.integrator).to_lowercase();
        let record = Record {
            id: id.clone(),
            name: req.name,
            priority: req.priority,
            manifest_json: req.manifest_json,
            options,
            state: State::Queued,
            error: String::new(),
            submitted_unix_ms: now_unix_ms(),
            width: plan.width,
            height: plan.height,
            tile: plan.tile,
            sky: plan.sky,
            info: format!(
                "variant={} integrator={integrator} spp={} max_depth={} seed={}",
                plan.variant.as_deref().unwrap_or("base"),
                plan.samples_per_pixel,
                plan.max_depth,
                plan.seed
            ),
            results: Vec::new(),
        };
        let shared = self.0.clone();
        let bytes = record.to_bytes();
        let key = id.clone();
        blocking(move || shared.store.put_job(&key, &bytes)).await?.map_err(internal)?;
        let status = {
            let mut st = self.0.lock();
            st.scheduler
                .add_job(id.clone(), record.priority, plan.tiles.len() as u32, &[], Instant::now())
                .map_err(|e| internal(format!("{e:?}")))?;
            st.started.insert(id.clone(), Instant::now());
            st.jobs.insert(id.clone(), record.clone());
            self.0.status(&st, &record)
        };
        info!(job = %id, name = %record.name, tiles = plan.tiles.len(), "job submitted");
        self.0.work.notify_waiters();
        self.0.bump();
        Ok(Response::new(status))
    }

    type WatchJobStream = Stream2<pb::JobStatus>;

    async fn watch_job(
        &self,
        request: Request<pb::JobRef>,
    ) -> Result<Response<Self::WatchJobStream>, Status> {
        let id = request.into_inner().job_id;
        let shared = self.0.clone();
        let missing = Status::not_found(format!("no job {id}"));
        let snapshot = move |shared: &Shared| -> Option<pb::JobStatus> {
            let st = shared.lock();
            st.jobs.get(&id).map(|r| shared.status(&st, r))
        };
        let first = snapshot(&shared).ok_or(missing)?;
        let (tx, rx) = mpsc::channel(16);
        let mut changes = shared.changed.subscribe();
        tokio::spawn(async move {
            let mut last = first;
            let mut done = pb::JobState::try_from(last.state).is_ok_and(|s| {
                matches!(s, pb::JobState::Done | pb::JobState::Failed | pb::JobState::Cancelled)
            });
            if tx.send(Ok(last.clone())).await.is_err() {
                return;
            }
            while !done {
                if changes.changed().await.is_err() {
                    return;
                }
                let Some(now) = snapshot(&shared) else { return };
                if now != last {
                    done = pb::JobState::try_from(now.state).is_ok_and(|s| {
                        matches!(
                            s,
                            pb::JobState::Done | pb::JobState::Failed | pb::JobState::Cancelled
                        )
                    });
                    if tx.send(Ok(now.clone())).await.is_err() {
                        return;
                    }
                    last = now;
                }
            }
        });
        Ok(Response::new(Box::pin(ReceiverStream::new(rx))))
    }

    type FetchResultStream = Stream2<pb::Chunk>;

    async fn fetch_result(
        &self,
        request: Request<pb::FetchResultRequest>,
    ) -> Result<Response<Self::FetchResultStream>, Status> {
        let req = request.into_inner();
        let known = {
            let st = self.0.lock();
            let record = st
                .jobs
                .get(&req.job_id)
                .ok_or_else(|| Status::not_found(format!("no job {}", req.job_id)))?;
            if record.state != State::Done {
                return Err(Status::failed_precondition(format!(
                    "job {} is {:?}, not done: its results are not written yet",
                    req.job_id, record.state
                )));
            }
            record.results.contains(&req.name)
        };
        if !known {
            return Err(Status::not_found(format!(
                "job {} has no result `{}`",
                req.job_id, req.name
            )));
        }
        let path = self.0.config.data_dir.join("jobs").join(&req.job_id).join(&req.name);
        let data = tokio::fs::read(&path)
            .await
            .map_err(|e| internal(format!("{}: {e}", path.display())))?;
        self.0.metrics.result_bytes_sent.inc_by(data.len() as u64);
        Ok(Response::new(chunk_stream(req.name, data)))
    }

    async fn cancel_job(
        &self,
        request: Request<pb::JobRef>,
    ) -> Result<Response<pb::JobStatus>, Status> {
        let id = request.into_inner().job_id;
        let mut st = self.0.lock();
        let state = st
            .jobs
            .get(&id)
            .map(|r| r.state)
            .ok_or_else(|| Status::not_found(format!("no job {id}")))?;
        if !state.is_final() {
            st.scheduler.cancel(&id);
            if let Some(r) = st.jobs.get_mut(&id) {
                r.state = State::Cancelled;
            }
        }
        let record = st.jobs[&id].clone();
        let status = self.0.status(&st, &record);
        drop(st);
        self.0.persist(&record);
        self.0.bump();
        Ok(Response::new(status))
    }

    async fn list_jobs(
        &self,
        _request: Request<pb::ListJobsRequest>,
    ) -> Result<Response<pb::JobList>, Status> {
        let st = self.0.lock();
        let jobs = st.jobs.values().map(|r| self.0.status(&st, r)).collect();
        Ok(Response::new(pb::JobList { jobs }))
    }

    async fn list_workers(
        &self,
        _request: Request<pb::ListWorkersRequest>,
    ) -> Result<Response<pb::WorkerList>, Status> {
        let st = self.0.lock();
        let now = Instant::now();
        let workers = st
            .scheduler
            .workers()
            .into_iter()
            .map(|w| pb::WorkerStatus {
                worker_id: self.0.epoch | w.id,
                name: w.name,
                capacity: w.capacity,
                leases: w.leases,
                tiles_done: w.done,
                tiles_failed: w.failed,
                last_seen_s: now.saturating_duration_since(w.last_seen).as_secs_f64(),
                build: st.builds.get(&w.id).cloned().unwrap_or_default(),
            })
            .collect();
        Ok(Response::new(pb::WorkerList { workers }))
    }
}

impl WorkService {
    fn lease_from(&self, worker: u64, lease: Option<&pb::Lease>) -> Result<Lease, Status> {
        let l = lease.ok_or_else(|| Status::invalid_argument("the lease is missing"))?;
        Ok(Lease {
            job: Arc::from(l.job_id.as_str()),
            tile: l.tile,
            attempt: l.attempt,
            worker: self.0.worker_id(worker),
        })
    }
}

impl WorkService {
    /// The leases a report asked for with its result.
    fn more(&self, header: &pb::TileHeader) -> Vec<pb::Lease> {
        if header.want == 0 {
            return Vec::new();
        }
        let id = self.0.worker_id(header.worker_id);
        let mut st = self.0.lock();
        if id == 0 || !st.scheduler.heartbeat(id, Instant::now()) {
            return Vec::new();
        }
        self.0.grant(st, id, header.want)
    }
}

#[tonic::async_trait]
impl pb::work_server::Work for WorkService {
    async fn register(
        &self,
        request: Request<pb::RegisterRequest>,
    ) -> Result<Response<pb::RegisterReply>, Status> {
        let req = request.into_inner();
        if req.protocol_version != PROTOCOL_VERSION {
            return Err(Status::failed_precondition(format!(
                "worker {} speaks protocol {}, this coordinator {PROTOCOL_VERSION}: run a worker \
                 of the same restauro release",
                req.name, req.protocol_version
            )));
        }
        let mut st = self.0.lock();
        let id = st.scheduler.register_worker(&req.name, req.capacity.max(1), Instant::now());
        st.builds.insert(id, req.build.clone());
        drop(st);
        info!(worker = id, name = %req.name, capacity = req.capacity, build = %req.build, "worker registered");
        let heartbeat = self.0.config.scheduler.heartbeat_timeout / 3;
        Ok(Response::new(pb::RegisterReply {
            worker_id: self.0.epoch | id,
            heartbeat_ms: heartbeat.as_millis().max(50) as u32,
        }))
    }

    async fn heartbeat(
        &self,
        request: Request<pb::HeartbeatRequest>,
    ) -> Result<Response<pb::HeartbeatReply>, Status> {
        let id = self.0.worker_id(request.into_inner().worker_id);
        let known = id != 0 && self.0.lock().scheduler.heartbeat(id, Instant::now());
        Ok(Response::new(pb::HeartbeatReply { known }))
    }

    async fn pull_leases(
        &self,
        request: Request<pb::PullRequest>,
    ) -> Result<Response<pb::PullReply>, Status> {
        let req = request.into_inner();
        let id = self.0.worker_id(req.worker_id);
        let deadline =
            tokio::time::Instant::now() + Duration::from_millis(u64::from(req.wait_ms.min(30_000)));
        loop {
            let notified = self.0.work.notified();
            tokio::pin!(notified);
            notified.as_mut().enable();
            {
                let mut st = self.0.lock();
                if id == 0 || !st.scheduler.heartbeat(id, Instant::now()) {
                    return Ok(Response::new(pb::PullReply { leases: Vec::new(), known: false }));
                }
                let leases = self.0.grant(st, id, req.max);
                if !leases.is_empty() {
                    return Ok(Response::new(pb::PullReply { leases, known: true }));
                }
            }
            if tokio::time::timeout_at(deadline, notified).await.is_err() {
                return Ok(Response::new(pb::PullReply { leases: Vec::new(), known: true }));
            }
        }
    }

    async fn report_tile(
        &self,
        request: Request<Streaming<pb::TileChunk>>,
    ) -> Result<Response<pb::ReportReply>, Status> {
        let mut stream = request.into_inner();
        let header = match stream.message().await?.and_then(|c| c.part) {
            Some(pb::tile_chunk::Part::Header(h)) => h,
            _ => return Err(Status::invalid_argument("a tile report starts with its header")),
        };
        let lease = self.lease_from(header.worker_id, header.lease.as_ref())?;
        let span = tracing::Span::current();
        span.record("job", &*lease.job);
        span.record("tile", lease.tile);
        span.record("worker", lease.worker);
        let (rect, spectral, sky) = {
            let st = self.0.lock();
            match st.jobs.get(&*lease.job) {
                Some(r) if matches!(r.state, State::Queued | State::Running) => {
                    let Some(rect) = r.tile(lease.tile) else {
                        return Err(Status::invalid_argument(format!(
                            "job {} has no tile {}",
                            lease.job, lease.tile
                        )));
                    };
                    (rect, r.options.spectral, r.sky)
                }
                _ => {
                    return Ok(Response::new(pb::ReportReply {
                        accepted: false,
                        leases: self.more(&header),
                    }));
                }
            }
        };
        let (xyz_bytes, spectral_bytes) = tile_sizes(&rect, spectral, sky);
        let expected = xyz_bytes + spectral_bytes;
        if header.xyz_bytes as usize != xyz_bytes
            || header.spectral_bytes as usize != spectral_bytes
        {
            return Err(Status::invalid_argument(format!(
                "tile {} of job {}: {} + {} bytes announced, expected {xyz_bytes} + {spectral_bytes}",
                lease.tile, lease.job, header.xyz_bytes, header.spectral_bytes
            )));
        }
        let mut data = Vec::with_capacity(expected);
        while let Some(chunk) = stream.next().await {
            match chunk?.part {
                Some(pb::tile_chunk::Part::Data(d)) => {
                    if data.len() + d.len() > expected {
                        return Err(Status::invalid_argument(format!(
                            "tile {} of job {}: more than the {expected} bytes announced",
                            lease.tile, lease.job
                        )));
                    }
                    data.extend_from_slice(&d);
                }
                _ => return Err(Status::invalid_argument("a tile report has one header")),
            }
        }
        if data.len() != expected {
            return Err(Status::invalid_argument(format!(
                "tile {} of job {}: {} bytes received, {expected} announced",
                lease.tile,
                lease.job,
                data.len()
            )));
        }
        self.0.metrics.tile_bytes_received.inc_by(data.len() as u64);
        if header.render_s.is_finite() && header.render_s >= 0.0 {
            self.0.metrics.tile_render_seconds.observe(header.render_s);
        }
        // Durable first, then accepted: an acknowledged tile is never rendered again.
        self.0.tile_commits.put(lease.job.clone(), lease.tile, data).await.map_err(internal)?;
        let completion = self.0.lock().scheduler.complete(&lease, Instant::now());
        match completion {
            Completion::Accepted { job_finished } => {
                debug!(job = %lease.job, tile = lease.tile, worker = lease.worker, render_s = header.render_s, "tile done");
                self.0.bump();
                if job_finished {
                    let shared = self.0.clone();
                    let id = lease.job.to_string();
                    tokio::task::spawn_blocking(move || shared.assemble(&id));
                }
                Ok(Response::new(pb::ReportReply { accepted: true, leases: self.more(&header) }))
            }
            Completion::Stale => {
                Ok(Response::new(pb::ReportReply { accepted: false, leases: self.more(&header) }))
            }
        }
    }

    async fn fail_tile(
        &self,
        request: Request<pb::FailRequest>,
    ) -> Result<Response<pb::ReportReply>, Status> {
        let req = request.into_inner();
        let lease = self.lease_from(req.worker_id, req.lease.as_ref())?;
        warn!(job = %lease.job, tile = lease.tile, worker = lease.worker, "tile failed: {}", req.reason);
        let outcome = self.0.lock().scheduler.fail(&lease, &req.reason, Instant::now());
        match outcome {
            Failure::Requeued => {
                self.0.work.notify_waiters();
                self.0.bump();
                Ok(Response::new(pb::ReportReply { accepted: true, leases: Vec::new() }))
            }
            Failure::JobFailed { reason } => {
                self.0.fail_job(&lease.job, reason);
                Ok(Response::new(pb::ReportReply { accepted: true, leases: Vec::new() }))
            }
            Failure::Stale => {
                Ok(Response::new(pb::ReportReply { accepted: false, leases: Vec::new() }))
            }
        }
    }

    async fn return_leases(
        &self,
        request: Request<pb::ReturnRequest>,
    ) -> Result<Response<pb::ReportReply>, Status> {
        let req = request.into_inner();
        let mut any = false;
        for l in &req.leases {
            let lease = self.lease_from(req.worker_id, Some(l))?;
            any |= self.0.lock().scheduler.give_back(&lease, Instant::now());
        }
        if req.leaving {
            let id = self.0.worker_id(req.worker_id);
            if id != 0 {
                let returned = self.0.lock().scheduler.remove_worker(id, Instant::now());
                info!(worker = id, returned = returned.len(), "worker left");
                any |= !returned.is_empty();
            }
        }
        if any {
            self.0.work.notify_waiters();
            self.0.bump();
        }
        Ok(Response::new(pb::ReportReply { accepted: any, leases: Vec::new() }))
    }

    async fn fetch_job(
        &self,
        request: Request<pb::JobRef>,
    ) -> Result<Response<pb::JobSpec>, Status> {
        let id = request.into_inner().job_id;
        let st = self.0.lock();
        let r = st.jobs.get(&id).ok_or_else(|| Status::not_found(format!("no job {id}")))?;
        Ok(Response::new(pb::JobSpec {
            job_id: id.clone(),
            manifest_json: r.manifest_json.clone(),
            options: Some(r.options.to_proto()),
        }))
    }

    type FetchAssetStream = Stream2<pb::Chunk>;

    async fn fetch_asset(
        &self,
        request: Request<pb::AssetRef>,
    ) -> Result<Response<Self::FetchAssetStream>, Status> {
        let reference = request.into_inner().reference;
        let hash = asset_hash(&reference)?.to_owned();
        let shared = self.0.clone();
        let data = blocking(move || shared.store.asset(&hash))
            .await?
            .map_err(internal)?
            .ok_or_else(|| Status::not_found(format!("no asset {reference}")))?;
        self.0.metrics.asset_bytes_sent.inc_by(data.len() as u64);
        Ok(Response::new(chunk_stream(reference, data)))
    }
}
