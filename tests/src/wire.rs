//! A hand-written client and worker of restauro's gRPC protocol, for tests that play a hostile
//! caller against a real coordinator process: they send what the real client and worker never
//! would (another worker's lease, a forged ticket, NaN pixels, a name with terminal escapes).

use restauro_assets::bundle_scene;
use restauro_image::framebuffer::{TileExtras, TileLayout, encode_tile};
use restauro_proto::pb::render_client::RenderClient;
use restauro_proto::pb::work_client::WorkClient;
use restauro_proto::{self as pb, CHUNK_BYTES, Credentials, PROTOCOL_VERSION};
use restauro_scene::bundle::Bundle;
use restauro_scene::job::JobSpec;
use restauro_scene::limits::Limits;
use restauro_scene::plan::Rect;
use std::num::NonZeroU32;
use std::path::Path;
use std::time::Duration;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Channel;

pub type Render = RenderClient<InterceptedService<Channel, Credentials>>;
pub type Work = WorkClient<InterceptedService<Channel, Credentials>>;

async fn channel(url: &str) -> Channel {
    Channel::from_shared(url.to_owned()).unwrap().connect().await.unwrap()
}

/// A client with the tests' client token.
pub async fn render_client(url: &str) -> Render {
    let credentials = Credentials::new(crate::CLIENT_TOKEN, PROTOCOL_VERSION).unwrap();
    RenderClient::with_interceptor(channel(url).await, credentials)
        .max_decoding_message_size(64 << 20)
}

/// A worker connection with the tests' worker token.
pub async fn work_client(url: &str) -> Work {
    let credentials = Credentials::new(crate::WORKER_TOKEN, PROTOCOL_VERSION).unwrap();
    WorkClient::with_interceptor(channel(url).await, credentials)
}

/// `data` uploaded as `reference`, in the protocol's chunks.
pub async fn upload_bytes(
    client: &mut Render,
    reference: &str,
    data: &[u8],
) -> Result<pb::AssetList, tonic::Status> {
    let mut chunks: Vec<pb::Chunk> = data
        .chunks(CHUNK_BYTES)
        .map(|c| pb::Chunk {
            name: String::new(),
            total_bytes: data.len() as u64,
            data: c.to_vec(),
        })
        .collect();
    if chunks.is_empty() {
        chunks.push(pb::Chunk::default());
    }
    chunks[0].name = reference.to_owned();
    client.upload_asset(tokio_stream::iter(chunks)).await.map(tonic::Response::into_inner)
}

/// The references of every file of the scene at `scene`.
pub fn bundle_references(scene: &Path) -> Vec<String> {
    bundle_scene(scene, &Limits::default()).unwrap().references()
}

/// The scene's bundle, every asset uploaded.
pub async fn upload(client: &mut Render, scene: &Path) -> Bundle {
    let bundle = bundle_scene(scene, &Limits::default()).unwrap();
    for reference in bundle.references() {
        let hash = reference.strip_prefix("blake3:").unwrap().split_once('.').unwrap().0;
        upload_bytes(client, &reference, &bundle.files[hash]).await.unwrap();
    }
    bundle
}

/// A job of `name` in tiles of `tile` pixels at `spp` samples per pixel.
pub fn spec(name: &str, tile: u32, spp: u32) -> JobSpec {
    JobSpec {
        name: restauro_scene::job::JobName::new(name).unwrap(),
        render: restauro_scene::plan::RenderOptions {
            samples_per_pixel: NonZeroU32::new(spp),
            tile: NonZeroU32::new(tile),
            ..Default::default()
        },
        ..JobSpec::default()
    }
}

/// A coordinator process for a test in `dir`, with the Aosta scene of `width × height`
/// uploaded: the coordinator, a client of it, and the scene's bundle.
pub async fn farm(
    dir: &Path,
    width: u32,
    height: u32,
    coordinator_args: &[&str],
) -> (crate::Coordinator, Render, Bundle) {
    let scene = crate::aosta_scene(dir, width, height);
    // The workers these tests play send made-up pixels: a check on a real worker would find
    // them out (tests/tests/checks.rs tests that).
    let mut args = vec!["--check-rate", "0", "--check-rate-new", "0"];
    args.extend(coordinator_args);
    let coordinator = crate::Coordinator::start(dir, &dir.join("data"), "127.0.0.1:0", &args);
    let mut client = render_client(&coordinator.url).await;
    let bundle = upload(&mut client, Path::new(&scene)).await;
    (coordinator, client, bundle)
}

/// Submits `spec` for `bundle`'s scene.
pub async fn submit(
    client: &mut Render,
    bundle: &Bundle,
    spec: &JobSpec,
) -> Result<pb::JobStatus, tonic::Status> {
    let request = pb::convert::submit_request(bundle.canonical_json(), spec);
    client.submit_job(request).await.map(tonic::Response::into_inner)
}

/// A registered worker's session, its identity drawn from its name.
pub async fn register(work: &mut Work, name: &str) -> pb::WorkerSession {
    register_as(work, name, *blake3::hash(name.as_bytes()).as_bytes()).await
}

