//! A real coordinator process against hand-written hostile callers: workers that report tiles
//! they were not given, forge leases and sessions, send NaN; clients that ask for jobs that would
//! exhaust the machine, upload wrong bytes, submit fields the job cannot use, or race each other.
//! Each test is one defect of the "trust the farm" issue, named in its doc comment.

use restauro_image::image_files::read_exr;
use restauro_proto as pb;
use restauro_scene::job::JobSpec;
use restauro_scene::plan::{Rect, RenderOptions};
use restauro_tests::wire::{self, is_final, spec};
use restauro_tests::{Coordinator, Worker, restauro, text};
use std::num::NonZeroU32;
use std::path::Path;
use std::time::Duration;
use tonic::Code;

/// The in-process render of the test's scene with `--spp spp --tile tile`: the reference every cluster
/// image must equal bit for bit.
fn reference(dir: &Path, spp: u32, tile: u32) -> Vec<[f32; 3]> {
    let scene = dir.join("aosta").join("aosta.toml");
    let scene = scene.to_str().unwrap();
    let out = dir.join("reference");
    let (spp, tile) = (spp.to_string(), tile.to_string());
    let args = ["render", scene, "--in-process", "--spp", &spp, "--tile", &tile];
    let o = restauro(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", text(&o));
    read_exr(&out.join("aosta.exr"), 1 << 24).unwrap().pixels
}

fn result(data: &Path, job: &str) -> Vec<[f32; 3]> {
    read_exr(&data.join("jobs").join(job).join("aosta.exr"), 1 << 24).unwrap().pixels
}

fn identical(a: &[[f32; 3]], b: &[[f32; 3]]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits))
}

fn rect(lease: &pb::Lease) -> Rect {
    lease.rect.unwrap().into()
}

/// Defects 1 and 5: a worker token holder cannot report another worker's lease, forge a lease
/// for a tile it was never given, or act with another worker's id; the final image is the one
/// the honest worker rendered, bit for bit.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_cannot_write_a_tile_it_was_not_leased_nor_act_as_another() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 64, 32, &[]).await;
    let data = d.join("data");
    let job = wire::submit(&mut client, &bundle, &spec("aosta", 16, 1)).await.unwrap();

    let mut holder = wire::work_client(&coordinator.url).await;
    let holder_session = wire::register(&mut holder, "holder").await;
    let lease = wire::lease(&mut holder, &holder_session, 1).await.remove(0);
    let mut thief = wire::work_client(&coordinator.url).await;
    let thief_session = wire::register(&mut thief, "thief").await;
    let bright = wire::tile_data(&rect(&lease), wire::AOSTA_TILES, 1e6);

    // The holder's lease, reported with the thief's own session.
    let e = wire::report(&mut thief, &thief_session, &lease, bright.clone()).await.unwrap_err();
    assert_eq!(e.code(), Code::PermissionDenied, "{e:?}");
    assert!(e.message().contains("granted to another worker"), "{}", e.message());
    // A lease of tile 1 made up from the holder's (its ticket does not fit).
    let forged = pb::Lease { tile: 1, holder: thief_session.worker_id, ..lease.clone() };
    let e = wire::report(&mut thief, &thief_session, &forged, bright.clone()).await.unwrap_err();
    assert_eq!(e.code(), Code::PermissionDenied, "{e:?}");
    assert!(e.message().contains("not one this coordinator gave out"), "{}", e.message());
    // The holder's id with a key of the thief's making: nothing happens.
    let posing = pb::WorkerSession { worker_id: holder_session.worker_id, key: vec![7; 32] };
    let reply = wire::report(&mut thief, &posing, &lease, bright).await.unwrap();
    assert!(!reply.known && !reply.accepted, "{reply:?}");
    let leave = pb::ReturnRequest { session: Some(posing), leases: Vec::new(), leaving: true };
    assert!(!thief.return_leases(leave).await.unwrap().into_inner().known);
    let beat = pb::HeartbeatRequest { session: Some(holder_session.clone()) };
    assert!(holder.heartbeat(beat).await.unwrap().into_inner().known, "the holder is still known");

    // The holder hands its lease back; a real worker renders the job.
    let back =
        pb::ReturnRequest { session: Some(holder_session), leases: vec![lease], leaving: true };
    assert!(holder.return_leases(back).await.unwrap().into_inner().accepted);
    let _worker = Worker::start(d, &coordinator.url, "honest", &[]);
    let end = wire::wait_end(&mut client, &job.job_id, Duration::from_secs(120)).await;
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    assert!(identical(&result(&data, &job.job_id), &reference(d, 1, 16)));
}

