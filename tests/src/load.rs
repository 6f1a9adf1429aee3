//! The coordinator under load (issue 35): many studio sessions and command-line clients on one
//! coordinator with two workers, and hostile callers among them — readers that never read,
//! uploads that stop sending, event streams nobody reads. What it measures: whether every honest
//! job finishes bit-identical to the in-process render, whether every studio request is
//! answered, the coordinator's memory over time, and each kind of request's latency (reported,
//! never asserted). A soak runs rounds of it for as long as asked, killing a worker and the
//! coordinator now and then.
//!
//! Used by `tests/load.rs` (CI's scale) and by the `load` benchmark binary (`src/bin/load.rs`),
//! which prints the report as JSON.

use crate::http::{Events, Response, try_request_within};
use crate::raw::{Head, Raw, memory_kb};
use crate::{CLIENT_TOKEN, Coordinator, WORKER_TOKEN, Worker, aosta_scene, restauro, text, wire};
use restauro_image::image_files::read_exr;
use restauro_proto as pb;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What to put on the coordinator.
#[derive(Clone, Debug)]
pub struct LoadPlan {
    /// Studio sessions: each signs in, keeps an event stream open, fetches the scene and its
    /// preview, takes a snapshot, follows it to its end and fetches its pictures.
    pub sessions: usize,
    /// `restauro submit --wait` processes, each rendering the scene and fetching its files.
    pub clients: usize,
    /// Requests for a 16 MiB file on raw HTTP/2 whose window is never opened.
    pub slow_readers: usize,
    /// Uploads that announce 200 MiB and send nothing.
    pub stalled_uploads: usize,
    /// Studio event streams opened and never read.
    pub unread_event_streams: usize,
    /// The scene's size in pixels, its samples per pixel and its tiles.
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub tile: u32,
    /// The coordinator's `--idle-timeout-s`: how long a silent reader or upload holds its place.
    pub idle_timeout_s: u32,
    /// Run rounds until this much time has passed, with kills (`None`: one round, no kills).
    pub soak: Option<Soak>,
}

/// The soak: how long, and how often a worker and the coordinator are killed (SIGKILL) and
/// started again.
#[derive(Clone, Copy, Debug)]
pub struct Soak {
    pub duration: Duration,
    pub worker_kill_every: Duration,
    pub coordinator_kill_every: Duration,
}

impl LoadPlan {
    /// The issue's load: 200 studio sessions, 50 clients, two workers, and hostile callers.
    pub fn issue() -> Self {
        LoadPlan {
            sessions: 200,
            clients: 50,
            slow_readers: 96,
            stalled_uploads: 4,
            unread_event_streams: 20,
            width: 48,
            height: 32,
            spp: 1,
            tile: 16,
            idle_timeout_s: 10,
            soak: None,
        }
    }
}

/// What a run saw.
#[derive(Debug, Default)]
pub struct LoadReport {
    /// Seconds from the start of the load to its end.
    pub elapsed_s: f64,
    /// The coordinator's resident memory before the load, its peak (VmHWM, over every process
    /// of a soak) and (seconds, MiB) samples over time.
    pub memory_before_mib: f64,
    pub memory_peak_mib: f64,
    pub memory_mib: Vec<(f64, f64)>,
    /// Studio requests sent, and answered with a success.
    pub studio_requests: usize,
    pub studio_answered: usize,
    /// What went wrong with those not answered (at most 20).
    pub studio_failures: Vec<String>,
    /// Milliseconds per kind of request.
    pub latency_ms: BTreeMap<&'static str, Vec<f64>>,
    /// Honest jobs: finished, finished bit-identical to the reference, and why others were not.
    pub jobs: usize,
    pub jobs_identical: usize,
    pub job_failures: Vec<String>,
    /// Slow readers served (holding a place) and refused; stalled uploads cut.
    pub slow_readers_served: usize,
    pub slow_readers_refused: usize,
    pub stalled_uploads_cut: usize,
    /// Soak: workers and coordinators killed.
    pub kills: usize,
}

