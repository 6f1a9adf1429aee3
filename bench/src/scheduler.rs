//! `restauro bench scheduler`: the coordinator's scheduling throughput over gRPC with a few
//! hundred simulated workers.
//!
//! A real coordinator process (this executable, on loopback, its store on disk) receives
//! several jobs of many small tiles; each simulated worker has its own connection and does what
//! a worker does — register, pull a few leases, report each tile (header and pixel data,
//! streamed), pull again — except rendering: its tiles are black. The jobs are submitted (and checked)
//! first; the clock runs from the workers' first pull to the last acknowledged result, so every
//! tile counted was leased, reported, checked and committed durably (in groups) by the
//! coordinator.

use crate::args::BenchArgs;
use crate::cpu::process_cpu_seconds;
use crate::error::BenchError;
use restauro_assets::bundle_scene;
use restauro_cluster::{self as cluster, LocalCluster};
use restauro_image::framebuffer::TileLayout;
use restauro_proto::pb::work_client::WorkClient;
use restauro_proto::{self as pb, Credentials, PROTOCOL_VERSION};
use restauro_scene::load::Limits;
use serde::Serialize;
use std::num::NonZeroU32;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};
use tonic::transport::Endpoint;

#[derive(Serialize)]
struct SchedulerBench {
    benchmark: &'static str,
    /// The coordinator's store: "redb" (its file) or "postgres".
    store: &'static str,
    simulated_workers: usize,
    jobs: u32,
    tiles_per_job: u32,
    tile_pixels: u32,
    /// Leases granted to the simulated workers.
    leases: u64,
    /// Results the coordinator acknowledged (durably stored).
    results_accepted: u64,
    seconds: f64,
    /// Leased and acknowledged tiles per second (one lease and one result each).
    tiles_per_second: f64,
    /// The coordinator process's CPU seconds over the run, and per thousand tiles.
    coordinator_cpu_seconds: f64,
    coordinator_cpu_ms_per_1000_tiles: f64,
    /// This process's CPU seconds (the simulated workers share the machine's cores).
    simulated_workers_cpu_seconds: f64,
}

#[derive(Default)]
struct Counts {
    leases: AtomicU64,
    accepted: AtomicU64,
}

type Result<T, E = BenchError> = std::result::Result<T, E>;

pub fn bench(args: &BenchArgs) -> Result<String> {
    let (_dir, scene) = crate::aosta_scene("restauro-bench-scheduler-", args)?;
    let bundle = bundle_scene(&scene, &Limits::default())?;
    // The tiles' layout: with a sky, each pixel carries its sky coverage too, and with a sun
    // its mask of lights.
    let lights = restauro_assets::load_scene(&scene, &Limits::default())?.lights;
    let is_sky = |l: &restauro_scene::load::ResolvedLight| {
        matches!(l, restauro_scene::load::ResolvedLight::Sky { .. })
    };
    let layout = TileLayout {
        sky: lights.iter().any(is_sky),
        lit: lights.iter().any(|l| !is_sky(l)),
        white: true,
        ..TileLayout::default()
    };
    let mut coordinator_args = vec!["--no-retinex"];
    if let Some(url) = &args.store {
        coordinator_args.extend(["--store", url.as_str()]);
    }
    let cluster = LocalCluster::start_with(0, None, &coordinator_args)?;
    let runtime = cluster::runtime()?;
    let workers = args.workers.max(1);
    let jobs = args.jobs.max(1);
    let tile = args.tile;
    let report = runtime.block_on(async {
        let mut client = cluster::connect(&cluster.url, &cluster.client_token).await?;
        cluster::upload(&mut client, &bundle).await?;
        let counts = Arc::new(Counts::default());
        let stop = Arc::new(AtomicBool::new(false));
        // Every simulated worker connects and registers before the clock starts.
        let mut registered = Vec::with_capacity(workers);
        for i in 0..workers {
            let (url, token) = (cluster.url.clone(), cluster.worker_token.clone());
            registered.push(async move { register(&url, &token, i).await });
        }
        let registered = futures_join_all(registered).await?;
        let mut total_tiles = 0u64;
        let mut tiles_per_job = 0;
        for j in 0..jobs {
            let spec = restauro_scene::job::JobSpec {
                name: restauro_scene::job::JobName::new(&format!("bench-{j}"))?,
                render: restauro_scene::plan::RenderOptions {
                    tile: NonZeroU32::new(tile),
                    samples_per_pixel: Some(NonZeroU32::MIN),
                    ..Default::default()
                },
                ..Default::default()
            };
            let status =
                cluster::submit(&mut client, &bundle, &spec, "submitting a benchmark job").await?;
            tiles_per_job = status.tiles_total;
            total_tiles += u64::from(status.tiles_total);
        }
        let cpu_before = process_cpu_seconds(&cluster.coordinator_pid().to_string());
        let own_cpu_before = process_cpu_seconds("self");
        let started = Instant::now();
        let mut tasks = tokio::task::JoinSet::new();
        for (client, session) in registered {
            tasks.spawn(simulated_worker(client, session, layout, counts.clone(), stop.clone()));
        }
        let deadline = Instant::now() + Duration::from_secs(600);
        while counts.accepted.load(Ordering::Relaxed) < total_tiles {
            if Instant::now() > deadline {
                return Err(BenchError::Stopped(
                    "the benchmark did not finish in 10 minutes".into(),
                ));
            }
            match tasks.try_join_next() {
                Some(Ok(Err(e))) => {
                    return Err(BenchError::Stopped(format!("a simulated worker failed: {e}")));
                }
                Some(Err(e)) => {
                    return Err(BenchError::Stopped(format!("a simulated worker stopped: {e}")));
                }
                _ => {}
            }
            tokio::time::sleep(Duration::from_millis(2)).await;
        }
        let seconds = started.elapsed().as_secs_f64();
        let cpu = process_cpu_seconds(&cluster.coordinator_pid().to_string()) - cpu_before;
        let own_cpu = process_cpu_seconds("self") - own_cpu_before;
        stop.store(true, Ordering::Relaxed);
        while let Some(r) = tasks.join_next().await {
            r??;
        }
        let accepted = counts.accepted.load(Ordering::Relaxed);
        Ok::<_, BenchError>(SchedulerBench {
            benchmark: "scheduler",
            store: if args.store.is_some() { "postgres" } else { "redb" },
            simulated_workers: workers,
            jobs,
            tiles_per_job,
            tile_pixels: tile * tile,
            leases: counts.leases.load(Ordering::Relaxed),
            results_accepted: accepted,
            seconds,
            tiles_per_second: accepted as f64 / seconds,
            coordinator_cpu_seconds: cpu,
            coordinator_cpu_ms_per_1000_tiles: cpu * 1e3 / (accepted.max(1) as f64 / 1e3),
            simulated_workers_cpu_seconds: own_cpu,
        })
    })?;
    drop(cluster);
    Ok(serde_json::to_string_pretty(&report)? + "\n")
}