/// Issue 35, finding 4: after a coordinator restart, a lease of the earlier run may be delivered
/// by the worker it was granted to, registered again with its identity, and by no other. Before,
/// any session holding the ticket could deliver it: worker R delivered worker P's lease and was
/// accepted, and P's own report of the tile was dropped.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_a_restart_only_its_own_worker_delivers_an_earlier_lease() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 64, 32, &[]).await;
    let data = d.join("data");
    wire::submit(&mut client, &bundle, &spec("aosta", 16, 1)).await.unwrap();
    let (p_identity, r_identity) = ([1u8; 32], [2u8; 32]);
    let mut p = wire::work_client(&coordinator.url).await;
    let p_session = wire::register_as(&mut p, "p", p_identity).await;
    let lease = wire::lease(&mut p, &p_session, 1).await.remove(0);
    let pixels = wire::tile_data(&rect(&lease), wire::AOSTA_TILES, 1.0);
    // The coordinator restarts on its store; both workers register again, each as itself.
    drop(client);
    drop(coordinator);
    let coordinator = Coordinator::start(d, &data, "127.0.0.1:0", &[]);
    let mut r = wire::work_client(&coordinator.url).await;
    let r_session = wire::register_as(&mut r, "r", r_identity).await;
    let e = wire::report(&mut r, &r_session, &lease, pixels.clone()).await.unwrap_err();
    assert_eq!(e.code(), Code::PermissionDenied, "{e:?}");
    assert!(e.message().contains("bound to the identity"), "{}", e.message());
    let mut p = wire::work_client(&coordinator.url).await;
    let p_again = wire::register_as(&mut p, "p", p_identity).await;
    let reply = wire::report(&mut p, &p_again, &lease, pixels).await.unwrap();
    assert!(reply.known && reply.accepted, "its own worker delivers it: {reply:?}");
}

/// Defect 3: NaN, ∞ and negative radiance are refused at the edge and count as the sending
/// worker's failure of the tile; the image stays finite and the honest render's.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn non_finite_or_negative_pixels_are_refused_and_count_against_the_worker() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 64, 32, &[]).await;
    let data = d.join("data");
    let job = wire::submit(&mut client, &bundle, &spec("aosta", 16, 1)).await.unwrap();
    let mut work = wire::work_client(&coordinator.url).await;
    // Two bad tiles from one worker (which then gets no more of the job), one from another.
    for (name, values) in [("broken", &[f32::NAN, f32::INFINITY][..]), ("negative", &[-1.0][..])] {
        let session = wire::register(&mut work, name).await;
        for &bad in values {
            let lease = wire::lease(&mut work, &session, 1).await.remove(0);
            let data = wire::tile_data(&rect(&lease), wire::AOSTA_TILES, bad);
            let e = wire::report(&mut work, &session, &lease, data).await.unwrap_err();
            assert_eq!(e.code(), Code::InvalidArgument, "{e:?}");
            assert!(e.message().contains(&format!("XYZ {bad}")), "{}", e.message());
        }
    }
    let workers = client.list_workers(pb::ListWorkersRequest {}).await.unwrap().into_inner();
    let failed = |name: &str| workers.workers.iter().find(|w| w.name == name).unwrap().tiles_failed;
    assert_eq!((failed("broken"), failed("negative")), (2, 1));
    let _worker = Worker::start(d, &coordinator.url, "honest", &[]);
    let end = wire::wait_end(&mut client, &job.job_id, Duration::from_secs(120)).await;
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    let image = result(&data, &job.job_id);
    assert!(image.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    assert!(identical(&image, &reference(d, 1, 16)));
}

