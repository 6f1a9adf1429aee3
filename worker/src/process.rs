//! The worker process: it dials the coordinator (so it works behind NAT and in Kubernetes),
//! registers with its capacity, protocol version and build, and then pulls tile leases one at a
//! time. Each job's scene is fetched (assets by hash, cached on disk), checked and prepared once;
//! tiles render on a rayon pool, never on the async runtime's threads. A result is sent back in
//! chunks and kept until the coordinator acknowledges it. SIGTERM drains: the tile in hand is
//! finished and delivered, then the worker exits.
//!
//! When the coordinator goes away the worker keeps trying to reach it; a restarted coordinator
//! does not know the worker, which then registers again.

use crate::metrics::WorkerMetrics;
use anyhow::{Context, Result, anyhow, bail};
use restauro_ops::signal::stop_signal;
use restauro_ops::token::read_token;
use restauro_proto::pb::work_client::WorkClient;
use restauro_proto::{self as pb, CHUNK_BYTES, Credentials, PROTOCOL_VERSION};
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::bundle::Bundle;
use restauro_scene::load::Limits;
use restauro_scene::plan::Plan;
use restauro_scene::scene_file::Integrator;
use std::collections::{BTreeMap, HashMap};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::{oneshot, watch};
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Channel;
use tracing::{Instrument, debug, info, info_span, warn};

type Client = WorkClient<InterceptedService<Channel, Credentials>>;

#[derive(clap::Args, Clone, Debug)]
pub struct WorkerArgs {
    /// The coordinator's URL (else RESTAURO_COORDINATOR).
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
    /// The protocol version to announce (for testing the coordinator's refusal).
    #[arg(long, hide = true, default_value_t = PROTOCOL_VERSION)]
    pub protocol_version: u32,
    /// Append `job tile attempt` for every tile rendered to this file (for tests).
    #[arg(long, hide = true)]
    pub tile_log: Option<PathBuf>,
    /// Serve Prometheus metrics (/metrics) and health (/healthz; /readyz once registered) over
    /// HTTP on this address (else RESTAURO_METRICS_LISTEN; off when neither is given). Port 0
    /// picks a free port, printed as `metrics on ADDR`.
    #[arg(long, env = "RESTAURO_METRICS_LISTEN")]
    pub metrics_listen: Option<std::net::SocketAddr>,
    /// Exit when standard input closes (an embedded cluster's processes end with their parent).
    #[arg(long, hide = true)]
    pub exit_with_stdin: bool,
}

/// A job ready to render.
struct ReadyJob {
    scene: PreparedScene,
    spectral: bool,
}

struct Worker {
    args: WorkerArgs,
    token: String,
    pool: Arc<rayon::ThreadPool>,
    cache: PathBuf,
    jobs: HashMap<String, Arc<ReadyJob>>,
    stop: watch::Receiver<bool>,
    metrics: Arc<WorkerMetrics>,
}

