//! A job's life against races and restarts, on real processes: a cancel that lands while the
//! job is post-processed, watchers that open as a job ends, limits raised on the coordinator
//! only, and results that a killed coordinator's successor takes instead of rendering again.

use restauro_proto as pb;
use restauro_scene::job::{JobSpec, RetinexOptions};
use restauro_scene::plan::{Rect, RenderOptions};
use restauro_scene::scene_file::Integrator;
use restauro_tests::wire::{self, is_final, spec};
use restauro_tests::{Coordinator, Worker, http_get, sample, signal, wait_for};
use std::num::NonZeroU32;
use std::path::Path;
use std::time::Duration;

/// Defect 7: a cancel that lands while the job is post-processed (its Retinex running) stands:
/// the job ends cancelled, stays cancelled, and leaves no result files.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cancel_during_post_processing_is_not_overturned() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 160, 90, &[]).await;
    let data = d.join("data");
    // 512 Retinex paths a pixel: a second or more of post-processing, a wide window for the
    // cancel.
    let slow =
        JobSpec { retinex: RetinexOptions::new(Some(512), None).unwrap(), ..spec("aosta", 64, 1) };
    let job = wire::submit(&mut client, &bundle, &slow).await.unwrap();
    let _worker = Worker::start(d, &coordinator.url, "w", &[]);
    let mut stream =
        client.watch_job(pb::JobRef { job_id: job.job_id.clone() }).await.unwrap().into_inner();
    let post_processing = pb::JobState::PostProcessing as i32;
    loop {
        let status = stream.message().await.unwrap().expect("the job reaches post-processing");
        assert!(!is_final(&status), "ended before post-processing: {status:?}");
        if status.state == post_processing {
            break;
        }
    }
    let cancelled = client.cancel_job(pb::JobRef { job_id: job.job_id.clone() }).await.unwrap();
    assert_eq!(cancelled.into_inner().state, pb::JobState::Cancelled as i32);
    // The Retinex finishes meanwhile; its results must not overturn the cancel.
    let results = data.join("jobs").join(&job.job_id);
    wait_for("the assembly to stop and its files to go", Duration::from_secs(120), || {
        !results.exists()
    });
    let last = wire::wait_end(&mut client, &job.job_id, Duration::from_secs(10)).await;
    assert_eq!(last.state, pb::JobState::Cancelled as i32, "{last:?}");
    assert!(last.results.is_empty());
    let e = client
        .fetch_result(pb::FetchResultRequest {
            job_id: job.job_id.clone(),
            name: "aosta.exr".into(),
        })
        .await
        .unwrap_err();
    assert_eq!(e.code(), tonic::Code::FailedPrecondition, "{e:?}");
}

/// A worker that hangs up while its tile is being committed (killed mid-report: tonic then
/// drops the call) must not leave the tile half-done, neither done nor requeued: the tile is done
/// once the store has it, and the job ends. Before, the call's end was the only way out of
/// "committing", and the cluster test's killed worker once held its job running for an hour.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_report_abandoned_while_its_tile_is_committed_still_completes_the_tile() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Each commit takes 1.5 s (a slow disk): the worker hangs up in the middle of it.
    let slow_disk = ["--fault-commit-delay-ms", "1500"];
    let (coordinator, mut client, bundle) = wire::farm(d, 32, 32, &slow_disk).await;
    let job = wire::submit(&mut client, &bundle, &spec("aosta", 32, 1)).await.unwrap();
    assert_eq!(job.tiles_total, 1);
    let mut work = wire::work_client(&coordinator.url).await;
    let session = wire::register(&mut work, "w").await;
    let lease = wire::lease(&mut work, &session, 1).await.remove(0);
    let rect = Rect::from(lease.rect.unwrap());
    let data = wire::tile_data(&rect, wire::AOSTA_TILES, 1.0);
    let report = wire::report(&mut work, &session, &lease, data);
    let abandoned = tokio::time::timeout(Duration::from_millis(500), report).await;
    assert!(abandoned.is_err(), "answered within the commit's delay: {abandoned:?}");
    drop(work);
    let end = wire::wait_end_logged(&mut client, &job.job_id, Duration::from_secs(60), d).await;
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    assert_eq!(end.tiles_done, 1);
}