/// Finding 3 of "trust under load": finite radiance beyond any scene (3.4·10³⁸, which once gave
/// +∞ in 64 pixels of the result's RGB) is refused naming the bound; the same tile at the bound
/// itself (10³⁰ in every XYZ and white value) is accepted, and every file of the result — the
/// EXR with its RGB, the seen image's EXR, both PNGs — is written without an ∞ or a NaN.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_tile_at_the_bound_gives_finite_result_files() {
    use restauro_image::radiometric_bound::MAX_RADIOMETRIC;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 64, 32, &[]).await;
    let job = wire::submit(&mut client, &bundle, &spec("aosta", 16, 1)).await.unwrap();
    let mut work = wire::work_client(&coordinator.url).await;
    let session = wire::register(&mut work, "beyond").await;
    let lease = wire::lease(&mut work, &session, 1).await.remove(0);
    let data = wire::tile_data(&rect(&lease), wire::AOSTA_TILES, 3.4e38);
    let e = wire::report(&mut work, &session, &lease, data).await.unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument, "{e:?}");
    let bound =
        "XYZ 340000000000000000000000000000000000000, which must be finite, ≥ 0 and at most 1e30";
    assert!(e.message().contains(bound), "{}", e.message());
    let session = wire::register(&mut work, "bright").await;
    let lease = wire::lease(&mut work, &session, 1).await.remove(0);
    let data = wire::tile_data(&rect(&lease), wire::AOSTA_TILES, MAX_RADIOMETRIC);
    let reply = wire::report(&mut work, &session, &lease, data).await.unwrap();
    assert!(reply.accepted, "{reply:?}");
    let _worker = Worker::start(d, &coordinator.url, "honest", &[]);
    let end = wire::wait_end(&mut client, &job.job_id, Duration::from_secs(120)).await;
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    let folder = d.join("data").join("jobs").join(&job.job_id);
    for name in ["aosta.exr", "aosta-retinex.exr"] {
        let image = exr::prelude::read_all_flat_layers_from_file(folder.join(name)).unwrap();
        for layer in image.layer_data {
            for c in layer.channel_data.list {
                let bad = c.sample_data.values_as_f32().position(|v| !v.is_finite());
                assert!(bad.is_none(), "{name}: channel {} at {bad:?}", c.name);
            }
        }
    }
    let bright =
        result(&d.join("data"), &job.job_id).iter().filter(|p| p[1] == MAX_RADIOMETRIC).count();
    let r = rect(&lease);
    assert_eq!(bright, (r.width * r.height) as usize, "the tile at the bound is in the image");
    for name in ["aosta.png", "aosta-retinex.png"] {
        assert!(std::fs::metadata(folder.join(name)).unwrap().len() > 0, "{name}");
    }
}

/// Defect 2: a job that would need gigabytes of tiles is refused naming the limit, and the
/// coordinator stays up and small.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn jobs_of_too_many_tiles_are_refused_without_harm() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) =
        wire::farm(d, 32, 16, &["--max-pixels", "300000000"]).await;
    let huge = |size: u32, tile: u32| JobSpec {
        render: RenderOptions {
            width: NonZeroU32::new(size),
            height: NonZeroU32::new(size),
            tile: NonZeroU32::new(tile),
            ..RenderOptions::default()
        },
        ..spec("huge", tile, 1)
    };
    for (size, tile, code, flag) in [
        (16_384, 1, Code::InvalidArgument, "--min-tile"),
        (16_384, 8, Code::ResourceExhausted, "--max-tiles"),
        (4096, 8, Code::ResourceExhausted, "--max-tiles"),
    ] {
        let e = wire::submit(&mut client, &bundle, &huge(size, tile)).await.unwrap_err();
        assert_eq!(e.code(), code, "{size}² in tiles of {tile}: {e:?}");
        assert!(e.message().contains(flag), "{}", e.message());
    }
    // Still serving, no job taken, and its memory never grew by the gigabytes those needed.
    let jobs = client.list_jobs(pb::ListJobsRequest {}).await.unwrap().into_inner();
    assert!(jobs.jobs.is_empty());
    let (peak_kib, _) = wire::memory_kib(coordinator.child.id());
    assert!(peak_kib < 200 << 10, "the coordinator's peak resident set: {peak_kib} KiB");
}

