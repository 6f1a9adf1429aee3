//! The cluster, as real processes on loopback: a coordinator, two workers and the client.

use restauro_coordinator::image_files::read_exr;
use restauro_tests::{CLIENT_TOKEN, Coordinator, WORKER_TOKEN, Worker, restauro, token_files};
use std::path::Path;
use std::time::{Duration, Instant};

fn text(o: &std::process::Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn aosta(dir: &Path) -> String {
    let scene = dir.join("aosta");
    let o = restauro(&[
        "scene",
        "aosta",
        "--out",
        scene.to_str().unwrap(),
        "--width",
        "96",
        "--height",
        "54",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    scene.join("aosta.toml").to_str().unwrap().to_owned()
}

fn pixels(path: &Path) -> Vec<[f32; 3]> {
    read_exr(path, 1 << 24).unwrap_or_else(|e| panic!("{}: {e}", path.display())).pixels
}

/// Bit-identical: compares every float's bits.
fn assert_identical(a: &[[f32; 3]], b: &[[f32; 3]]) {
    assert_eq!(a.len(), b.len());
    let differ =
        a.iter().zip(b).filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits)).count();
    assert_eq!(differ, 0, "{differ} of {} pixels differ", a.len());
}

#[test]
fn two_workers_render_what_one_process_renders_and_survive_a_killed_worker() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta(d);
    let local = d.join("local");
    let o = restauro(&[
        "render",
        &scene,
        "--in-process",
        "--spp",
        "2",
        "--tile",
        "16",
        "--out",
        local.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let reference = pixels(&local.join("aosta.exr"));

    let coordinator =
        Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &["--heartbeat-timeout-s", "1"]);
    let _w1 = Worker::start(d, &coordinator.url, "w1", &[]);
    let mut w2 = Worker::start(d, &coordinator.url, "w2", &[]);
    let (client_token, _) = token_files(d);
    let out = d.join("cluster");
    let o = restauro(&[
        "submit",
        &scene,
        "--wait",
        "--spp",
        "2",
        "--tile",
        "16",
        "--out",
        out.to_str().unwrap(),
        "--coordinator",
        &coordinator.url,
        "--token-file",
        client_token.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert_identical(&pixels(&out.join("aosta.exr")), &reference);
    let retinex = pixels(&out.join("aosta-retinex.exr"));
    assert_identical(&retinex, &pixels(&local.join("aosta-retinex.exr")));

    // A worker killed mid-job (SIGKILL): its tiles go back to the queue, the job completes and
    // the image is the same.
    let job = restauro(&[
        "submit",
        &scene,
        "--spp",
        "8",
        "--tile",
        "16",
        "--coordinator",
        &coordinator.url,
        "--token-file",
        client_token.to_str().unwrap(),
    ]);
    assert!(job.status.success(), "{}", text(&job));
    let id = String::from_utf8_lossy(&job.stdout).trim().to_owned();
    std::thread::sleep(Duration::from_millis(300));
    w2.0.kill().unwrap();
    let started = Instant::now();
    let out8 = d.join("cluster8");
    let o = restauro(&[
        "watch",
        &id,
        "--coordinator",
        &coordinator.url,
        "--token-file",
        client_token.to_str().unwrap(),
    ]);
    assert!(text(&o).contains("done"), "{}", text(&o));
    assert!(started.elapsed() < Duration::from_secs(120));
    let o = restauro(&[
        "fetch",
        &id,
        "--out",
        out8.to_str().unwrap(),
        "--coordinator",
        &coordinator.url,
        "--token-file",
        client_token.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let local8 = d.join("local8");
    let o = restauro(&[
        "render",
        &scene,
        "--in-process",
        "--spp",
        "8",
        "--tile",
        "16",
        "--out",
        local8.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert_identical(&pixels(&out8.join("aosta.exr")), &pixels(&local8.join("aosta.exr")));
}

#[test]
fn tokens_roles_versions_and_bad_scenes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta(d);
    let coordinator = Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &[]);
    let url = coordinator.url.as_str();
    let wrong = d.join("wrong.token");
    std::fs::write(&wrong, "not-a-token").unwrap();
    let worker_token = d.join("worker.token");
    let client_token = d.join("client.token");
    assert_eq!(std::fs::read_to_string(&client_token).unwrap(), CLIENT_TOKEN);

    let o = restauro(&["jobs", "--coordinator", url, "--token-file", wrong.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("unauthenticated"), "{}", text(&o));
    // A worker's token cannot act as a client.
    let o =
        restauro(&["jobs", "--coordinator", url, "--token-file", worker_token.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("forbidden"), "{}", text(&o));
    // A client of another protocol version.
    let o = restauro(&[
        "jobs",
        "--coordinator",
        url,
        "--token-file",
        client_token.to_str().unwrap(),
        "--protocol-version",
        "99",
    ]);
    assert!(
        !o.status.success() && text(&o).contains("protocol version 99 refused"),
        "{}",
        text(&o)
    );
    // A client's token cannot register a worker; a worker of another version is refused.
    let stolen = d.join("stolen.token");
    std::fs::write(&stolen, CLIENT_TOKEN).unwrap();
    let mut w = Worker::start_with_token(d, url, "thief", &stolen, &[]);
    let status = w.0.wait().unwrap();
    let log = std::fs::read_to_string(d.join("thief.log")).unwrap();
    assert!(!status.success() && log.contains("forbidden"), "{log}");
    let mut w = Worker::start(d, url, "old", &["--protocol-version", "0"]);
    let status = w.0.wait().unwrap();
    let log = std::fs::read_to_string(d.join("old.log")).unwrap();
    assert!(!status.success() && log.contains("protocol version 0 refused"), "{log}");
    assert_ne!(WORKER_TOKEN, CLIENT_TOKEN);

    // A scene the plan refuses (an unknown variant) is refused with the validation message,
    // which names what the scene does define.
    let o = restauro(&[
        "submit",
        &scene,
        "--variant",
        "polished",
        "--coordinator",
        url,
        "--token-file",
        client_token.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success()
            && text(&o).contains("unknown variant `polished`; the scene defines as-found, cleaned"),
        "{}",
        text(&o)
    );
}
