//! What an operator's tools see: the Prometheus endpoints of a coordinator and a worker (real
//! processes), scraped over HTTP — every listed metric present, and moving when jobs run and when
//! a lease expires — their health routes, and the gRPC health and reflection services.

use restauro_tests::{
    Coordinator, Worker, aosta_scene, http_get as get, restauro, sample as value, signal, text,
    token_files, wait_for,
};
use std::path::Path;
use std::time::{Duration, Instant};

/// A worker with its metrics endpoint; the worker and the endpoint's address.
fn worker(dir: &Path, url: &str) -> (Worker, String) {
    Worker::start_with_metrics(dir, url, "w1", &[])
}

const COORDINATOR_METRICS: [&str; 20] = [
    "restauro_tiles_queued",
    "restauro_tiles_leased",
    "restauro_workers_connected",
    "restauro_jobs_unfinished",
    "restauro_store_failing",
    "restauro_leases_total",
    "restauro_tiles_done_total",
    "restauro_tiles_requeued_total",
    "restauro_lease_expiries_total",
    "restauro_workers_lost_total",
    "restauro_tile_render_seconds_count",
    "restauro_retinex_seconds_count",
    "restauro_tile_received_bytes_total",
    "restauro_asset_received_bytes_total",
    "restauro_asset_sent_bytes_total",
    "restauro_result_sent_bytes_total",
    "restauro_tile_checks_agreed_total",
    "restauro_tile_checks_disputed_total",
    "restauro_tile_checks_undecided_total",
    "restauro_workers_quarantined_total",
];

const WORKER_METRICS: [&str; 6] = [
    "restauro_worker_tiles_rendered_total",
    "restauro_worker_tiles_delivered_total",
    "restauro_worker_tile_render_seconds_count",
    "restauro_worker_sent_bytes_total",
    "restauro_worker_asset_received_bytes_total",
    "restauro_worker_registered",
];