/// Defect 4: an upload streams to disk while it is hashed: 256 MiB of wrong bytes are refused
/// without the coordinator holding them, and leave nothing behind; uploads over the file limit
/// or the shared upload budget are refused naming the flag.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn uploads_are_streamed_bounded_and_checked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = d.join("data");
    let coordinator = Coordinator::start(d, &data, "127.0.0.1:0", &["--max-upload-mb", "300"]);
    let mut client = wire::render_client(&coordinator.url).await;
    let (before_kib, _) = wire::memory_kib(coordinator.child.id());
    // 64 hex digits that are not the hash of the zeros sent.
    let named = format!("blake3:{}.bin", "ab".repeat(32));
    let upload = |name: String, total: u64, chunks: usize| {
        tokio_stream::iter((0..chunks).map(move |i| pb::Chunk {
            name: if i == 0 { name.clone() } else { String::new() },
            total_bytes: total,
            data: vec![0u8; 1 << 20],
        }))
    };
    let e = client.upload_asset(upload(named.clone(), 256 << 20, 256)).await.unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument, "{e:?}");
    assert!(e.message().contains("do not have this hash"), "{}", e.message());
    let (peak_kib, _) = wire::memory_kib(coordinator.child.id());
    assert!(
        peak_kib < before_kib + (64 << 10),
        "the peak resident set grew from {before_kib} to {peak_kib} KiB for a 256 MiB upload"
    );
    let left: Vec<_> = std::fs::read_dir(data.join("assets")).unwrap().collect();
    assert!(left.is_empty(), "nothing kept of a refused upload: {left:?}");
    let e = client.upload_asset(upload(named.clone(), 3 << 30, 1)).await.unwrap_err();
    assert_eq!(e.code(), Code::ResourceExhausted, "{e:?}");
    assert!(e.message().contains("--max-file-mb"), "{}", e.message());
    let e = client.upload_asset(upload(named.clone(), 400 << 20, 1)).await.unwrap_err();
    assert_eq!(e.code(), Code::ResourceExhausted, "{e:?}");
    assert!(e.message().contains("--max-upload-mb"), "{}", e.message());
    // More bytes than announced.
    let e = client.upload_asset(upload(named, 1 << 20, 2)).await.unwrap_err();
    assert!(e.message().contains("more than the 1048576 bytes announced"), "{}", e.message());
}

/// Defect 6: every field of a submission is checked at the edge, once: names with terminal
/// escapes or of 100 000 characters, 4·10⁹ Retinex paths, an unknown integrator, a NaN
/// exposure are refused naming the field, and no job is taken.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn submissions_with_unusable_fields_are_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_coordinator, mut client, bundle) = wire::farm(d, 32, 16, &[]).await;
    let good = pb::convert::submit_request(bundle.canonical_json(), &spec("ok", 16, 1));
    let mut cases: Vec<(pb::SubmitJobRequest, &str)> = Vec::new();
    let mut r = good.clone();
    r.name = "evil\u{1b}[2J\nname".into();
    cases.push((r, "name: character"));
    let mut r = good.clone();
    r.name = "x".repeat(100_000);
    cases.push((r, "name: 100000 characters"));
    let mut r = good.clone();
    r.retinex = Some(pb::RetinexOptions { paths: Some(4_000_000_000), seed: None });
    cases.push((r, "retinex.paths"));
    let mut r = good.clone();
    r.render.as_mut().unwrap().integrator = 7;
    cases.push((r, "render.integrator"));
    let mut r = good.clone();
    r.exposure = Some(pb::Exposure { mode: Some(pb::exposure::Mode::AutomaticKey(f64::NAN)) });
    cases.push((r, "exposure"));
    let mut r = good.clone();
    r.manifest_json = "{not json".into();
    cases.push((r, "manifest_json"));
    for (request, field) in cases {
        let e = client.submit_job(request).await.unwrap_err();
        assert_eq!(e.code(), Code::InvalidArgument, "{field}: {e:?}");
        assert!(e.message().contains(field), "{field}: {}", e.message());
    }
    let jobs = client.list_jobs(pb::ListJobsRequest {}).await.unwrap().into_inner();
    assert!(jobs.jobs.is_empty(), "{:?}", jobs.jobs);
    assert!(client.submit_job(good).await.is_ok());
}

/// Defect 9: a retryable failure (the transport's) hands the tile back and counts against
/// nobody; the same failures reported as the tile's fail the job after three workers.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn retryable_failures_count_against_nobody() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 32, 16, &[]).await;
    let job = wire::submit(&mut client, &bundle, &spec("aosta", 16, 1)).await.unwrap();
    let mut work = wire::work_client(&coordinator.url).await;
    for retryable in [true, false] {
        for i in 0..3 {
            let session = wire::register(&mut work, &format!("w{i}-{retryable}")).await;
            let lease = wire::lease(&mut work, &session, 1).await.remove(0);
            assert_eq!(lease.tile, 0, "the requeued tile goes first");
            let reply = work
                .fail_tile(pb::FailRequest {
                    session: Some(session),
                    lease: Some(lease),
                    reason: "coordinator unreachable while fetching an asset".into(),
                    retryable,
                })
                .await
                .unwrap()
                .into_inner();
            assert!(reply.known && reply.accepted, "{reply:?}");
        }
        let status = wire::status(&mut client, &job.job_id).await;
        if retryable {
            assert_eq!(status.state, pb::JobState::Running as i32, "{status:?}");
            assert_eq!(status.tiles_requeued, 3);
        } else {
            assert_eq!(status.state, pb::JobState::Failed as i32, "{status:?}");
            assert!(status.error.contains("tile 0 failed on 3 workers"), "{}", status.error);
        }
    }
}

