//! The worker process: it dials the coordinator (so it works behind NAT and in Kubernetes),
//! registers with its capacity, protocol version and build, and then pulls tile leases one at a
//! time. Each job's scene is fetched (assets by hash, cached on disk), checked and prepared once;
//! tiles render on a rayon pool, never on the async runtime's threads. A result is sent back in
//! chunks and kept until the coordinator acknowledges it. SIGTERM drains: the tile in hand is
//! finished and delivered, then the worker exits.
//!
//! When the coordinator goes away the worker keeps trying to reach it; a restarted coordinator
//! does not know the worker's session, and the worker registers again. Results outlive a
//! session: a tile rendered under one is delivered with the next (its lease's ticket still
//! proves it was given out, see the coordinator's `lease`), so a coordinator restart loses no
//! finished work.

use crate::error::{Result, WorkerError};
use crate::failure::{JobError, retryable};
use crate::metrics::WorkerMetrics;
use crate::scene_cache::SceneCache;
use restauro_image::framebuffer::{TileExtras, TileLayout, encode_tile, tile_sizes};
use restauro_ops::signal::stop_signal;
use restauro_ops::token::read_token;
use restauro_proto::pb::work_client::WorkClient;
use restauro_proto::transport::Failover;
use restauro_proto::{self as pb, CHUNK_BYTES, Credentials, PROTOCOL_VERSION};
use restauro_render::prepared::PreparedScene;
use restauro_render::tile::render_tile;
use restauro_scene::bundle::Bundle;
use restauro_scene::limits::Limits;
use restauro_scene::plan::{Plan, Rect};
use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::{mpsc, oneshot, watch};
use tonic::service::interceptor::InterceptedService;
use tracing::{Instrument, debug, info, info_span, warn};

type Client = WorkClient<InterceptedService<Failover, Credentials>>;

#[derive(clap::Args, Clone, Debug)]
pub struct WorkerArgs {
    /// The coordinator's URL, or several separated by commas (coordinators taking turns to
    /// lead on one PostgreSQL store: calls go to the one leading) (else RESTAURO_COORDINATOR).
    #[arg(long, env = "RESTAURO_COORDINATOR")]
    pub coordinator: String,
    /// A file holding the worker token (else RESTAURO_WORKER_TOKEN).
    #[arg(long)]
    pub token_file: Option<PathBuf>,
    /// For an https:// coordinator: a PEM file of the certificate authority to trust besides
    /// the system's (else RESTAURO_TLS_CA).
    #[arg(long, env = "RESTAURO_TLS_CA")]
    pub tls_ca: Option<PathBuf>,
    /// Render threads; 0 uses every core.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// The name shown in `restauro workers`; the host name by default.
    #[arg(long)]
    pub name: Option<String>,
    /// Where fetched scene assets are cached, by hash.
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// The memory the prepared scenes of the jobs in hand may hold, in MiB; the least recently
    /// used scene goes first when a new one does not fit.
    #[arg(long, default_value_t = 4096)]
    pub scene_cache_mb: usize,
    /// The protocol version to announce (for testing the coordinator's refusal).
    #[arg(long, hide = true, default_value_t = PROTOCOL_VERSION)]
    pub protocol_version: u32,
    /// Append `job tile attempt` for every tile rendered to this file (for tests).
    #[arg(long, hide = true)]
    pub tile_log: Option<PathBuf>,
    /// Fault injection for tests of the coordinator's tile checks: from the tile this worker
    /// renders with this number (1 for its first), it sends one pixel altered by the least bit
    /// of its X. 0: never.
    #[arg(long, hide = true, default_value_t = 0)]
    pub fault_lie_from: u64,
    /// With --fault-lie-from: how many tiles in a row it alters.
    #[arg(long, hide = true, default_value_t = u64::MAX)]
    pub fault_lie_count: u64,
    /// The operations endpoint: /metrics and health (/healthz; /readyz once registered), and
    /// who may read the metrics.
    #[command(flatten)]
    pub metrics: restauro_ops::metrics_access::MetricsArgs,
    /// Exit when standard input closes (an embedded cluster's processes end with their parent).
    #[arg(long, hide = true)]
    pub exit_with_stdin: bool,
}