type Worker = WorkClient<
    tonic::service::interceptor::InterceptedService<tonic::transport::Channel, Credentials>,
>;

async fn futures_join_all<T: Send + 'static>(
    futures: Vec<impl std::future::Future<Output = Result<T>> + Send + 'static>,
) -> Result<Vec<T>> {
    let mut set = tokio::task::JoinSet::new();
    for (i, f) in futures.into_iter().enumerate() {
        set.spawn(async move { f.await.map(|v| (i, v)) });
    }
    let mut out = Vec::new();
    while let Some(r) = set.join_next().await {
        out.push(r??);
    }
    out.sort_by_key(|(i, _)| *i);
    Ok(out.into_iter().map(|(_, v)| v).collect())
}

/// A simulated worker's call that the coordinator refused.
fn refused(what: &'static str, status: tonic::Status) -> BenchError {
    BenchError::Refused { what, message: status.message().to_owned() }
}

/// A simulated worker's own connection, registered.
async fn register(url: &str, token: &str, index: usize) -> Result<(Worker, pb::WorkerSession)> {
    let channel = Endpoint::from_shared(url.to_owned())?.tcp_nodelay(true).connect().await?;
    let credentials = Credentials::new(token, PROTOCOL_VERSION)
        .map_err(|e| BenchError::Stopped(e.to_string()))?;
    let mut client = WorkClient::with_interceptor(channel, credentials);
    let reply = client
        .register(pb::RegisterRequest {
            protocol_version: PROTOCOL_VERSION,
            name: format!("simulated-{index}"),
            capacity: 1,
            build: "restauro bench scheduler".into(),
            identity: (index as u64).to_le_bytes().repeat(4),
        })
        .await
        .map_err(|s| refused("registering a simulated worker", s))?;
    let session = reply
        .into_inner()
        .session
        .ok_or_else(|| BenchError::Stopped("registered without a session".into()))?;
    Ok((client, session))
}

/// Pulls up to four leases and reports a black tile of each leased size, then pulls again.
async fn simulated_worker(
    mut client: Worker,
    session: pb::WorkerSession,
    layout: TileLayout,
    counts: Arc<Counts>,
    stop: Arc<AtomicBool>,
) -> Result<()> {
    while !stop.load(Ordering::Relaxed) {
        let reply = client
            .pull_leases(pb::PullRequest { session: Some(session.clone()), max: 4, wait_ms: 50 })
            .await
            .map_err(|s| refused("pulling", s))?
            .into_inner();
        if !reply.known {
            return Err(BenchError::Stopped("the coordinator forgot a simulated worker".into()));
        }
        counts.leases.fetch_add(reply.leases.len() as u64, Ordering::Relaxed);
        for lease in reply.leases {
            let rect = restauro_scene::plan::Rect::from(lease.rect.unwrap_or_default());
            let (bytes, _) = restauro_image::framebuffer::tile_sizes(&rect, layout);
            let header = pb::TileHeader {
                session: Some(session.clone()),
                lease: Some(lease),
                rays: 0,
                render_s: 0.0,
                xyz_bytes: bytes as u64,
                spectral_bytes: 0,
            };
            let messages = [
                pb::TileChunk { part: Some(pb::tile_chunk::Part::Header(header)) },
                pb::TileChunk { part: Some(pb::tile_chunk::Part::Data(vec![0; bytes])) },
            ];
            let reply = client
                .report_tile(tokio_stream::iter(messages))
                .await
                .map_err(|s| refused("reporting", s))?
                .into_inner();
            if reply.accepted {
                counts.accepted.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
    Ok(())
}