/// Defect 10: a late report of an expired lease, after the job is done and its tiles dropped,
/// is stale and stores nothing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_late_report_after_the_job_ended_stores_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = ["--lease-timeout-s", "1", "--heartbeat-timeout-s", "60", "--no-retinex"];
    let (mut coordinator, mut client, bundle) = wire::farm(d, 32, 16, &args).await;
    let data = d.join("data");
    let job = wire::submit(&mut client, &bundle, &spec("aosta", 16, 1)).await.unwrap();
    let mut late = wire::work_client(&coordinator.url).await;
    let session = wire::register(&mut late, "late").await;
    let lease = wire::lease(&mut late, &session, 1).await.remove(0);
    let worker = Worker::start(d, &coordinator.url, "honest", &[]);
    let end = wire::wait_end(&mut client, &job.job_id, Duration::from_secs(120)).await;
    assert_eq!(end.state, pb::JobState::Done as i32, "{end:?}");
    let reply = wire::report(
        &mut late,
        &session,
        &lease,
        wire::tile_data(&rect(&lease), wire::AOSTA_TILES, 5.0),
    )
    .await
    .unwrap();
    assert!(reply.known && !reply.accepted, "{reply:?}");
    drop(worker);
    // Stopped as an operator stops it, so that the removal queued when the job ended is
    // committed (a killed coordinator drops the tiles when it next starts).
    restauro_tests::signal(&coordinator.child, "-TERM");
    let status = coordinator.child.wait().unwrap();
    assert!(status.success(), "the coordinator exited with {status}");
    let store = restauro_farm::store::Store::open(&data.join("store.redb")).unwrap();
    assert!(store.finished_tiles(&job.job_id).unwrap().is_empty(), "tiles of a done job");
}

/// Defect 17: `--max-jobs` holds under concurrent submissions.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn max_jobs_holds_under_concurrent_submissions() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (coordinator, mut client, bundle) = wire::farm(d, 32, 16, &["--max-jobs", "3"]).await;
    let mut tasks = tokio::task::JoinSet::new();
    for i in 0..24 {
        let (url, bundle) = (coordinator.url.clone(), bundle.clone());
        tasks.spawn(async move {
            let mut client = wire::render_client(&url).await;
            wire::submit(&mut client, &bundle, &spec(&format!("j{i}"), 16, 1)).await
        });
    }
    let (mut accepted, mut refused) = (0, 0);
    while let Some(r) = tasks.join_next().await {
        match r.unwrap() {
            Ok(_) => accepted += 1,
            Err(e) => {
                assert_eq!(e.code(), Code::ResourceExhausted, "{e:?}");
                assert!(e.message().contains("--max-jobs"), "{}", e.message());
                refused += 1;
            }
        }
    }
    assert_eq!((accepted, refused), (3, 21));
    let jobs = client.list_jobs(pb::ListJobsRequest {}).await.unwrap().into_inner();
    assert_eq!(jobs.jobs.iter().filter(|j| !is_final(j)).count(), 3);
}

/// Defect 20: temporary result files that a killed coordinator left are removed at start, and
/// nothing else is.
#[test]
fn a_starting_coordinator_removes_unfinished_result_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = d.join("data");
    let job = data.join("jobs").join("0b5e8f0e-0000-4000-8000-000000000000");
    std::fs::create_dir_all(&job).unwrap();
    std::fs::write(job.join(".aosta.exr.4242.tmp"), b"half").unwrap();
    std::fs::write(job.join(".aosta-retinex.png.77.tmp"), b"half").unwrap();
    std::fs::write(job.join("aosta.exr"), b"whole").unwrap();
    let _coordinator = Coordinator::start(d, &data, "127.0.0.1:0", &[]);
    let mut left: Vec<String> = std::fs::read_dir(&job)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["aosta.exr"]);
}