/// What a job's prepared scene is made from: its scene (the manifest names every file by its
/// hash), its plan and its limits, hashed. Jobs with the same key share one prepared scene.
fn content_key(manifest_json: &str, plan: &pb::Plan, limits: &pb::SceneLimits) -> String {
    use prost::Message;
    let mut hasher = blake3::Hasher::new();
    for part in [manifest_json.as_bytes(), &plan.encode_to_vec(), &limits.encode_to_vec()] {
        hasher.update(&(part.len() as u64).to_le_bytes());
        hasher.update(part);
    }
    hasher.finalize().to_hex().to_string()
}

/// A job ready to render.
struct ReadyJob {
    scene: PreparedScene,
    plan: Plan,
    /// The job's number of the frame's first tile (0 for a still).
    first_tile: u32,
}

/// The worker's registration, shared with the tasks that deliver results: `None` while it is
/// not registered.
type SessionWatch = watch::Receiver<Option<pb::WorkerSession>>;

struct Worker {
    args: WorkerArgs,
    token: String,
    pool: Arc<rayon::ThreadPool>,
    cache: PathBuf,
    scenes: SceneCache<ReadyJob>,
    stop: watch::Receiver<bool>,
    session: watch::Sender<Option<pb::WorkerSession>>,
    metrics: Arc<WorkerMetrics>,
}

pub fn run(args: &WorkerArgs) -> Result<()> {
    let token = read_token(args.token_file.as_deref(), "RESTAURO_WORKER_TOKEN", "--token-file")?;
    let metrics_endpoint = args.metrics.endpoint()?;
    let threads = if args.threads == 0 { num_threads() } else { args.threads };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("render-{i}"))
        .build()
        .map_err(WorkerError::RenderThreads)?;
    let cache =
        args.cache.clone().unwrap_or_else(|| std::env::temp_dir().join("restauro-worker-cache"));
    std::fs::create_dir_all(&cache)
        .map_err(|error| WorkerError::Cache { path: cache.clone(), error })?;
    remove_partial_assets(&cache);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .map_err(WorkerError::Runtime)?;
    runtime.block_on(async {
        let (stop_tx, stop) = watch::channel(false);
        let exit_with_stdin = args.exit_with_stdin;
        tokio::spawn(async move {
            stop_signal(exit_with_stdin).await;
            info!("stop requested: finishing the tile in hand");
            let _ = stop_tx.send(true);
        });
        let metrics = Arc::new(WorkerMetrics::new());
        // The endpoint outlives the drain, so a probe sees the worker until it exits.
        let endpoint = match metrics_endpoint {
            Some((at, access)) => {
                let probe: Arc<dyn restauro_ops::endpoint::Probe> = metrics.clone();
                let (addr, task) = restauro_ops::endpoint::serve(
                    at,
                    probe,
                    access,
                    Default::default(),
                    std::future::pending(),
                )
                .await?;
                let mut out = std::io::stdout().lock();
                writeln!(out, "metrics on {addr}").map_err(WorkerError::Stdout)?;
                out.flush().map_err(WorkerError::Stdout)?;
                Some(task)
            }
            None => None,
        };
        let mut worker = Worker {
            args: args.clone(),
            token,
            pool: Arc::new(pool),
            cache,
            scenes: SceneCache::new(args.scene_cache_mb.saturating_mul(1 << 20)),
            stop,
            session: watch::Sender::new(None),
            metrics,
        };
        let served = worker.serve(threads as u32).await;
        if let Some(task) = endpoint {
            task.abort();
        }
        served
    })
}