impl LoadReport {
    /// The report as JSON: counts, memory, and each latency's count, median, 95th percentile
    /// and maximum.
    pub fn json(&self) -> serde_json::Value {
        let latency: serde_json::Map<String, serde_json::Value> = self
            .latency_ms
            .iter()
            .map(|(kind, values)| {
                let mut v = values.clone();
                v.sort_by(f64::total_cmp);
                let at = |q: f64| v.get(((v.len() as f64 - 1.0) * q).round() as usize).copied();
                let summary = serde_json::json!({
                    "count": v.len(), "p50_ms": at(0.5), "p95_ms": at(0.95), "max_ms": v.last(),
                });
                ((*kind).to_owned(), summary)
            })
            .collect();
        serde_json::json!({
            "schema": "restauro.bench.load/1",
            "elapsed_s": self.elapsed_s,
            "coordinator_memory_mib": {
                "before": self.memory_before_mib,
                "peak": self.memory_peak_mib,
                "over_time": self.memory_mib.iter().map(|(t, m)| [*t, *m]).collect::<Vec<_>>(),
            },
            "studio": {
                "requests": self.studio_requests,
                "answered": self.studio_answered,
                "failures": self.studio_failures,
            },
            "jobs": { "finished": self.jobs, "identical": self.jobs_identical, "failures": self.job_failures },
            "hostile": {
                "slow_readers_served": self.slow_readers_served,
                "slow_readers_refused": self.slow_readers_refused,
                "stalled_uploads_cut": self.stalled_uploads_cut,
            },
            "kills": self.kills,
            "latency": latency,
        })
    }
}

/// What the threads of a run share.
struct Shared {
    studio: Mutex<String>,
    grpc: Mutex<String>,
    pid: AtomicU32,
    /// Retry a request that finds no coordinator (a soak kills it) instead of failing.
    patient: bool,
    stop: AtomicBool,
    report: Mutex<LoadReport>,
    peak_kb: AtomicUsize,
    /// The client token's file.
    token: PathBuf,
}

impl Shared {
    fn latency(&self, kind: &'static str, took: Duration) {
        let mut r = self.report.lock().unwrap();
        r.latency_ms.entry(kind).or_default().push(took.as_secs_f64() * 1e3);
    }

    fn studio_failure(&self, what: String) {
        let mut r = self.report.lock().unwrap();
        if r.studio_failures.len() < 20 {
            r.studio_failures.push(what);
        }
    }

    /// One studio request, timed as `kind`; a success counts as answered. A soak retries a
    /// request that finds no coordinator for up to two minutes (the time is the whole wait).
    fn studio(
        &self,
        kind: &'static str,
        method: &str,
        path: &str,
        headers: &[(&str, &str)],
        body: &[u8],
    ) -> Option<Response> {
        let started = Instant::now();
        self.report.lock().unwrap().studio_requests += 1;
        loop {
            let addr = self.studio.lock().unwrap().clone();
            // A page waits as long as the coordinator takes; latency is what is measured.
            let patience = Duration::from_secs(600);
            match try_request_within(&addr, method, path, headers, body, patience) {
                Ok(r) if (200..300).contains(&r.status) => {
                    self.latency(kind, started.elapsed());
                    self.report.lock().unwrap().studio_answered += 1;
                    return Some(r);
                }
                Ok(r) if !(self.patient && r.status >= 500) => {
                    self.studio_failure(format!("{method} {path}: {} {}", r.status, r.text()));
                    return None;
                }
                Ok(_) | Err(_) if self.patient && started.elapsed() < Duration::from_secs(120) => {
                    std::thread::sleep(Duration::from_millis(500));
                }
                Ok(r) => {
                    self.studio_failure(format!("{method} {path}: {} {}", r.status, r.text()));
                    return None;
                }
                Err(e) => {
                    self.studio_failure(format!("{method} {path}: {e}"));
                    return None;
                }
            }
        }
    }
}

/// The resident memory of the coordinator now, in MiB, and its process's peak in kB.
fn sample_memory(shared: &Shared, started: Instant) {
    let (now_kb, peak_kb) = memory_kb(shared.pid.load(Ordering::Relaxed));
    shared.peak_kb.fetch_max(peak_kb as usize, Ordering::Relaxed);
    let t = started.elapsed().as_secs_f64();
    shared.report.lock().unwrap().memory_mib.push((t, now_kb as f64 / 1024.0));
}

/// The XYZ pixels of an EXR, bit for bit.
fn pixels(path: &Path) -> Result<Vec<[u32; 3]>, String> {
    let image = read_exr(path, 1 << 24).map_err(|e| e.to_string())?;
    Ok(image.pixels.iter().map(|p| p.map(f32::to_bits)).collect())
}