#[test]
fn metrics_are_scraped_and_move_when_jobs_run_and_leases_expire() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 192, 108);
    // Leases expire after a second: a stopped worker's tiles go back to the queue quickly,
    // while a running one renders each small tile in milliseconds.
    let coordinator = Coordinator::start(
        d,
        &d.join("data"),
        "127.0.0.1:0",
        &["--metrics-listen", "127.0.0.1:0", "--lease-timeout-s", "1"],
    );
    let c = coordinator.metrics.clone().unwrap();
    let (status, body) = get(&c, "/metrics");
    assert_eq!(status, 200, "{body}");
    let before = body;
    for name in COORDINATOR_METRICS {
        value(&before, name);
    }
    assert_eq!(get(&c, "/healthz").0, 200);
    assert_eq!(get(&c, "/readyz").0, 200);

    let (mut w, wm) = worker(d, &coordinator.url);
    // Ready once registered.
    wait_for("the worker to register", Duration::from_secs(20), || get(&wm, "/readyz").0 == 200);
    let worker_before = get(&wm, "/metrics").1;
    for name in WORKER_METRICS {
        value(&worker_before, name);
    }
    assert_eq!(value(&worker_before, "restauro_worker_registered"), 1.0);
    assert_eq!(value(&get(&c, "/metrics").1, "restauro_workers_connected"), 1.0);

    // A job, start to end.
    let (client_token, _) = token_files(d);
    let client = |args: &[&str]| {
        let mut all = args.to_vec();
        all.extend(["--coordinator", &coordinator.url, "--token-file"]);
        all.push(client_token.to_str().unwrap());
        restauro(&all)
    };
    let out = d.join("out");
    let o = client(&[
        "submit",
        &scene,
        "--wait",
        "--spp",
        "1",
        "--tile",
        "32",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    the_job_moved_the_counters(&c, &wm, &before, &worker_before);

    // A second job, long enough to freeze the worker in the middle of.
    let o = client(&["submit", &scene, "--spp", "64", "--tile", "16"]);
    assert!(o.status.success(), "{}", text(&o));
    a_frozen_workers_lease_expires_and_its_tile_is_requeued(&c, &w);
    let _ = w.0.kill();
    let _ = w.0.wait();
}

/// The first job (24 tiles) moved the coordinator's counters at `c` from `before` and the
/// worker's at `wm` from `worker_before`, and left nothing queued, leased or unfinished.
fn the_job_moved_the_counters(c: &str, wm: &str, before: &str, worker_before: &str) {
    let after = get(c, "/metrics").1;
    let tiles = 6.0 * 4.0; // 192×108 in tiles of 32
    let moved = |name: &str| value(&after, name) - value(before, name);
    assert_eq!(moved("restauro_tiles_done_total"), tiles, "{after}");
    assert!(moved("restauro_leases_total") >= tiles);
    assert_eq!(moved("restauro_tile_render_seconds_count"), tiles);
    assert_eq!(moved("restauro_retinex_seconds_count"), 1.0);
    for name in [
        "restauro_tile_received_bytes_total",
        "restauro_asset_received_bytes_total",
        "restauro_asset_sent_bytes_total",
        "restauro_result_sent_bytes_total",
    ] {
        assert!(moved(name) > 0.0, "{name} did not move");
    }
    assert_eq!(value(&after, "restauro_tiles_queued"), 0.0);
    assert_eq!(value(&after, "restauro_tiles_leased"), 0.0);
    assert_eq!(value(&after, "restauro_jobs_unfinished"), 0.0);
    let worker_after = get(wm, "/metrics").1;
    let worker_moved = |name: &str| value(&worker_after, name) - value(worker_before, name);
    assert_eq!(worker_moved("restauro_worker_tiles_rendered_total"), tiles);
    assert_eq!(worker_moved("restauro_worker_tile_render_seconds_count"), tiles);
    for name in ["restauro_worker_sent_bytes_total", "restauro_worker_asset_received_bytes_total"] {
        assert!(worker_moved(name) > 0.0, "{name} did not move");
    }
    wait_for("the last delivery to count", Duration::from_secs(5), || {
        value(&get(wm, "/metrics").1, "restauro_worker_tiles_delivered_total") >= tiles
    });
}

/// A second job, with the worker `w` frozen (SIGSTOP) while it holds a lease: tiles are queued
/// and leased meanwhile (as the coordinator's metrics at `c` show), the lease expires and its
/// tile is requeued; thawed, the worker finishes the job.
fn a_frozen_workers_lease_expires_and_its_tile_is_requeued(c: &str, w: &Worker) {
    let mut seen_queued = false;
    let mut seen_leased = false;
    let mut expired = false;
    for _ in 0..5 {
        wait_for("the second job to start", Duration::from_secs(20), || {
            value(&get(c, "/metrics").1, "restauro_tiles_leased") >= 1.0
        });
        signal(&w.0, "-STOP");
        let frozen = get(c, "/metrics").1;
        seen_queued |= value(&frozen, "restauro_tiles_queued") > 0.0;
        seen_leased |= value(&frozen, "restauro_tiles_leased") > 0.0;
        let deadline = Instant::now() + Duration::from_secs(4);
        while Instant::now() < deadline && !expired {
            expired = value(&get(c, "/metrics").1, "restauro_lease_expiries_total") >= 1.0;
            std::thread::sleep(Duration::from_millis(100));
        }
        signal(&w.0, "-CONT");
        if expired {
            break;
        }
    }
    assert!(seen_queued && seen_leased && expired, "{seen_queued} {seen_leased} {expired}");
    let now = get(c, "/metrics").1;
    assert!(value(&now, "restauro_tiles_requeued_total") >= 1.0, "{now}");
}

/// The standard gRPC health service answers without a token; reflection lists the services.
#[test]
fn grpc_health_and_reflection_answer() {
    use tonic_health::pb::HealthCheckRequest;
    use tonic_health::pb::health_check_response::ServingStatus;
    use tonic_health::pb::health_client::HealthClient;
    use tonic_reflection::pb::v1::ServerReflectionRequest;
    use tonic_reflection::pb::v1::server_reflection_client::ServerReflectionClient;
    use tonic_reflection::pb::v1::server_reflection_request::MessageRequest;
    use tonic_reflection::pb::v1::server_reflection_response::MessageResponse;

    let dir = tempfile::tempdir().unwrap();
    let coordinator = Coordinator::start(dir.path(), &dir.path().join("data"), "127.0.0.1:0", &[]);
    let runtime = tokio::runtime::Runtime::new().unwrap();
    runtime.block_on(async {
        let channel = tonic::transport::Endpoint::from_shared(coordinator.url.clone())
            .unwrap()
            .connect()
            .await
            .unwrap();
        let mut health = HealthClient::new(channel.clone());
        for service in ["", "restauro.v1.Render", "restauro.v1.Work"] {
            let reply = health
                .check(HealthCheckRequest { service: service.into() })
                .await
                .unwrap_or_else(|s| panic!("health of `{service}`: {s}"))
                .into_inner();
            assert_eq!(reply.status, ServingStatus::Serving as i32, "`{service}`");
        }
        let unknown = health.check(HealthCheckRequest { service: "nope".into() }).await;
        assert_eq!(unknown.unwrap_err().code(), tonic::Code::NotFound);

        let mut reflection = ServerReflectionClient::new(channel);
        let request = ServerReflectionRequest {
            host: String::new(),
            message_request: Some(MessageRequest::ListServices(String::new())),
        };
        let mut replies = reflection
            .server_reflection_info(tokio_stream::iter([request]))
            .await
            .unwrap()
            .into_inner();
        let reply = replies.message().await.unwrap().unwrap();
        let Some(MessageResponse::ListServicesResponse(list)) = reply.message_response else {
            panic!("{reply:?}");
        };
        let names: Vec<String> = list.service.into_iter().map(|s| s.name).collect();
        for expected in ["restauro.v1.Render", "restauro.v1.Work", "grpc.health.v1.Health"] {
            assert!(names.iter().any(|n| n == expected), "{expected} not in {names:?}");
        }
    });
}

/// A worker told to stop (SIGTERM, as Kubernetes and systemd do when scaling down) while its
/// coordinator is unreachable holds no tile: it exits at once, successfully, and says why — an
/// orchestrator must not count it as a failed pod or unit.
#[test]
fn a_worker_stopped_while_its_coordinator_is_away_exits_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A port nobody listens on: bound, then released.
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let (mut w, metrics) = worker(d, &format!("http://127.0.0.1:{port}"));
    let log = d.join("w1.log");
    wait_for("the worker to retry", Duration::from_secs(20), || {
        std::fs::read_to_string(&log).unwrap_or_default().contains("cannot reach the coordinator")
    });
    assert_eq!(get(&metrics, "/readyz").0, 503, "not registered, so not ready");

    signal(&w.0, "-TERM");
    let deadline = Instant::now() + Duration::from_secs(10);
    let status = loop {
        if let Some(status) = w.0.try_wait().unwrap() {
            break status;
        }
        assert!(Instant::now() < deadline, "the worker did not exit within 10 s of SIGTERM");
        std::thread::sleep(Duration::from_millis(20));
    };
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(status.success(), "the worker exited with {status}:\n{text}");
    assert!(text.contains("stopped before reaching the coordinator"), "{text}");
}