fn num_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Removes the files of asset downloads a killed worker left behind.
fn remove_partial_assets(cache: &Path) {
    let Ok(entries) = std::fs::read_dir(cache) else { return };
    for entry in entries.flatten() {
        if entry.file_name().to_string_lossy().contains(".partial-") {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// A refusal that retrying does not cure (the wrong token, another protocol, a bad request).
fn is_refusal(status: &tonic::Status) -> bool {
    matches!(
        status.code(),
        tonic::Code::Unauthenticated
            | tonic::Code::PermissionDenied
            | tonic::Code::FailedPrecondition
            | tonic::Code::InvalidArgument
    )
}

impl Worker {
    fn stopping(&self) -> bool {
        *self.stop.borrow()
    }

    /// Connects, retrying while the coordinator is unreachable. `None` when a stop is requested
    /// first: a worker that is not connected holds no tile, so stopping then is a clean exit (an
    /// orchestrator scaling workers down while the coordinator restarts must not see a failure).
    async fn connect(&self) -> Result<Option<Client>> {
        let credentials = Credentials::new(&self.token, self.args.protocol_version)
            .map_err(WorkerError::Token)?;
        let endpoints = restauro_proto::transport::endpoints(
            &self.args.coordinator,
            self.args.tls_ca.as_deref(),
        )?;
        let mut stop = self.stop.clone();
        let mut backoff = Duration::from_millis(50);
        loop {
            // A connection attempt to a host that drops packets can take as long as TCP's own
            // timeout: the stop request must not wait for it.
            let attempt = tokio::select! {
                attempt = restauro_proto::transport::connect(&endpoints) => attempt,
                _ = stop.wait_for(|stopping| *stopping) => return Ok(None),
            };
            match attempt {
                Ok(channel) => {
                    return Ok(Some(
                        WorkClient::with_interceptor(channel, credentials)
                            .max_decoding_message_size(8 << 20),
                    ));
                }
                Err((url, e)) => {
                    warn!(
                        "cannot reach the coordinator at {url}: {}; retrying",
                        restauro_proto::transport::error_chain(&e)
                    );
                    tokio::select! {
                        () = tokio::time::sleep(backoff) => {}
                        _ = stop.wait_for(|stopping| *stopping) => return Ok(None),
                    }
                    backoff = (backoff * 2).min(Duration::from_secs(1));
                }
            }
        }
    }

    /// Registers, heartbeats and renders until stopped; connects and registers again when the
    /// coordinator goes away or forgets this worker. Rendered tiles are delivered in the
    /// background, across registrations, each kept until acknowledged.
    async fn serve(&mut self, capacity: u32) -> Result<()> {
        let name = self.args.name.clone().unwrap_or_else(hostname);
        // Its identity for its whole life: its leases are bound to it, so after a coordinator
        // restart it (and only it) may deliver what it rendered under the earlier run.
        let identity = identity();
        let mut reports = tokio::task::JoinSet::new();
        // Sessions a delivery found the coordinator no longer knows (see [`report_slot`]).
        let (unknown_tx, mut unknown_rx) = mpsc::unbounded_channel();
        'connection: loop {
            if self.stopping() {
                return self.drain(&mut reports, None).await;
            }
            let Some(mut client) = self.connect().await? else {
                info!("stopped before reaching the coordinator: no tile in hand");
                return self.drain(&mut reports, None).await;
            };
            let Some(reply) = self.register(&mut client, &name, capacity, &identity).await? else {
                continue;
            };
            let session = reply.session.ok_or(WorkerError::NoSession)?;
            info!(worker = session.worker_id, %name, capacity, "registered");
            self.session.send_replace(Some(session.clone()));
            self.metrics.registered.set(1);
            let heartbeat = heartbeat(client.clone(), session.clone(), reply.heartbeat_ms);
            // Results rendered under an earlier session go first: a restarted coordinator takes
            // them (their leases' tickets prove them), and this worker must not lease one of
            // those tiles again and render it twice.
            if !reports.is_empty() {
                let settled = tokio::time::timeout(DRAIN_PATIENCE, async {
                    while reports.join_next().await.is_some() {}
                });
                if settled.await.is_err() {
                    warn!("results of an earlier session still undelivered; going on");
                }
            }
            loop {
                if self.stopping() {
                    heartbeat.abort();
                    return self.drain(&mut reports, Some((client, session))).await;
                }
                let pull = client.pull_leases(pb::PullRequest {
                    session: Some(session.clone()),
                    max: 1,
                    wait_ms: 1000,
                });
                let mut stop = self.stop.clone();
                let pulled = tokio::select! {
                    pulled = pull => pulled,
                    _ = stop.wait_for(|stopping| *stopping) => continue,
                };
                let reply = match pulled {
                    Ok(r) => r.into_inner(),
                    Err(status) => {
                        warn!("pulling leases: {}; reconnecting", status.message());
                        self.unregistered(&heartbeat);
                        tokio::time::sleep(Duration::from_millis(100)).await;
                        continue 'connection;
                    }
                };
                if !reply.known {
                    info!("the coordinator does not know this worker; registering again");
                    self.unregistered(&heartbeat);
                    continue 'connection;
                }
                for lease in reply.leases {
                    let span = info_span!("tile", job = %lease.job_id, tile = lease.tile, attempt = lease.attempt);
                    match self.render(&mut client, &session, lease).instrument(span.clone()).await {
                        Ok(Some(report)) => {
                            let delivery = report.deliver(
                                client.clone(),
                                self.session.subscribe(),
                                unknown_tx.clone(),
                                self.metrics.clone(),
                            );
                            reports.spawn(delivery.instrument(span));
                            if !report_slot(&mut reports, &mut unknown_rx, &session).await {
                                info!(
                                    "the coordinator no longer knows this worker; registering again"
                                );
                                self.unregistered(&heartbeat);
                                continue 'connection;
                            }
                        }
                        Ok(None) => {}
                        Err(e) => warn!("{}", restauro_proto::transport::error_chain(&e)),
                    }
                }
            }
        }
    }

    /// Registers with the coordinator as `name`: its reply, or `None` when the call failed in
    /// a way worth retrying (after a pause); a refusal (a bad token, another protocol) ends it.
    async fn register(
        &self,
        client: &mut Client,
        name: &str,
        capacity: u32,
        identity: &[u8],
    ) -> Result<Option<pb::RegisterReply>> {
        let request = pb::RegisterRequest {
            protocol_version: self.args.protocol_version,
            name: name.to_owned(),
            capacity,
            build: format!("restauro-worker {}", env!("CARGO_PKG_VERSION")),
            identity: identity.to_vec(),
        };
        match client.register(request).await {
            Ok(r) => Ok(Some(r.into_inner())),
            Err(status) if is_refusal(&status) => Err(WorkerError::Refused(status)),
            Err(status) => {
                warn!("registering: {}; retrying", status.message());
                tokio::time::sleep(Duration::from_millis(200)).await;
                Ok(None)
            }
        }
    }

    fn unregistered(&self, heartbeat: &tokio::task::JoinHandle<()>) {
        heartbeat.abort();
        self.session.send_replace(None);
        self.metrics.registered.set(0);
    }

    /// Delivers what is rendered, then leaves, handing back any lease granted to a poll that was
    /// abandoned. Without a connection, results wait for none: they are lost with the worker,
    /// and their tiles go back to the queue when its leases expire.
    async fn drain(
        &self,
        reports: &mut tokio::task::JoinSet<()>,
        connection: Option<(Client, pb::WorkerSession)>,
    ) -> Result<()> {
        let Some((mut client, session)) = connection else {
            reports.abort_all();
            return Ok(());
        };
        let delivered = tokio::time::timeout(DRAIN_PATIENCE, async {
            while reports.join_next().await.is_some() {}
        });
        if delivered.await.is_err() {
            warn!("results still undelivered after {DRAIN_PATIENCE:?}: leaving without them");
            reports.abort_all();
        }
        let leave = pb::ReturnRequest { session: Some(session), leases: Vec::new(), leaving: true };
        if let Err(status) = client.return_leases(leave).await {
            info!("leaving: {}", status.message());
        }
        self.session.send_replace(None);
        self.metrics.registered.set(0);
        info!("drained; exiting");
        Ok(())
    }

    /// Renders one leased tile; the result, ready to send. `None` when the job could not be
    /// made ready (the tile is then reported as failed, retryable or not).
    async fn render(
        &mut self,
        client: &mut Client,
        session: &pb::WorkerSession,
        lease: pb::Lease,
    ) -> Result<Option<Report>> {
        let job = match self.job(client, session, &lease.job_id, lease.frame).await {
            Ok(job) => job,
            Err(e) => {
                self.fail(client, session, lease, &e).await?;
                return Ok(None);
            }
        };
        let rect = lease.rect.map(Rect::from);
        let tile = lease.tile.checked_sub(job.first_tile);
        if rect.is_none() || rect != tile.and_then(|t| job.plan.tile_rect(t)) {
            let e = JobError::Scene(format!(
                "lease of tile {} with rectangle {rect:?}, which is not the plan's tile",
                lease.tile
            ));
            self.fail(client, session, lease, &e).await?;
            return Ok(None);
        }
        let rect = rect.expect("checked");
        if let Some(log) = &self.args.tile_log {
            let line = format!("{} {} {}\n", lease.job_id, lease.tile, lease.attempt);
            std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(log)
                .and_then(|mut f| f.write_all(line.as_bytes()))
                .map_err(|error| WorkerError::TileLog { path: log.clone(), error })?;
        }
        let started = Instant::now();
        let (tx, rx) = oneshot::channel();
        {
            let job = job.clone();
            self.pool.spawn(move || {
                let tile = render_tile(&job.scene, rect, job.plan.spectral);
                let _ = tx.send(tile);
            });
        }
        let tile = match rx.await {
            Ok(tile) => tile,
            Err(_) => {
                let e = JobError::Local("the render thread stopped".into());
                self.fail(client, session, lease, &e).await?;
                return Ok(None);
            }
        };
        let render_s = started.elapsed().as_secs_f64();
        self.metrics.tiles_rendered.inc();
        self.metrics.tile_render_seconds.observe(render_s);
        debug!(render_s, rays = tile.rays, "tile rendered");
        // What the plan asks for: a plan from before the light masks carries none.
        let layout = TileLayout::from(&job.plan);
        let extras = TileExtras {
            sky: tile.sky.as_deref().filter(|_| layout.sky),
            lit_by: tile.lit_by.as_deref().filter(|_| layout.lit),
            white: tile.white.as_deref().filter(|_| layout.white),
            samples: tile.samples.as_deref().filter(|_| layout.counts()),
        };
        let mut data = encode_tile(
            &tile.xyz,
            extras,
            tile.spectral.as_ref().map(|s| s.iter().map(|p| &p.0[..])),
        );
        let (from, count) = (self.args.fault_lie_from, self.args.fault_lie_count);
        let nth = self.metrics.tiles_rendered.get();
        if from > 0 && nth >= from && nth - from < count {
            warn!(nth, "fault injection: sending this tile with one pixel altered");
            data[0] ^= 1;
        }
        let (image_bytes, spectral_bytes) = tile_sizes(&rect, layout);
        let header = pb::TileHeader {
            session: None,
            lease: Some(lease),
            rays: tile.rays,
            render_s,
            xyz_bytes: image_bytes as u64,
            spectral_bytes: spectral_bytes as u64,
        };
        Ok(Some(Report { header, data }))
    }

    /// Tells the coordinator the tile could not be rendered here, and whether that was the
    /// transport's fault (`failure::retryable`).
    async fn fail(
        &self,
        client: &mut Client,
        session: &pb::WorkerSession,
        lease: pb::Lease,
        error: &JobError,
    ) -> Result<()> {
        let reason = error.to_string();
        let retryable = retryable(error);
        warn!(job = %lease.job_id, tile = lease.tile, retryable, "{reason}");
        if retryable {
            // The coordinator (or the way to it) is in trouble: give it a moment.
            tokio::time::sleep(Duration::from_millis(200)).await;
        }
        client
            .fail_tile(pb::FailRequest {
                session: Some(session.clone()),
                lease: Some(lease),
                reason,
                retryable,
            })
            .await
            .map_err(WorkerError::ReportFailure)?;
        Ok(())
    }

    /// The prepared scene of a job, fetched and prepared on first use: the coordinator's own
    /// plan and limits, so that no worker plans a job otherwise than the coordinator did.
    async fn job(
        &mut self,
        client: &mut Client,
        session: &pb::WorkerSession,
        job_id: &str,
        frame: u32,
    ) -> Result<Arc<ReadyJob>, JobError> {
        // A sequence's frames are scenes of their own, cached apart.
        let key = format!("{job_id}#{frame}");
        if let Some(job) = self.scenes.get(&key) {
            return Ok(job);
        }
        let fetch = |what: String| move |status| JobError::Fetch { what, status };
        let spec = client
            .fetch_job(pb::FetchJobRequest {
                session: Some(session.clone()),
                job_id: job_id.to_owned(),
                frame,
            })
            .await
            .map_err(fetch(format!("job {job_id}")))?
            .into_inner();
        let scene_error = |e: &dyn std::fmt::Display| JobError::Scene(format!("job {job_id}: {e}"));
        let (wire_plan, wire_limits) = (
            spec.plan.ok_or_else(|| scene_error(&"no plan"))?,
            spec.limits.ok_or_else(|| scene_error(&"no limits"))?,
        );
        let content = content_key(&spec.manifest_json, &wire_plan, &wire_limits);
        let first_tile = spec.first_tile;
        if let Some((ready, bytes)) = self.scenes.get_by_content(&content)
            && ready.first_tile == first_tile
        {
            self.scenes.insert(&key, &content, ready.clone(), bytes);
            return Ok(ready);
        }
        let plan = Plan::try_from(wire_plan).map_err(|e| scene_error(&e))?;
        let limits = Limits::from(wire_limits);
        let label = PathBuf::from(format!("job {job_id}"));
        plan.check(&limits, &label).map_err(|e| scene_error(&e))?;
        let skeleton = Bundle {
            scene: Bundle::parse_manifest(&spec.manifest_json).map_err(|e| scene_error(&e))?,
            files: BTreeMap::new(),
        };
        let mut files = BTreeMap::new();
        for reference in skeleton.references() {
            let (hash, bytes) = self.asset(client, session, &reference, &limits).await?;
            files.insert(hash, bytes);
        }
        let manifest = spec.manifest_json;
        let pool = self.pool.clone();
        let job_name = job_id.to_owned();
        let ready = tokio::task::spawn_blocking(move || -> Result<ReadyJob, JobError> {
            let scene_error = |e: &dyn std::fmt::Display| JobError::Scene(format!("job {job_name}: {e}"));
            let bundle = Bundle::from_parts(&manifest, files).map_err(|e| scene_error(&e))?;
            let mut scene = bundle.load(&limits).map_err(|e| scene_error(&e))?;
            plan.apply(&mut scene);
            let started = Instant::now();
            let prepared = pool
                .install(|| PreparedScene::for_plan(&scene, &plan))
                .map_err(|e| scene_error(&e))?;
            info!(job = %job_name, triangles = prepared.triangle_count(), mib = prepared.memory_bytes() >> 20, seconds = started.elapsed().as_secs_f64(), "scene prepared");
            Ok(ReadyJob { scene: prepared, plan, first_tile })
        })
        .await
        .map_err(|e| JobError::Local(format!("preparing job {job_id}: {e}")))??;
        let bytes = ready.scene.memory_bytes();
        let ready = Arc::new(ready);
        for evicted in self.scenes.insert(&key, &content, ready.clone(), bytes) {
            info!(job = %evicted, "scene dropped from the cache (least recently used)");
        }
        Ok(ready)
    }

    /// An asset's bytes, from the disk cache or the coordinator, checked against its hash.
    async fn asset(
        &self,
        client: &mut Client,
        session: &pb::WorkerSession,
        reference: &str,
        limits: &Limits,
    ) -> Result<(String, Vec<u8>), JobError> {
        let hash = reference
            .strip_prefix("blake3:")
            .and_then(|r| r.split_once('.'))
            .map(|(h, _)| h.to_ascii_lowercase())
            .filter(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()))
            .ok_or_else(|| {
                JobError::Scene(format!("asset reference `{reference}` is not blake3:<hash>.<ext>"))
            })?;
        let cached = self.cache.join(&hash);
        if let Ok(bytes) = std::fs::read(&cached)
            && blake3::hash(&bytes).to_hex().as_str() == hash
        {
            return Ok((hash, bytes));
        }
        let fetch = |status| JobError::Fetch { what: format!("asset {reference}"), status };
        let mut stream = client
            .fetch_asset(pb::FetchAssetRequest {
                session: Some(session.clone()),
                reference: reference.to_owned(),
            })
            .await
            .map_err(fetch)?
            .into_inner();
        let mut bytes = Vec::new();
        while let Some(chunk) = stream.message().await.map_err(fetch)? {
            if (bytes.len() + chunk.data.len()) as u64 > limits.max_file_bytes {
                return Err(JobError::Scene(format!(
                    "asset {reference} is larger than the limit of {} bytes",
                    limits.max_file_bytes
                )));
            }
            bytes.extend_from_slice(&chunk.data);
        }
        if blake3::hash(&bytes).to_hex().as_str() != hash {
            return Err(JobError::Damaged { reference: reference.to_owned() });
        }
        self.metrics.asset_bytes_received.inc_by(bytes.len() as u64);
        let temporary = self.cache.join(format!("{hash}.partial-{}", std::process::id()));
        if std::fs::write(&temporary, &bytes)
            .and_then(|()| std::fs::rename(&temporary, &cached))
            .is_err()
        {
            let _ = std::fs::remove_file(&temporary);
            warn!("could not cache {reference} in {}", self.cache.display());
        }
        Ok((hash, bytes))
    }
}

/// 32 bytes from the operating system's random source (two UUID v4 draw them).
fn identity() -> [u8; 32] {
    let mut bytes = [0u8; 32];
    bytes[..16].copy_from_slice(uuid::Uuid::new_v4().as_bytes());
    bytes[16..].copy_from_slice(uuid::Uuid::new_v4().as_bytes());
    bytes
}

/// Heartbeats until the coordinator no longer knows the session (or the task is aborted).
fn heartbeat(
    mut client: Client,
    session: pb::WorkerSession,
    period_ms: u32,
) -> tokio::task::JoinHandle<()> {
    let period = Duration::from_millis(u64::from(period_ms.max(50)));
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(period);
        loop {
            tick.tick().await;
            let beat = pb::HeartbeatRequest { session: Some(session.clone()) };
            match client.heartbeat(beat).await {
                Ok(r) if !r.get_ref().known => return,
                _ => {}
            }
        }
    })
}