/// The reference: the scene rendered in-process, as every cluster image must equal it.
fn reference(dir: &Path, scene: &str, plan: &LoadPlan) -> Vec<[u32; 3]> {
    let out = dir.join("reference");
    let (spp, tile) = (plan.spp.to_string(), plan.tile.to_string());
    let args = ["render", scene, "--in-process", "--spp", &spp, "--tile", &tile, "--out"];
    let o = restauro(&[&args[..], &[out.to_str().unwrap()]].concat());
    assert!(o.status.success(), "the reference render: {}", text(&o));
    pixels(&out.join("aosta.exr")).unwrap()
}

/// One command-line client: submits the scene, waits, fetches the files; whether its image is
/// the reference.
fn cli_client(shared: &Shared, dir: &Path, scene: &str, plan: &LoadPlan, reference: &[[u32; 3]]) {
    let out = dir.join("out");
    let (spp, tile) = (plan.spp.to_string(), plan.tile.to_string());
    let url = format!("http://{}", shared.grpc.lock().unwrap());
    let token = &shared.token;
    let started = Instant::now();
    let o = restauro(&[
        "submit",
        scene,
        "--spp",
        &spp,
        "--tile",
        &tile,
        "--wait",
        "--out",
        out.to_str().unwrap(),
        "--coordinator",
        &url,
        "--token-file",
        token.to_str().unwrap(),
    ]);
    shared.latency("cli submit to files", started.elapsed());
    let verdict = if o.status.success() {
        pixels(&out.join("aosta.exr")).map(|p| p == reference)
    } else {
        Err(text(&o))
    };
    record_job(shared, verdict, "a client's job");
}

fn record_job(shared: &Shared, verdict: Result<bool, String>, what: &str) {
    let mut r = shared.report.lock().unwrap();
    r.jobs += 1;
    match verdict {
        Ok(true) => r.jobs_identical += 1,
        Ok(false) => r.job_failures.push(format!("{what}: its image differs from the reference")),
        Err(e) => r.job_failures.push(format!("{what}: {e}")),
    }
}

/// The scene's snapshot request, from its view: its own camera.
fn snapshot_body(view: &serde_json::Value, plan: &LoadPlan) -> String {
    let c = &view["camera"];
    serde_json::json!({
        "camera": {
            "position": c["position"], "target": c["target"], "up": c["up"],
            "vertical_fov_deg": c["vertical_fov_deg"]
        },
        "render": {
            "width": plan.width, "height": plan.height,
            "samples_per_pixel": plan.spp, "integrator": "whitted",
        },
    })
    .to_string()
}

/// One studio session: the result EXR of its snapshot, when it got that far.
fn studio_session(shared: &Arc<Shared>, scene_id: &str, body: &str) -> Option<Vec<u8>> {
    let origin = format!("http://{}", shared.studio.lock().unwrap());
    let token = serde_json::json!({ "token": CLIENT_TOKEN }).to_string();
    let signed = shared.studio(
        "sign in",
        "POST",
        "/api/session",
        &[("Origin", &origin)],
        token.as_bytes(),
    )?;
    let set = signed.header("set-cookie").unwrap_or_default();
    let cookie = set.split(';').next().unwrap_or_default().to_owned();
    let auth = [("Cookie", cookie.as_str()), ("Origin", origin.as_str())];
    follow_events(shared, cookie.clone());
    shared.studio("scene", "GET", &format!("/api/scenes/{scene_id}"), &auth, b"")?;
    let glb = shared.studio(
        "preview",
        "GET",
        &format!("/api/scenes/{scene_id}/preview.glb"),
        &auth,
        b"",
    )?;
    if !glb.body.starts_with(b"glTF") {
        shared.studio_failure("the preview is not glTF".into());
    }
    let path = format!("/api/scenes/{scene_id}/snapshots");
    let job = shared.studio("snapshot", "POST", &path, &auth, body.as_bytes())?.json();
    let id = job["id"].as_str()?.to_owned();
    let job = loop {
        std::thread::sleep(Duration::from_secs(1));
        let job = shared.studio("job status", "GET", &format!("/api/jobs/{id}"), &auth, b"")?;
        let job = job.json();
        if job["finished"].as_bool() == Some(true) {
            break job;
        }
    };
    if job["state"] != "done" {
        record_job(shared, Err(format!("{job}")), "a snapshot");
        return None;
    }
    shared.studio("display", "GET", &format!("/api/jobs/{id}/display.png"), &auth, b"")?;
    let exr = job["results"]
        .as_array()?
        .iter()
        .find_map(|n| n.as_str().filter(|n| n.ends_with(".exr") && !n.ends_with("-retinex.exr")))?;
    let result = format!("/api/jobs/{id}/results/{exr}");
    Some(shared.studio("result", "GET", &result, &auth, b"")?.body)
}