pub fn run(args: &WorkerArgs) -> Result<()> {
    let token = read_token(args.token_file.as_deref(), "RESTAURO_WORKER_TOKEN", "--token-file")?;
    let threads = if args.threads == 0 { num_threads() } else { args.threads };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("render-{i}"))
        .build()
        .context("starting the render threads")?;
    let cache =
        args.cache.clone().unwrap_or_else(|| std::env::temp_dir().join("restauro-worker-cache"));
    std::fs::create_dir_all(&cache).with_context(|| format!("creating {}", cache.display()))?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .context("starting the async runtime")?;
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
        let endpoint = match args.metrics_listen {
            Some(at) => {
                let probe: Arc<dyn restauro_ops::endpoint::Probe> = metrics.clone();
                let (addr, task) =
                    restauro_ops::endpoint::serve(at, probe, std::future::pending()).await?;
                let mut out = std::io::stdout().lock();
                writeln!(out, "metrics on {addr}")?;
                out.flush()?;
                Some(task)
            }
            None => None,
        };
        let mut worker = Worker {
            args: args.clone(),
            token,
            pool: Arc::new(pool),
            cache,
            jobs: HashMap::new(),
            stop,
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
            .map_err(|e| anyhow!("worker token: {e}"))?;
        let endpoint = restauro_proto::transport::endpoint(
            &self.args.coordinator,
            self.args.tls_ca.as_deref(),
        )?;
        let mut stop = self.stop.clone();
        let mut backoff = Duration::from_millis(50);
        loop {
            // A connection attempt to a host that drops packets can take as long as TCP's own
            // timeout: the stop request must not wait for it.
            let attempt = tokio::select! {
                attempt = endpoint.connect() => attempt,
                _ = stop.wait_for(|stopping| *stopping) => return Ok(None),
            };
            match attempt {
                Ok(channel) => {
                    return Ok(Some(
                        WorkClient::with_interceptor(channel, credentials)
                            .max_decoding_message_size(8 << 20),
                    ));
                }
                Err(e) => {
                    warn!(
                        "cannot reach the coordinator at {}: {}; retrying",
                        self.args.coordinator,
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

    /// Registers, heartbeats and renders until stopped; reconnects and registers again when the
    /// coordinator goes away or forgets this worker.
    async fn serve(&mut self, capacity: u32) -> Result<()> {
        let name = self.args.name.clone().unwrap_or_else(hostname);
        'connection: loop {
            if self.stopping() {
                return Ok(());
            }
            let Some(mut client) = self.connect().await? else {
                info!("stopped before reaching the coordinator: no tile in hand");
                return Ok(());
            };
            let reply = match client
                .register(pb::RegisterRequest {
                    protocol_version: self.args.protocol_version,
                    name: name.clone(),
                    capacity,
                    build: format!("restauro-worker {}", env!("CARGO_PKG_VERSION")),
                })
                .await
            {
                Ok(r) => r.into_inner(),
                Err(status) if is_refusal(&status) => {
                    bail!("the coordinator refused this worker: {}", status.message())
                }
                Err(status) => {
                    warn!("registering: {}; retrying", status.message());
                    tokio::time::sleep(Duration::from_millis(200)).await;
                    continue;
                }
            };
            let id = reply.worker_id;
            info!(worker = id, %name, capacity, "registered");
            self.metrics.registered.set(1);
            let heartbeat = {
                let mut client = client.clone();
                let period = Duration::from_millis(u64::from(reply.heartbeat_ms.max(50)));
                tokio::spawn(async move {
                    let mut tick = tokio::time::interval(period);
                    loop {
                        tick.tick().await;
                        match client.heartbeat(pb::HeartbeatRequest { worker_id: id }).await {
                            Ok(r) if !r.get_ref().known => return,
                            _ => {}
                        }
                    }
                })
            };
            // Results travel back in the background, each kept until acknowledged, so the next
            // tile starts while the coordinator commits the last one.
            let mut reports = tokio::task::JoinSet::new();
            loop {
                if self.stopping() {
                    // Drain: deliver what is rendered, then leave, handing back any lease granted
                    // to a poll that was abandoned.
                    while reports.join_next().await.is_some() {}
                    let leave =
                        pb::ReturnRequest { worker_id: id, leases: Vec::new(), leaving: true };
                    if let Err(status) = client.return_leases(leave).await {
                        info!("leaving: {}", status.message());
                    }
                    heartbeat.abort();
                    self.metrics.registered.set(0);
                    info!("drained; exiting");
                    return Ok(());
                }
                let pull =
                    client.pull_leases(pb::PullRequest { worker_id: id, max: 1, wait_ms: 1000 });
                let mut stop = self.stop.clone();
                let pulled = tokio::select! {
                    pulled = pull => pulled,
                    _ = stop.wait_for(|stopping| *stopping) => continue,
                };
                let reply = match pulled {
                    Ok(r) => r.into_inner(),
                    Err(status) => {
                        warn!("pulling leases: {}; reconnecting", status.message());
                        self.metrics.registered.set(0);
                        while reports.join_next().await.is_some() {}
                        heartbeat.abort();
                        tokio::time::sleep(Duration::from_millis(100)).await;
                        continue 'connection;
                    }
                };
                if !reply.known {
                    info!("the coordinator does not know this worker; registering again");
                    self.metrics.registered.set(0);
                    while reports.join_next().await.is_some() {}
                    heartbeat.abort();
                    continue 'connection;
                }
                for lease in reply.leases {
                    let span = info_span!("tile", job = %lease.job_id, tile = lease.tile, attempt = lease.attempt);
                    match self.render(&mut client, id, lease).instrument(span.clone()).await {
                        Ok(Some(report)) => {
                            while reports.len() >= MAX_REPORTS_IN_FLIGHT {
                                reports.join_next().await;
                            }
                            let client = client.clone();
                            let metrics = self.metrics.clone();
                            reports.spawn(report.deliver(client, metrics).instrument(span));
                        }
                        Ok(None) => {}
                        Err(e) => warn!("{e:#}"),
                    }
                }
            }
        }
    }

    /// Renders one leased tile; the result, ready to send. `None` when the job could not be
    /// prepared (the tile is reported as failed).
    async fn render(
        &mut self,
        client: &mut Client,
        id: u64,
        lease: pb::Lease,
    ) -> Result<Option<Report>> {
        let rect = lease.rect.ok_or_else(|| anyhow!("a lease without a rectangle"))?;
        let rect = Rect { x: rect.x, y: rect.y, width: rect.width, height: rect.height };
        let job = match self.job(client, &lease.job_id).await {
            Ok(job) => job,
            Err(e) => {
                let reason = format!("{e:#}");
                warn!(job = %lease.job_id, tile = lease.tile, "{reason}");
                client
                    .fail_tile(pb::FailRequest {
                        worker_id: id,
                        lease: Some(lease.clone()),
                        reason,
                    })
                    .await?;
                return Ok(None);
            }
        };
        if let Some(log) = &self.args.tile_log {
            let line = format!("{} {} {}\n", lease.job_id, lease.tile, lease.attempt);
            std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(log)
                .and_then(|mut f| f.write_all(line.as_bytes()))
                .with_context(|| format!("appending to {}", log.display()))?;
        }
        let started = Instant::now();
        let (tx, rx) = oneshot::channel();
        {
            let job = job.clone();
            self.pool.spawn(move || {
                let tile = render_tile(&job.scene, rect, job.spectral);
                let _ = tx.send(tile);
            });
        }
        let tile = rx.await.context("the render thread stopped")?;
        let render_s = started.elapsed().as_secs_f64();
        self.metrics.tiles_rendered.inc();
        self.metrics.tile_render_seconds.observe(render_s);
        debug!(render_s, rays = tile.rays, "tile rendered");
        // The wire form of coordinator::framebuffer: XYZ, sky coverage (scenes with a sky), spectra.
        let mut data = Vec::with_capacity(tile.xyz.len() * 16);
        for v in tile.xyz.iter().flatten().chain(tile.sky.iter().flatten()) {
            data.extend_from_slice(&v.to_le_bytes());
        }
        let xyz_bytes = data.len() as u64;
        if let Some(spectra) = &tile.spectral {
            for v in spectra.iter().flat_map(|s| s.0.iter()) {
                data.extend_from_slice(&v.to_le_bytes());
            }
        }
        let header = pb::TileHeader {
            worker_id: id,
            lease: Some(lease),
            rays: tile.rays,
            render_s,
            xyz_bytes,
            spectral_bytes: data.len() as u64 - xyz_bytes,
            // The next lease is pulled while this result travels; none is wanted with it.
            want: 0,
        };
        Ok(Some(Report { header, data }))
    }

    /// The prepared scene of a job, fetched and prepared on first use.
    async fn job(&mut self, client: &mut Client, job_id: &str) -> Result<Arc<ReadyJob>> {
        if let Some(job) = self.jobs.get(job_id) {
            return Ok(job.clone());
        }
        let spec = client
            .fetch_job(pb::JobRef { job_id: job_id.to_owned() })
            .await
            .map_err(|s| anyhow!("fetching job {job_id}: {}", s.message()))?
            .into_inner();
        let skeleton: Bundle =
            Bundle { scene: serde_json_scene(&spec.manifest_json)?, files: BTreeMap::new() };
        let mut files = BTreeMap::new();
        for reference in skeleton.references() {
            let (hash, bytes) = self.asset(client, &reference).await?;
            files.insert(hash, bytes);
        }
        let options = spec.options.unwrap_or_default();
        let manifest = spec.manifest_json;
        let pool = self.pool.clone();
        let job_name = job_id.to_owned();
        let ready = tokio::task::spawn_blocking(move || -> Result<ReadyJob> {
            let bundle = Bundle::from_parts(&manifest, files)?;
            let limits = Limits::default();
            let mut scene = bundle.load(&limits)?;
            let render_options = restauro_scene::plan::RenderOptions {
                variant: nonempty(&options.variant),
                integrator: match options.integrator.as_str() {
                    "" => None,
                    "whitted" => Some(Integrator::Whitted),
                    "path" => Some(Integrator::Path),
                    other => bail!("integrator `{other}`: use whitted or path"),
                },
                samples_per_pixel: nonzero(options.samples_per_pixel),
                width: nonzero(options.width),
                height: nonzero(options.height),
                spectral: options.spectral,
                tile: nonzero(options.tile),
            };
            let plan = Plan::new(&scene, &render_options, &limits, Path::new(&format!("job {job_name}")))?;
            plan.apply(&mut scene);
            let started = Instant::now();
            let prepared = pool.install(|| {
                PreparedScene::new(&scene, plan.variant.as_deref(), Settings::from(&plan))
            })?;
            info!(job = %job_name, triangles = prepared.triangle_count(), seconds = started.elapsed().as_secs_f64(), "scene prepared");
            Ok(ReadyJob { scene: prepared, spectral: plan.spectral })
        })
        .await??;
        let ready = Arc::new(ready);
        // A worker keeps a few jobs' scenes; older ones are prepared again if they come back.
        if self.jobs.len() >= 4 {
            self.jobs.clear();
        }
        self.jobs.insert(job_id.to_owned(), ready.clone());
        Ok(ready)
    }

    /// An asset's bytes, from the disk cache or the coordinator, checked against its hash.
    async fn asset(&self, client: &mut Client, reference: &str) -> Result<(String, Vec<u8>)> {
        let hash = reference
            .strip_prefix("blake3:")
            .and_then(|r| r.split_once('.'))
            .map(|(h, _)| h.to_owned())
            .filter(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()))
            .ok_or_else(|| anyhow!("asset reference `{reference}` is not blake3:<hash>.<ext>"))?;
        let cached = self.cache.join(&hash);
        if let Ok(bytes) = std::fs::read(&cached)
            && blake3::hash(&bytes).to_hex().as_str() == hash
        {
            return Ok((hash, bytes));
        }
        let mut stream = client
            .fetch_asset(pb::AssetRef { reference: reference.to_owned() })
            .await
            .map_err(|s| anyhow!("fetching {reference}: {}", s.message()))?
            .into_inner();
        let mut bytes = Vec::new();
        while let Some(chunk) =
            stream.message().await.map_err(|s| anyhow!("fetching {reference}: {}", s.message()))?
        {
            bytes.extend_from_slice(&chunk.data);
        }
        if blake3::hash(&bytes).to_hex().as_str() != hash {
            bail!("asset {reference} arrived damaged (its hash differs)");
        }
        self.metrics.asset_bytes_received.inc_by(bytes.len() as u64);
        let temporary = self.cache.join(format!("{hash}.partial-{}", std::process::id()));
        if std::fs::write(&temporary, &bytes)
            .and_then(|()| std::fs::rename(&temporary, &cached))
            .is_err()
        {
            warn!("could not cache {reference} in {}", self.cache.display());
        }
        Ok((hash, bytes))
    }
}

/// Rendered tiles sent back at once; more wait for one of these to be acknowledged.
const MAX_REPORTS_IN_FLIGHT: usize = 4;

/// A rendered tile on its way to the coordinator.
struct Report {
    header: pb::TileHeader,
    data: Vec<u8>,
}

impl Report {
    /// Sends the tile in chunks, retrying while the coordinator is unreachable: a result is
    /// kept until it is acknowledged (or refused, or given up after many attempts).
    async fn deliver(self, mut client: Client, metrics: Arc<WorkerMetrics>) {
        let lease = self.header.lease.clone().unwrap_or_default();
        let mut backoff = Duration::from_millis(100);
        for attempt in 0.. {
            let mut messages = vec![pb::TileChunk {
                part: Some(pb::tile_chunk::Part::Header(self.header.clone())),
            }];
            messages.extend(
                self.data
                    .chunks(CHUNK_BYTES)
                    .map(|c| pb::TileChunk { part: Some(pb::tile_chunk::Part::Data(c.to_vec())) }),
            );
            match client.report_tile(tokio_stream::iter(messages)).await {
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
                    if attempt >= 50 {
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

fn serde_json_scene(manifest: &str) -> Result<restauro_scene::scene_file::SceneFile> {
    Bundle::parse_manifest(manifest).map_err(|e| anyhow!("{e}"))
}

fn nonzero(v: u32) -> Option<u32> {
    (v != 0).then_some(v)
}

fn nonempty(s: &str) -> Option<String> {
    (!s.is_empty()).then(|| s.to_owned())
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