/// Rendered tiles sent back at once; more wait for one of these to be acknowledged.
const MAX_REPORTS_IN_FLIGHT: usize = 4;

/// How long a rendered tile is kept for delivery while the coordinator cannot be reached.
const DELIVERY_PATIENCE: Duration = Duration::from_secs(600);

/// How long a stopping worker waits for its results to be delivered.
const DRAIN_PATIENCE: Duration = Duration::from_secs(120);

/// Waits until fewer than [`MAX_REPORTS_IN_FLIGHT`] results are on their way; `false` when a
/// delivery finds that the coordinator no longer knows `session` (it restarted). Those results
/// wait for the worker to register again, which only its main loop does: waiting here for them
/// to finish would hold both until the deliveries give up ([`DELIVERY_PATIENCE`]).
async fn report_slot(
    reports: &mut tokio::task::JoinSet<()>,
    unknown: &mut mpsc::UnboundedReceiver<pb::WorkerSession>,
    session: &pb::WorkerSession,
) -> bool {
    while reports.len() >= MAX_REPORTS_IN_FLIGHT {
        tokio::select! {
            _ = reports.join_next() => {}
            Some(gone) = unknown.recv() => {
                if &gone == session {
                    return false;
                }
            }
        }
    }
    true
}

/// A rendered tile on its way to the coordinator.
struct Report {
    header: pb::TileHeader,
    data: Vec<u8>,
}