/// A registered worker's session, with the identity given (the same worker registering again
/// after a coordinator restart gives the same).
pub async fn register_as(work: &mut Work, name: &str, identity: [u8; 32]) -> pb::WorkerSession {
    let reply = work
        .register(pb::RegisterRequest {
            protocol_version: PROTOCOL_VERSION,
            name: name.to_owned(),
            capacity: 1,
            build: "restauro-tests".into(),
            identity: identity.to_vec(),
        })
        .await
        .unwrap()
        .into_inner();
    reply.session.unwrap()
}

/// Up to `max` leases, waiting up to a second.
pub async fn pull(work: &mut Work, session: &pb::WorkerSession, max: u32) -> pb::PullReply {
    work.pull_leases(pb::PullRequest { session: Some(session.clone()), max, wait_ms: 1000 })
        .await
        .unwrap()
        .into_inner()
}

/// Leases, pulled until at least one comes (the job was just submitted).
pub async fn lease(work: &mut Work, session: &pb::WorkerSession, max: u32) -> Vec<pb::Lease> {
    for _ in 0..30 {
        let reply = pull(work, session, max).await;
        assert!(reply.known, "the coordinator forgot the worker");
        if !reply.leases.is_empty() {
            return reply.leases;
        }
    }
    panic!("no lease in 30 s")
}

/// The tiles of the demo's facade (`aosta`): XYZ, sky coverage (it has a sky), light masks
/// (it has a sun) and adapting whites (it is an image), no spectra.
pub const AOSTA_TILES: TileLayout =
    TileLayout { spectral: false, sky: true, lit: true, white: true, samples_cap: 0 };

/// The bytes of a tile of `rect` whose every XYZ value is `value`, with sky coverage 0 and no
/// light as the layout asks.
pub fn tile_data(rect: &Rect, layout: TileLayout, value: f32) -> Vec<u8> {
    let pixels = rect.width as usize * rect.height as usize;
    let xyz = vec![[value; 3]; pixels];
    let (sky, lit, white) = (vec![0f32; pixels], vec![0u32; pixels], vec![[value; 4]; pixels]);
    let samples = vec![layout.samples_cap; pixels];
    let extras = TileExtras {
        sky: layout.sky.then_some(&sky[..]),
        lit_by: layout.lit.then_some(&lit[..]),
        white: layout.white.then_some(&white[..]),
        samples: layout.counts().then_some(&samples[..]),
    };
    encode_tile(&xyz, extras, None::<std::iter::Empty<&[f32]>>)
}

/// Reports `data` for `lease` with `session`.
pub async fn report(
    work: &mut Work,
    session: &pb::WorkerSession,
    lease: &pb::Lease,
    data: Vec<u8>,
) -> Result<pb::ReportReply, tonic::Status> {
    let header = pb::TileHeader {
        session: Some(session.clone()),
        lease: Some(lease.clone()),
        rays: 0,
        render_s: 0.0,
        xyz_bytes: data.len() as u64,
        spectral_bytes: 0,
    };
    let messages = [
        pb::TileChunk { part: Some(pb::tile_chunk::Part::Header(header)) },
        pb::TileChunk { part: Some(pb::tile_chunk::Part::Data(data)) },
    ];
    work.report_tile(tokio_stream::iter(messages)).await.map(tonic::Response::into_inner)
}

/// The job's status, from the list.
pub async fn status(client: &mut Render, job: &str) -> pb::JobStatus {
    let list = client.list_jobs(pb::ListJobsRequest {}).await.unwrap().into_inner();
    list.jobs.into_iter().find(|j| j.job_id == job).expect("the job is listed")
}

/// Follows the job until it ends; its last status. Fails the test after `limit`.
pub async fn wait_end(client: &mut Render, job: &str, limit: Duration) -> pb::JobStatus {
    let watch = async {
        let mut stream =
            client.watch_job(pb::JobRef { job_id: job.to_owned() }).await.unwrap().into_inner();
        let mut last = None;
        while let Some(s) = stream.message().await.unwrap() {
            last = Some(s);
        }
        last.expect("a status")
    };
    tokio::time::timeout(limit, watch).await.expect("the job ended in time")
}

/// [`wait_end`], with the logs of the processes in `dir` in the failure's message.
pub async fn wait_end_logged(
    client: &mut Render,
    job: &str,
    limit: Duration,
    dir: &std::path::Path,
) -> pb::JobStatus {
    let end = tokio::time::timeout(limit, wait_end(client, job, limit + Duration::from_secs(1)));
    match end.await {
        Ok(status) => status,
        Err(_) => panic!("the job did not end within {limit:?}\n{}", crate::logs(dir)),
    }
}

/// Whether a status's state is final.
pub fn is_final(status: &pb::JobStatus) -> bool {
    matches!(
        pb::JobState::try_from(status.state),
        Ok(pb::JobState::Done | pb::JobState::Failed | pb::JobState::Cancelled)
    )
}

/// The resident-set peak (VmHWM) and the current resident set (VmRSS) of a process, in KiB.
pub fn memory_kib(pid: u32) -> (u64, u64) {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.trim().trim_end_matches(" kB").trim().parse().ok())
            .unwrap_or(0)
    };
    (field("VmHWM:"), field("VmRSS:"))
}