/// Defect 8: watchers opened while jobs end all see the end (none waits for a change that
/// already happened).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_watch_opened_as_jobs_end_sees_the_end() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 16, 8, &["--no-retinex"]).await;
    let _worker = Worker::start(d, &coordinator.url, "w", &[]);
    for round in 0..10 {
        let job =
            wire::submit(&mut client, &bundle, &spec(&format!("j{round}"), 16, 1)).await.unwrap();
        let mut watchers = tokio::task::JoinSet::new();
        for _ in 0..20 {
            let (url, id) = (coordinator.url.clone(), job.job_id.clone());
            watchers.spawn(async move {
                let mut client = wire::render_client(&url).await;
                wire::wait_end(&mut client, &id, Duration::from_secs(60)).await
            });
        }
        while let Some(end) = watchers.join_next().await {
            assert_eq!(end.unwrap().state, pb::JobState::Done as i32);
        }
    }
}

/// Defect 11: limits raised on the coordinator reach its workers with the job: a job over the
/// default samples-per-pixel limit, accepted by a coordinator started with a higher one, is
/// rendered by a worker that has no limit flags of its own.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn workers_render_within_the_coordinators_limits() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) =
        wire::farm(d, 4, 2, &["--max-spp", "100000", "--no-retinex"]).await;
    let over_default = JobSpec {
        render: RenderOptions {
            integrator: Some(Integrator::Whitted),
            width: NonZeroU32::new(2),
            height: NonZeroU32::new(1),
            ..spec("many-samples", 8, 70_000).render
        },
        ..spec("many-samples", 8, 70_000)
    };
    let job = wire::submit(&mut client, &bundle, &over_default).await.unwrap();
    let _worker = Worker::start(d, &coordinator.url, "w", &[]);
    let end = wire::wait_end(&mut client, &job.job_id, Duration::from_secs(300)).await;
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    // The same through `restauro render`'s embedded cluster: its coordinator is given the
    // limits the command was given.
    let scene = d.join("aosta").join("aosta.toml");
    let out = d.join("embedded");
    let o = restauro_tests::restauro(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        "70000",
        "--max-spp",
        "100000",
        "--integrator",
        "whitted",
        "--width",
        "2",
        "--height",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", restauro_tests::text(&o));
}

fn tile_lines(log: &Path) -> Vec<u32> {
    std::fs::read_to_string(log)
        .unwrap_or_default()
        .lines()
        .map(|l| l.split(' ').nth(1).unwrap().parse().unwrap())
        .collect()
}

/// Defect 21: a tile rendered under a coordinator that is then killed before it acknowledged
/// the result is taken by the coordinator restarted on the same store, not rendered again:
/// with one worker, every tile is rendered exactly once across the restart.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn results_of_a_killed_coordinators_leases_are_taken_by_its_successor() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = ["--no-retinex", "--heartbeat-timeout-s", "60"];
    let (mut coordinator, mut client, bundle) = wire::farm(d, 64, 32, &args).await;
    let data = d.join("data");
    let url = coordinator.url.clone();
    let job = wire::submit(&mut client, &bundle, &spec("aosta", 16, 64)).await.unwrap();
    let log = d.join("tiles.log");
    let (_worker, metrics) =
        Worker::start_with_metrics(d, &url, "w", &["--tile-log", log.to_str().unwrap()]);
    let scrape = |name: &str| sample(&http_get(&metrics, "/metrics").1, name);
    wait_for("three tiles rendered", Duration::from_secs(120), || {
        scrape("restauro_worker_tiles_rendered_total") >= 3.0
    });
    // Frozen, the coordinator acknowledges nothing: the result in flight, or the next one
    // rendered, is left with the worker when the coordinator is killed.
    signal(&coordinator.child, "-STOP");
    let rendered = scrape("restauro_worker_tiles_rendered_total");
    wait_for("a result the coordinator has not acknowledged", Duration::from_secs(120), || {
        scrape("restauro_worker_tiles_rendered_total")
            > scrape("restauro_worker_tiles_delivered_total")
    });
    coordinator.child.kill().unwrap();
    coordinator.child.wait().unwrap();
    let stored = {
        let store = restauro_farm::store::Store::open(&data.join("store.redb")).unwrap();
        store.finished_tiles(&job.job_id).unwrap()
    };
    let addr = url.strip_prefix("http://").unwrap();
    let _successor = Coordinator::start(d, &data, addr, &args);
    let mut client = wire::render_client(&url).await;
    let end = wire::wait_end_logged(&mut client, &job.job_id, Duration::from_secs(120), d).await;
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    let tiles = tile_lines(&log);
    let mut sorted = tiles.clone();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        (0..end.tiles_total).collect::<Vec<_>>(),
        "every tile rendered exactly once; {} were rendered before the kill, {} stored",
        rendered,
        stored.len()
    );
}