/// Finding 6 of "trust under load": /metrics was open to anyone who reached the port. Now a
/// coordinator and a worker refuse to serve it open on an address other machines reach, and with
/// a token file answer only a scraper that sends the token; health stays open for the probes.
#[test]
fn metrics_beyond_loopback_need_a_token_and_health_stays_open() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (client_token, worker_token) = token_files(d);
    let (data, cache) = (d.join("refused-data"), d.join("refused-cache"));
    let coordinator_args = vec![
        "--listen".as_ref(),
        "127.0.0.1:0".as_ref(),
        "--data".as_ref(),
        data.as_os_str(),
        "--client-token-file".as_ref(),
        client_token.as_os_str(),
        "--worker-token-file".as_ref(),
        worker_token.as_os_str(),
    ];
    let worker_args = vec![
        "--coordinator".as_ref(),
        "http://127.0.0.1:9".as_ref(),
        "--token-file".as_ref(),
        worker_token.as_os_str(),
        "--cache".as_ref(),
        cache.as_os_str(),
    ];
    for (binary, args) in
        [("restauro-coordinator", coordinator_args), ("restauro-worker", worker_args)]
    {
        let mut command = std::process::Command::new(restauro_tests::binary(binary));
        command.args::<_, &std::ffi::OsStr>(args);
        command.args(["--metrics-listen", "0.0.0.0:0"]).env_remove("RESTAURO_METRICS_TOKEN");
        let o = restauro_tests::output_within(&mut command, Duration::from_secs(60));
        assert!(!o.status.success(), "{binary} served open metrics on 0.0.0.0");
        let said = text(&o);
        assert!(
            said.contains("--metrics-listen 0.0.0.0:0 can be reached from other machines"),
            "{said}"
        );
        assert!(said.contains("give --metrics-token-file FILE"), "{said}");
    }

    let token = d.join("metrics.token");
    std::fs::write(&token, "scrape-only\n").unwrap();
    let token = token.to_str().unwrap();
    let guarded = ["--metrics-listen", "127.0.0.1:0", "--metrics-token-file", token];
    let coordinator = Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &guarded);
    let (_worker, w) = Worker::start_with_metrics(d, &coordinator.url, "w1", &guarded[2..]);
    let c = coordinator.metrics.clone().unwrap();
    let get_with = |addr: &str, path: &str, authorization: Option<&str>| {
        let headers: Vec<(&str, &str)> =
            authorization.map(|a| ("authorization", a)).into_iter().collect();
        restauro_tests::http::request(addr, "GET", path, &headers, b"")
    };
    for addr in [&c, &w] {
        for wrong in [None, Some("Bearer scrape"), Some("Basic c2NyYXBlLW9ubHk=")] {
            let answer = get_with(addr, "/metrics", wrong);
            assert_eq!(answer.status, 401, "{wrong:?}: {}", answer.text());
            assert!(answer.header("www-authenticate").is_some_and(|h| h.starts_with("Bearer")));
            assert!(!answer.text().contains("restauro_"), "{}", answer.text());
        }
        let answer = get_with(addr, "/metrics", Some("Bearer scrape-only"));
        assert_eq!(answer.status, 200, "{}", answer.text());
        assert!(answer.text().contains("restauro_"), "{}", answer.text());
        assert_eq!(get_with(addr, "/healthz", None).status, 200);
    }
    assert_eq!(get_with(&c, "/readyz", None).status, 200);
}