/// Keeps an event stream of the session open and read until the run stops. As the page does,
/// it opens the stream again when the coordinator ends it (a reader that lags behind a burst of
/// changes, a soak's kill), from the last event it saw.
fn follow_events(shared: &Arc<Shared>, cookie: String) {
    let shared = shared.clone();
    std::thread::spawn(move || {
        let mut last_id = String::new();
        while !shared.stop.load(Ordering::Relaxed) {
            let addr = shared.studio.lock().unwrap().clone();
            let started = Instant::now();
            let mut headers = vec![("Cookie", cookie.as_str())];
            if !last_id.is_empty() {
                headers.push(("Last-Event-ID", last_id.as_str()));
            }
            let Ok(mut events) = Events::try_open(&addr, "/api/events", &headers) else {
                std::thread::sleep(Duration::from_millis(500));
                continue;
            };
            shared.latency("events open", started.elapsed());
            while !shared.stop.load(Ordering::Relaxed) {
                match events.try_next_event() {
                    Ok(event) if !event.id.is_empty() => last_id = event.id,
                    Ok(_) => {}
                    Err(_) => break,
                }
            }
        }
    });
}

/// The hostile callers: readers that never read a 16 MiB asset, uploads that announce 200 MiB
/// and send nothing, event streams never read. Runs on its own runtime until the load ends.
fn hostile(shared: &Arc<Shared>, plan: &LoadPlan) -> std::thread::JoinHandle<()> {
    let (shared, plan) = (shared.clone(), plan.clone());
    std::thread::spawn(move || {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        runtime.block_on(hostile_calls(&shared, &plan));
    })
}