impl Report {
    /// Sends the tile in chunks with the worker's session of the moment, retrying while the
    /// coordinator is unreachable or does not know the session (then waiting for the worker to
    /// register again): a result is kept until it is acknowledged, refused, or has waited
    /// [`DELIVERY_PATIENCE`].
    async fn deliver(
        self,
        mut client: Client,
        mut session: SessionWatch,
        unknown: mpsc::UnboundedSender<pb::WorkerSession>,
        metrics: Arc<WorkerMetrics>,
    ) {
        let lease = self.header.lease.clone().unwrap_or_default();
        let give_up = tokio::time::Instant::now() + DELIVERY_PATIENCE;
        let mut backoff = Duration::from_millis(100);
        loop {
            let current = match tokio::time::timeout_at(give_up, session.wait_for(Option::is_some))
                .await
            {
                Ok(Ok(s)) => s.clone(),
                _ => {
                    warn!(job = %lease.job_id, tile = lease.tile, "giving up on the result: not registered with a coordinator");
                    return;
                }
            };
            let mut header = self.header.clone();
            header.session = current.clone();
            let mut messages =
                vec![pb::TileChunk { part: Some(pb::tile_chunk::Part::Header(header)) }];
            messages.extend(
                self.data
                    .chunks(CHUNK_BYTES)
                    .map(|c| pb::TileChunk { part: Some(pb::tile_chunk::Part::Data(c.to_vec())) }),
            );
            match client.report_tile(tokio_stream::iter(messages)).await {
                Ok(reply) if !reply.get_ref().known => {
                    // This session is gone; the worker registers again (told so, in case it is
                    // waiting for this delivery), and this result goes with the next session.
                    if let Some(gone) = &current {
                        let _ = unknown.send(gone.clone());
                    }
                    let _ =
                        tokio::time::timeout_at(give_up, session.wait_for(|s| *s != current)).await;
                }
                Ok(reply) => {
                    metrics.bytes_sent.inc_by(self.data.len() as u64);
                    if reply.get_ref().accepted {
                        metrics.tiles_delivered.inc();
                    } else {
                        info!(job = %lease.job_id, tile = lease.tile, "result no longer wanted (stale lease)");
                    }
                    return;
                }
                Err(status) if is_refusal(&status) => {
                    warn!(job = %lease.job_id, tile = lease.tile, "result refused: {}", status.message());
                    return;
                }
                Err(status) => {
                    if tokio::time::Instant::now() >= give_up {
                        warn!(job = %lease.job_id, tile = lease.tile, "giving up on the result: {}", status.message());
                        return;
                    }
                    warn!(tile = lease.tile, "reporting: {}; retrying", status.message());
                    tokio::time::sleep(backoff).await;
                    backoff = (backoff * 2).min(Duration::from_secs(1));
                }
            }
        }
    }
}

fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_owned())
        .ok()
        .filter(|s| !s.is_empty())
        .map_or_else(
            || format!("worker-{}", std::process::id()),
            |h| format!("{h}-{}", std::process::id()),
        )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session(worker_id: u64) -> pb::WorkerSession {
        pb::WorkerSession { worker_id, ..Default::default() }
    }

    /// `n` deliveries that never end, as results waiting for a registration do.
    fn stuck_deliveries(n: usize) -> tokio::task::JoinSet<()> {
        let mut reports = tokio::task::JoinSet::new();
        for _ in 0..n {
            reports.spawn(std::future::pending());
        }
        reports
    }

    #[tokio::test]
    async fn a_full_set_of_deliveries_gives_way_when_the_coordinator_forgets_the_session() {
        let (tx, mut rx) = mpsc::unbounded_channel();
        let mut reports = stuck_deliveries(MAX_REPORTS_IN_FLIGHT);
        // A session of an earlier registration is not this one: the wait goes on.
        tx.send(session(1)).unwrap();
        let waited = tokio::time::timeout(
            Duration::from_millis(200),
            report_slot(&mut reports, &mut rx, &session(2)),
        )
        .await;
        assert!(waited.is_err(), "gave way for a session that is not the current one");
        // This session is unknown to the coordinator: the worker must register again.
        tx.send(session(2)).unwrap();
        let waited = tokio::time::timeout(
            Duration::from_secs(5),
            report_slot(&mut reports, &mut rx, &session(2)),
        )
        .await;
        assert_eq!(waited, Ok(false), "still waiting for deliveries that wait for it");
    }

    #[tokio::test]
    async fn a_finished_delivery_frees_a_slot() {
        let (_tx, mut rx) = mpsc::unbounded_channel();
        // A full set, one of which ends.
        let mut reports = stuck_deliveries(MAX_REPORTS_IN_FLIGHT - 1);
        reports.spawn(async {});
        let waited = tokio::time::timeout(
            Duration::from_secs(5),
            report_slot(&mut reports, &mut rx, &session(2)),
        )
        .await;
        assert_eq!(waited, Ok(true));
        assert!(reports.len() < MAX_REPORTS_IN_FLIGHT);
    }
}
