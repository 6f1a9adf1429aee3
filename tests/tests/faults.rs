//! Faults a site's coordinator meets, on real processes: its disk filling up under a job, and a
//! restart while a client waits for its job.

use restauro_image::image_files::read_exr;
use restauro_proto as pb;
use restauro_scene::job::JobSpec;
use restauro_scene::plan::RenderOptions;
use restauro_tests::wire::{self, spec};
use restauro_tests::{
    Coordinator, Worker, aosta_scene, http_get, restauro, sample, text, token_files, wait_for,
};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

/// Defect 18: when the store cannot be written (here: the kernel refuses to let its file grow,
/// RLIMIT_FSIZE, the way a full disk refuses a write), the coordinator says so — in its log, in
/// `restauro jobs`, in its metrics and `/readyz` — keeps every worker's result for a retry, and
/// finishes the job without a restart once writes succeed again. The image is the in-process
/// render's, bit for bit.
#[test]
fn a_store_that_cannot_grow_is_reported_and_the_job_resumes_when_it_can() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 160, 90);
    let data = d.join("data");
    // A new store is 1 MiB; the job's spectral tiles are 4.9 MB. `trap "" XFSZ` makes a write
    // past the limit fail (EFBIG) instead of killing the process; the coordinator inherits it.
    let limit = format!("--fsize={}:unlimited", 3 << 20);
    let prefix = ["sh", "-c", "trap '' XFSZ; exec prlimit \"$@\"", "sh", limit.as_str(), "--"];
    let coordinator = Coordinator::start_under(
        &prefix,
        d,
        &data,
        "127.0.0.1:0",
        &["--no-retinex", "--metrics-listen", "127.0.0.1:0"],
    );
    let metrics = coordinator.metrics.clone().unwrap();
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let (mut client, job) = runtime.block_on(async {
        let mut client = wire::render_client(&coordinator.url).await;
        let bundle = wire::upload(&mut client, Path::new(&scene)).await;
        let spectral = JobSpec {
            render: RenderOptions { spectral: true, ..spec("aosta", 16, 1).render },
            ..spec("aosta", 16, 1)
        };
        let job = wire::submit(&mut client, &bundle, &spectral).await.unwrap();
        (client, job)
    });
    let _worker = Worker::start(d, &coordinator.url, "w", &[]);
    let scrape = || http_get(&metrics, "/metrics").1;
    wait_for("the store to fail", Duration::from_secs(120), || {
        sample(&scrape(), "restauro_store_failing") == 1.0
    });
    let (status, body) = http_get(&metrics, "/readyz");
    assert_eq!(status, 503, "{body}");
    assert!(body.contains("cannot be written"), "{body}");
    let (client_token, _) = token_files(d);
    let args = ["jobs", "--coordinator", &coordinator.url, "--token-file"];
    let jobs = restauro(&[&args[..], &[client_token.to_str().unwrap()]].concat());
    let listed = text(&jobs);
    assert!(
        listed.contains("coordinator: the store") && listed.contains("cannot be written"),
        "{listed}"
    );
    let log = std::fs::read_to_string(d.join("coordinator.log")).unwrap();
    assert!(log.contains("the store cannot be written"), "{log}");
    let running = runtime.block_on(wire::status(&mut client, &job.job_id));
    assert_eq!(running.state, pb::JobState::Running as i32, "{running:?}");

    // Space returns: the same process goes on.
    let pid = coordinator.child.id().to_string();
    let raised = Command::new("prlimit")
        .args(["--pid", &pid, "--fsize=unlimited:unlimited"])
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(raised.success());
    let end = runtime.block_on(wire::wait_end(&mut client, &job.job_id, Duration::from_secs(300)));
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    wait_for("the store to be reported well again", Duration::from_secs(30), || {
        sample(&scrape(), "restauro_store_failing") == 0.0
    });
    assert_eq!(http_get(&metrics, "/readyz").0, 200);
    let local = d.join("local");
    let args = ["render", &scene, "--in-process", "--spp", "1", "--tile", "16", "--spectral"];
    let o = restauro(&[&args[..], &["--out", local.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", text(&o));
    let pixels = |p: &Path| read_exr(p, 1 << 24).unwrap().pixels;
    let cluster = pixels(&data.join("jobs").join(&job.job_id).join("aosta.exr"));
    let reference = pixels(&local.join("aosta.exr"));
    let same = cluster.len() == reference.len()
        && cluster.iter().zip(&reference).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits));
    assert!(same, "the image after the full store differs from the in-process render");
}

/// Defect 19: `restauro submit --wait` survives a restart of its coordinator: it reconnects,
/// resumes the watch and fetches the results.
#[test]
fn submit_wait_survives_a_coordinator_restart() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 96, 54);
    let data = d.join("data");
    let mut coordinator = Coordinator::start(d, &data, "127.0.0.1:0", &["--no-retinex"]);
    let url = coordinator.url.clone();
    let log = d.join("tiles.log");
    let _worker = Worker::start(d, &url, "w", &["--tile-log", log.to_str().unwrap()]);
    let (client_token, _) = token_files(d);
    let out = d.join("out");
    let submit = Command::new(restauro_tests::binary("restauro"))
        .args(["submit", &scene, "--wait", "--spp", "16", "--tile", "16", "--coordinator", &url])
        .arg("--token-file")
        .arg(&client_token)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let tiles = || std::fs::read_to_string(&log).unwrap_or_default().lines().count();
    wait_for("some tiles rendered", Duration::from_secs(120), || tiles() >= 4);
    coordinator.child.kill().unwrap();
    coordinator.child.wait().unwrap();
    let _successor =
        Coordinator::start(d, &data, url.strip_prefix("http://").unwrap(), &["--no-retinex"]);
    let o = submit.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("aosta.exr").exists(), "{}", text(&o));
}