async fn hostile_calls(shared: &Arc<Shared>, plan: &LoadPlan) {
    let url = format!("http://{}", shared.grpc.lock().unwrap());
    // Made before connecting: a connection whose runtime is busy cannot answer the
    // coordinator's pings, and is closed as dead.
    let data: Vec<u8> =
        (0..16u64 << 20).map(|i| (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8).collect();
    let mut client = wire::render_client(&url).await;
    let reference = format!("blake3:{}.bin", blake3::hash(&data).to_hex());
    wire::upload_bytes(&mut client, &reference, &data).await.unwrap();
    let mut work = wire::work_client(&url).await;
    let session = wire::register(&mut work, "slow-reader").await;
    let request = pb::FetchAssetRequest { session: Some(session), reference };
    let mut held = Vec::new();
    let mut connections = Vec::new();
    for i in 0..plan.slow_readers {
        if i % 32 == 0 {
            connections.push(Raw::connect(&url).await);
        }
        let raw = connections.last_mut().unwrap();
        match raw.call("/restauro.v1.Work/FetchAsset", WORKER_TOKEN, &request, true).await {
            Ok((Head::Streaming(body), _)) => held.push(body),
            Ok((Head::Refused(..), _)) | Err(_) => {
                shared.report.lock().unwrap().slow_readers_refused += 1;
            }
        }
    }
    shared.report.lock().unwrap().slow_readers_served = held.len();
    let mut stalled = Vec::new();
    for i in 0..plan.stalled_uploads {
        let mut raw = Raw::connect(&url).await;
        let name = format!("blake3:{}.bin", blake3::hash(&[i as u8]).to_hex());
        let first = pb::Chunk { name, total_bytes: 200 << 20, data: Vec::new() };
        stalled.push(tokio::spawn(async move {
            let call = raw.call("/restauro.v1.Render/UploadAsset", CLIENT_TOKEN, &first, false);
            matches!(call.await, Ok((Head::Refused(..), _)) | Err(_))
        }));
    }
    let studio = shared.studio.lock().unwrap().clone();
    let bearer = format!("Bearer {CLIENT_TOKEN}");
    let unread: Vec<_> = (0..plan.unread_event_streams)
        .filter_map(|_| {
            Events::try_open(&studio, "/api/events", &[("Authorization", &bearer)]).ok()
        })
        .collect();
    for s in stalled {
        if s.await.unwrap_or(false) {
            shared.report.lock().unwrap().stalled_uploads_cut += 1;
        }
    }
    while !shared.stop.load(Ordering::Relaxed) {
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    drop((held, connections, unread));
}

/// The farm of a run: its coordinator's arguments, and the coordinator and workers.
struct Farm {
    dir: PathBuf,
    args: Vec<String>,
    coordinator: Coordinator,
    workers: Vec<Worker>,
    /// A soak's next kills (of a worker, of the coordinator) and its next victim among workers:
    /// kept from round to round.
    next_kills: Option<(Duration, Duration)>,
    victim: usize,
}

impl Farm {
    fn start(dir: &Path, plan: &LoadPlan, grpc: &str, studio: &str) -> Farm {
        let args: Vec<String> = [
            "--studio-listen",
            studio,
            "--max-jobs",
            "1000",
            "--idle-timeout-s",
            &plan.idle_timeout_s.to_string(),
        ]
        .map(str::to_owned)
        .to_vec();
        let coordinator = Self::coordinator(dir, grpc, &args);
        let workers =
            (0..2).map(|i| Worker::start(dir, &coordinator.url, &format!("w{i}"), &[])).collect();
        Farm { dir: dir.to_owned(), args, coordinator, workers, next_kills: None, victim: 0 }
    }

    fn coordinator(dir: &Path, grpc: &str, args: &[String]) -> Coordinator {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        Coordinator::start(dir, &dir.join("data"), grpc, &args)
    }

    /// Kills the coordinator and starts another on the same addresses and store.
    fn restart_coordinator(&mut self, shared: &Shared) {
        let grpc = shared.grpc.lock().unwrap().clone();
        let _ = self.coordinator.child.kill();
        let _ = self.coordinator.child.wait();
        let studio = shared.studio.lock().unwrap().clone();
        let mut args = self.args.clone();
        args[1] = studio;
        self.coordinator = Self::coordinator(&self.dir, &grpc, &args);
        shared.pid.store(self.coordinator.child.id(), Ordering::Relaxed);
    }

    /// Kills worker `i % 2` and starts another in its place, the `i`th.
    fn restart_worker(&mut self, i: usize) {
        let name = format!("w{i}-again");
        self.workers[i % 2] = Worker::start(&self.dir, &self.coordinator.url, &name, &[]);
    }
}

/// Runs the load of `plan` in `dir` (scenes, store, results, logs).
pub fn run(dir: &Path, plan: &LoadPlan) -> LoadReport {
    let scene = aosta_scene(dir, plan.width, plan.height);
    let reference = reference(dir, &scene, plan);
    let mut farm = Farm::start(dir, plan, "127.0.0.1:0", "127.0.0.1:0");
    let shared = Arc::new(Shared {
        studio: Mutex::new(farm.coordinator.studio.clone().unwrap()),
        grpc: Mutex::new(farm.coordinator.url.trim_start_matches("http://").to_owned()),
        pid: AtomicU32::new(farm.coordinator.child.id()),
        patient: plan.soak.is_some(),
        stop: AtomicBool::new(false),
        report: Mutex::new(LoadReport::default()),
        peak_kb: AtomicUsize::new(0),
        token: crate::token_files(dir).0,
    });
    // The first job puts the scene in the coordinator for the studio.
    let first = dir.join("first");
    std::fs::create_dir_all(&first).unwrap();
    cli_client(&shared, &first, &scene, plan, &reference);
    let bearer = format!("Bearer {CLIENT_TOKEN}");
    let auth = [("Authorization", bearer.as_str())];
    let scenes = shared.studio("scenes", "GET", "/api/scenes", &auth, b"").expect("the scenes");
    let scene_id = scenes.json()[0]["id"].as_str().expect("a scene").to_owned();
    let view = shared.studio("scene", "GET", &format!("/api/scenes/{scene_id}"), &auth, b"");
    let body = snapshot_body(&view.expect("the scene's view").json(), plan);
    // A snapshot on the quiet farm: what every snapshot under load must equal. (Not the
    // in-process render: the studio's camera goes through the view's offset and back.)
    let quiet = studio_session(&shared, &scene_id, &body).expect("a snapshot on the quiet farm");
    let quiet_path = dir.join("quiet-snapshot.exr");
    std::fs::write(&quiet_path, quiet).unwrap();
    let quiet = pixels(&quiet_path).unwrap();
    let memory_before = memory_kb(shared.pid.load(Ordering::Relaxed)).0 as f64 / 1024.0;
    *shared.report.lock().unwrap() = LoadReport::default();
    let started = Instant::now();
    let sampler = {
        let shared = shared.clone();
        std::thread::spawn(move || {
            while !shared.stop.load(Ordering::Relaxed) {
                sample_memory(&shared, started);
                std::thread::sleep(Duration::from_millis(250));
            }
        })
    };
    let hostile = hostile(&shared, plan);
    let run = Run {
        shared: shared.clone(),
        dir: dir.to_owned(),
        scene,
        plan: plan.clone(),
        reference: Arc::new(reference),
        scene_id,
        body,
        snapshots: Arc::default(),
    };
    let mut round = 0;
    loop {
        round += 1;
        run.round(round, &mut farm, started);
        match plan.soak {
            Some(soak) if started.elapsed() < soak.duration => continue,
            _ => break,
        }
    }
    shared.stop.store(true, Ordering::Relaxed);
    let _ = hostile.join();
    let _ = sampler.join();
    check_snapshots(&shared, dir, &run.snapshots.lock().unwrap(), &quiet);
    let mut report = std::mem::take(&mut *shared.report.lock().unwrap());
    report.elapsed_s = started.elapsed().as_secs_f64();
    report.memory_before_mib = memory_before;
    report.memory_peak_mib = shared.peak_kb.load(Ordering::Relaxed) as f64 / 1024.0;
    drop(farm);
    report
}

/// What the rounds of a run share.
struct Run {
    shared: Arc<Shared>,
    dir: PathBuf,
    scene: String,
    plan: LoadPlan,
    reference: Arc<Vec<[u32; 3]>>,
    scene_id: String,
    body: String,
    snapshots: Arc<Mutex<Vec<Vec<u8>>>>,
}

impl Run {
    /// One round: every session and client at once; in a soak, kills while they run.
    fn round(&self, round: usize, farm: &mut Farm, started: Instant) {
        let mut threads = Vec::new();
        for i in 0..self.plan.clients {
            let (shared, scene, plan, reference) = (
                self.shared.clone(),
                self.scene.clone(),
                self.plan.clone(),
                self.reference.clone(),
            );
            let client_dir = self.dir.join(format!("clients/{round}-{i}"));
            std::fs::create_dir_all(&client_dir).unwrap();
            threads.push(std::thread::spawn(move || {
                cli_client(&shared, &client_dir, &scene, &plan, &reference);
            }));
        }
        for _ in 0..self.plan.sessions {
            let (shared, scene_id, body, snapshots) = (
                self.shared.clone(),
                self.scene_id.clone(),
                self.body.clone(),
                self.snapshots.clone(),
            );
            threads.push(std::thread::spawn(move || {
                if let Some(exr) = studio_session(&shared, &scene_id, &body) {
                    snapshots.lock().unwrap().push(exr);
                }
            }));
        }
        if let Some(soak) = self.plan.soak {
            self.kill_while_running(&threads, soak, farm, started);
        }
        threads.into_iter().for_each(|t| t.join().unwrap());
    }

    /// A soak's kills: a worker every `worker_kill_every`, the coordinator every
    /// `coordinator_kill_every`, until the round's threads end.
    fn kill_while_running(
        &self,
        threads: &[std::thread::JoinHandle<()>],
        soak: Soak,
        farm: &mut Farm,
        started: Instant,
    ) {
        let shared = &self.shared;
        let now = started.elapsed();
        let (mut next_worker, mut next_coordinator) = farm
            .next_kills
            .unwrap_or((now + soak.worker_kill_every, now + soak.coordinator_kill_every));
        while threads.iter().any(|t| !t.is_finished()) {
            std::thread::sleep(Duration::from_millis(200));
            let now = started.elapsed();
            if now >= next_worker {
                farm.restart_worker(farm.victim);
                farm.victim += 1;
                next_worker = now + soak.worker_kill_every;
                shared.report.lock().unwrap().kills += 1;
            }
            if now >= next_coordinator {
                // The peak of the process about to go.
                sample_memory(shared, started);
                farm.restart_coordinator(shared);
                next_coordinator = now + soak.coordinator_kill_every;
                shared.report.lock().unwrap().kills += 1;
            }
        }
        farm.next_kills = Some((next_worker, next_coordinator));
    }
}

/// Every snapshot took the same view: each must be the one taken on the quiet farm.
fn check_snapshots(shared: &Shared, dir: &Path, snapshots: &[Vec<u8>], reference: &[[u32; 3]]) {
    let path = dir.join("snapshot.exr");
    for exr in snapshots {
        std::fs::write(&path, exr).unwrap();
        record_job(shared, pixels(&path).map(|p| p == reference), "a snapshot");
    }
}
