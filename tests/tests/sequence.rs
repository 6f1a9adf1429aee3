//! Sequences on the cluster, as real processes on loopback: each frame is the same scene
//! rendered alone, bit for bit; frames are ready in order while the job runs and can be
//! fetched then; a coordinator killed mid-sequence resumes without rendering a finished tile
//! again, and with the eye's state it had reached; and what cannot be a sequence is refused with
//! the fix.

use restauro_proto as pb;
use restauro_scene::sequence::Frame;
use restauro_tests::{Coordinator, Worker, aosta_scene, client, restauro, text, wire};
use std::collections::HashMap;
use std::path::Path;

/// The scene at `scene` with its sun's date-time set to `datetime`, written beside it as `name`.
fn at_time(scene: &str, datetime: &str, name: &str) -> String {
    let text = std::fs::read_to_string(scene).unwrap();
    let own = "datetime = \"2026-07-15T15:30:00+02:00\"";
    assert!(text.contains(own), "the generated scene's sun has moved: update this test");
    let path = Path::new(scene).with_file_name(name);
    std::fs::write(&path, text.replace(own, &format!("datetime = \"{datetime}\""))).unwrap();
    path.to_str().unwrap().to_owned()
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn each_frame_of_a_day_is_the_same_scene_rendered_alone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 64, 36);
    let out = d.join("day");
    let o = restauro(&[
        "sequence",
        &scene,
        "--sun-from",
        "05:00",
        "--to",
        "21:00",
        "--every",
        "4h",
        "--spp",
        "2",
        "--tile",
        "16",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let said = text(&o);
    assert!(said.contains("as 5 frames") && said.contains("frame 0004: 21:00"), "{said}");
    assert!(said.contains("frames an hour"), "{said}");
    // At 05:00 the sun has not risen at Aosta in July (it rises near 05:50 CEST): the sky
    // alone lights that frame. At 13:00 it is high.
    for (frame, datetime) in [(0, "2026-07-15T05:00:00+02:00"), (2, "2026-07-15T13:00:00+02:00")] {
        let alone = at_time(&scene, datetime, &format!("alone-{frame}.toml"));
        let alone_out = d.join(format!("alone-{frame}"));
        let o = restauro(&[
            "render",
            &alone,
            "--in-process",
            "--spp",
            "2",
            "--tile",
            "16",
            "--out",
            alone_out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o));
        for suffix in [".exr", ".png", "-retinex.exr", "-retinex.png"] {
            let a = bytes(&alone_out.join(format!("alone-{frame}{suffix}")));
            let b = bytes(&out.join(format!("aosta-{frame:04}{suffix}")));
            assert!(a == b, "frame {frame}{suffix} differs from the scene at {datetime} alone");
        }
    }
    let (dawn, noon) = (bytes(&out.join("aosta-0000.exr")), bytes(&out.join("aosta-0002.exr")));
    assert_ne!(dawn, noon, "the frames are of different hours");
    the_sheet_and_the_video_hold_the_seen_frames(&out, 5);
}

/// The contact sheet is a PNG wider than one frame; the video is an APNG of every seen frame,
/// at 2 frames a second, whose first frame is the first seen PNG.
fn the_sheet_and_the_video_hold_the_seen_frames(out: &Path, frames: u32) {
    let decoded = |path: &Path| {
        let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut reader = png::Decoder::new(std::io::BufReader::new(file)).read_info().unwrap();
        let mut data = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut data).unwrap();
        data.truncate(frame.buffer_size());
        let info = reader.info();
        let control = info.animation_control.map(|a| a.num_frames);
        let delay = info.frame_control.map(|f| (f.delay_num, f.delay_den));
        (frame.width, control, delay, data)
    };
    let (sheet_width, ..) = decoded(&out.join("aosta-sheet.png"));
    let (frame_width, _, _, first) = decoded(&out.join("aosta-0000-retinex.png"));
    assert!(sheet_width > frame_width);
    let (width, control, delay, video_first) = decoded(&out.join("aosta.apng"));
    assert_eq!((width, control), (frame_width, Some(frames)));
    assert_eq!(delay, Some((100, 200)));
    assert!(video_first == first, "the video starts with the first seen frame");
}

#[test]
fn what_cannot_be_a_sequence_is_refused_with_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 32, 18);
    let refused = |extra: &[&str]| {
        let mut args = vec!["sequence", scene.as_str(), "--out", "never"];
        args.extend(extra);
        let o = restauro(&args);
        assert!(!o.status.success(), "{extra:?} was accepted");
        text(&o)
    };
    let e = refused(&["--sun-from", "06:00", "--to", "21:00", "--every", "0m"]);
    assert!(e.contains("a step of zero") && e.contains("15m"), "{e}");
    let e = refused(&["--sun-from", "22:00", "--to", "23:30", "--every", "30m"]);
    assert!(e.contains("the sun never rises") && e.contains("sunrise and sunset"), "{e}");
    let e = refused(&["--path", "front", "--fps", "25"]);
    assert!(e.contains("at least two saved views"), "{e}");
    let e = refused(&[]);
    assert!(e.contains("say which sequence") && e.contains("--sun-from"), "{e}");
    let e = refused(&["--sun-from", "06:00", "--to", "21:00", "--every", "1s"]);
    assert!(e.contains("--max-frames"), "{e}");
    let e = refused(&["--sun-from", "6 am", "--to", "21:00", "--every", "1h"]);
    assert!(e.contains("HH:MM"), "{e}");
    let e = refused(&["--sun-from", "06:00", "--to", "21:00", "--every", "1h", "--in-process"]);
    assert!(e.contains("a sequence runs on a cluster (leave it out)"), "{e}");
    let e =
        refused(&["--sun-from", "06:00", "--to", "21:00", "--every", "1h", "--variants", "a,b"]);
    assert!(e.contains("one kind of sequence") && e.contains("not several"), "{e}");
    let e = refused(&["--sun-from", "06:00", "--to", "21:00", "--every", "1h", "--video-fps", "0"]);
    assert!(e.contains("between 0 and 240"), "{e}");
    let clear = Path::new(&scene).with_file_name("aosta-clear.toml");
    let o = restauro(&[
        "illuminance",
        clear.to_str().unwrap(),
        "--in-process",
        "--sun-from",
        "12:00",
        "--to",
        "13:00",
        "--every",
        "1h",
        "--out",
        "never",
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("makes the grids at one time; a sequence runs on a cluster"),
        "{}",
        text(&o)
    );
    assert!(!Path::new("never").exists());
}

/// A walk through two saved views at 1.4 m/s and 5 frames a second: the frames step along the
/// path, and the first is the first view's.
#[test]
fn a_walk_through_saved_views_renders_its_frames() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 32, 18);
    let mut text_of = std::fs::read_to_string(&scene).unwrap();
    text_of.push_str(
        "\n[[views]]\nname = \"west\"\nposition = [-6.0, -30.0, 1.7]\ntarget = [0.0, 0.0, 9.0]\nvertical_fov_deg = 50.0\n\
         \n[[views]]\nname = \"east\"\nposition = [-3.0, -30.0, 1.7]\ntarget = [0.0, 0.0, 9.0]\nvertical_fov_deg = 50.0\n",
    );
    std::fs::write(&scene, text_of).unwrap();
    let out = d.join("walk");
    let o = restauro(&[
        "sequence",
        &scene,
        "--path",
        "west,east",
        "--fps",
        "5",
        "--spp",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    // 3 m at 1.4 m/s is 2.14 s: frames at 0, 0.2, …, 2.0 s.
    let said = text(&o);
    assert!(said.contains("as 11 frames") && said.contains("frame 0010: 2.00 s, 2.8 m"), "{said}");
    assert!(out.join("aosta-0010.png").is_file());
    // The walker's eye: frames 0.2 s apart, each seen by the eye the one before left.
    let lagging = eye_follows_the_frames(&out, "aosta", 11, 0.2);
    assert!(lagging >= 5, "only {lagging} of 10 frames were seen by an eye behind their light");
    // The first frame stands at the first view: the scene's own camera, which is there.
    let alone = d.join("alone");
    let o = restauro(&[
        "render",
        &scene,
        "--in-process",
        "--spp",
        "1",
        "--out",
        alone.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(bytes(&alone.join("aosta.exr")) == bytes(&out.join("aosta-0000.exr")));
}

/// Frames every hour of a day, as a time-lapse seen by an eye that lives them 2 s apart.
fn morning() -> Vec<Frame> {
    (7..=14)
        .map(|h| Frame {
            label: format!("{h:02}:00"),
            datetime: Some(format!("2026-07-15T{h:02}:00:00+02:00")),
            camera: None,
            variant: None,
            elapsed_s: Some(f64::from(h - 7) * TIME_LAPSE_STEP_S),
        })
        .collect()
}

const TIME_LAPSE_STEP_S: f64 = 2.0;

/// The words `key=value` of a seen frame's settings (its EXR's `restauroRetinex` attribute).
fn seen_words(path: &Path) -> HashMap<String, String> {
    let meta = exr::meta::MetaData::read_from_file(path, false).unwrap();
    let key = exr::meta::attribute::Text::from("restauroRetinex");
    let Some(exr::meta::attribute::AttributeValue::Text(text)) =
        meta.headers[0].own_attributes.other.get(&key)
    else {
        panic!("{}: no restauroRetinex attribute", path.display());
    };
    text.to_string()
        .split(' ')
        .filter_map(|w| w.split_once('=').map(|(k, v)| (k.to_owned(), v.to_owned())))
        .collect()
}

fn numbers(words: &HashMap<String, String>, key: &str) -> Vec<f64> {
    words[key].split(',').map(|v| v.parse().unwrap()).collect()
}

/// `light + (before − light) · share`, or `light` once within a millionth of it.
fn towards(light: f64, before: f64, share: f64) -> f64 {
    let moved = light + (before - light) * share;
    if (moved - light).abs() <= 1e-6 * light { light } else { moved }
}

/// The seen frames `<stem>-0000-retinex.exr` … of a sequence whose frames are `step_s` apart
/// are seen by one eye: frame 0's is adapted to its light; each later frame's state is its
/// light's, moved towards the state before by the share of the step still to go — for the
/// level e^(−step / 80 ms) (Pattanaik et al. 2000's cones), for the slow colour state
/// 2^(−step / 20 s) (Rinner & Gegenfurtner 2000's half-life). Returns how many frames' eyes
/// lagged their light.
fn eye_follows_the_frames(out: &Path, stem: &str, frames: u32, step_s: f64) -> usize {
    let mut before: Option<(f64, Vec<f64>)> = None;
    let mut lagging = 0;
    for k in 0..frames {
        let words = seen_words(&out.join(format!("{stem}-{k:04}-retinex.exr")));
        let (light, eye) = (numbers(&words, "light-cones"), numbers(&words, "eye-slow-cones"));
        let light_level = numbers(&words, "light-level-cd-m2")[0];
        let eye_level = numbers(&words, "eye-level-cd-m2")[0];
        let (level, cones) = match &before {
            None => (light_level, light.clone()),
            Some((l, c)) => (
                towards(light_level, *l, (-step_s / 0.080f64).exp()),
                (0..3).map(|i| towards(light[i], c[i], 0.5f64.powf(step_s / 20.0))).collect(),
            ),
        };
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        assert!(close(eye_level, level), "frame {k}: the eye's level {eye_level}, not {level}");
        for i in 0..3 {
            assert!(
                close(eye[i], cones[i]),
                "frame {k}, cone {i}: the eye is at {}, the time course puts it at {}",
                eye[i],
                cones[i]
            );
        }
        lagging += usize::from(eye != light);
        before = Some((eye_level, eye));
    }
    lagging
}

fn lines(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path).unwrap_or_default().lines().map(str::to_owned).collect()
}

/// The job's tiles in a worker's log (`job tile attempt` a line).
fn tiles_in(lines: &[String], id: &str) -> Vec<u32> {
    lines
        .iter()
        .filter(|l| l.starts_with(id))
        .map(|l| l.split(' ').nth(1).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn frames_are_ready_in_order_and_a_restarted_coordinator_renders_no_finished_tile_again() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let (mut coordinator, mut grpc, bundle) =
        runtime.block_on(wire::farm(d, 96, 54, &["--heartbeat-timeout-s", "2"]));
    let url = coordinator.url.clone();
    let logs: Vec<_> = (1..=2).map(|i| d.join(format!("tiles-{i}.log"))).collect();
    let _workers: Vec<Worker> = logs
        .iter()
        .enumerate()
        .map(|(i, log)| {
            Worker::start(d, &url, &format!("w{i}"), &["--tile-log", log.to_str().unwrap()])
        })
        .collect();
    let spec = restauro_scene::job::JobSpec { frames: morning(), ..wire::spec("aosta", 16, 24) };
    let status = runtime.block_on(wire::submit(&mut grpc, &bundle, &spec)).unwrap();
    let id = status.job_id.clone();
    assert_eq!((status.frames_total, status.tiles_total), (8, 8 * 24));
    // Follow the job until a frame is ready, and fetch it while the others render.
    let seen = runtime.block_on(async {
        let mut stream =
            grpc.watch_job(pb::pb::JobRef { job_id: id.clone() }).await.unwrap().into_inner();
        let mut ready = 0;
        while let Some(s) = stream.message().await.unwrap() {
            assert!(s.frames_ready >= ready, "frames became ready out of order");
            ready = s.frames_ready;
            for f in &s.frames {
                assert!(f.index >= ready && f.tiles_done <= f.tiles_total && f.tiles_total == 24);
            }
            if ready >= 1 {
                return s;
            }
        }
        panic!("the watch ended before a frame was ready");
    });
    assert!(seen.frames_ready < 8, "the whole sequence ran before the restart: slow it down");
    let early = runtime.block_on(async {
        let request =
            pb::pb::FetchResultRequest { job_id: id.clone(), name: "aosta-0000.png".into() };
        let mut stream = grpc.fetch_result(request).await.unwrap().into_inner();
        let mut bytes = Vec::new();
        while let Some(chunk) = stream.message().await.unwrap() {
            bytes.extend(chunk.data);
        }
        bytes
    });
    assert!(early.starts_with(b"\x89PNG"), "a ready frame is fetched while the job runs");
    coordinator.child.kill().unwrap();
    coordinator.child.wait().unwrap();
    let offsets: Vec<usize> = logs.iter().map(|l| lines(l).len()).collect();
    let finished: Vec<u32> = {
        let store = restauro_farm::store::Store::open(&d.join("data/store.redb")).unwrap();
        let (_, record) = store.jobs().unwrap().into_iter().find(|(k, _)| *k == id).unwrap();
        let record = restauro_farm::job::JobRecord::from_bytes(&id, &record).unwrap();
        let ready = record.frames_ready;
        assert!(ready >= 1);
        let mut done = store.finished_tiles(&id).unwrap();
        done.extend(0..record.frame_range(ready - 1).end);
        done
    };
    let addr = url.strip_prefix("http://").unwrap();
    let _coordinator = Coordinator::start(d, &d.join("data"), addr, &[]);
    let token = restauro_tests::token_files(d).0;
    let o = client(&["watch", &id], &url, &token);
    assert!(text(&o).contains("done"), "{}", text(&o));
    for (log, &from) in logs.iter().zip(&offsets) {
        let after = tiles_in(&lines(log)[from..], &id);
        for tile in after {
            assert!(
                !finished.contains(&tile),
                "tile {tile} was finished before the restart and rendered again"
            );
        }
    }
    let out = d.join("fetched");
    let o = client(&["fetch", &id, "--out", out.to_str().unwrap()], &url, &token);
    assert!(o.status.success(), "{}", text(&o));
    for frame in 0..8 {
        for suffix in [".exr", ".png", "-retinex.exr", "-retinex.png"] {
            assert!(
                out.join(format!("aosta-{frame:04}{suffix}")).is_file(),
                "frame {frame}{suffix}"
            );
        }
    }
    // The frame fetched early is the one the finished job lists.
    assert!(early == bytes(&out.join("aosta-0000.png")));
    // One eye saw the frames, through the restart: the frame after it is seen by the eye the
    // frame before it left.
    let lagging = eye_follows_the_frames(&out, "aosta", 8, TIME_LAPSE_STEP_S);
    assert!(lagging >= 6, "only {lagging} of 7 frames were seen by an eye behind their light");
}

/// A sequence from a hostile or careless client: a frame's date-time without its offset, more
/// frames or tiles than the coordinator takes, a frame a worker asks for that the job does not
/// have. Each is refused naming the fix; a sequence within the limits is taken after them.
#[test]
fn sequences_over_the_coordinators_limits_are_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let runtime = tokio::runtime::Runtime::new().unwrap();
    runtime.block_on(async {
        let limits = ["--max-frames", "6", "--max-job-tiles", "100"];
        let (coordinator, mut client, bundle) = wire::farm(d, 64, 36, &limits).await;
        let with = |frames: Vec<Frame>| restauro_scene::job::JobSpec {
            frames,
            ..wire::spec("aosta", 16, 1)
        };
        let mut no_offset = morning();
        no_offset[1].datetime = Some("2026-07-15T08:00:00".into());
        let e = wire::submit(&mut client, &bundle, &with(no_offset)).await.unwrap_err();
        assert_eq!(e.code(), tonic::Code::InvalidArgument);
        assert!(
            e.message().contains("frame 1 (08:00)") && e.message().contains("UTC offset"),
            "{e}"
        );
        let mut backwards = morning();
        backwards[2].elapsed_s = Some(1.0);
        let e = wire::submit(&mut client, &bundle, &with(backwards)).await.unwrap_err();
        assert_eq!(e.code(), tonic::Code::InvalidArgument);
        assert!(e.message().contains("frame 2 is at 1 s, before frame 1"), "{e}");
        // A hypothesis the scene does not have: its frame is planned, and refused.
        let mut unknown = morning()[..2].to_vec();
        unknown[1].variant = Some("gilded".into());
        let e = wire::submit(&mut client, &bundle, &with(unknown)).await.unwrap_err();
        assert_eq!(e.code(), tonic::Code::InvalidArgument);
        assert!(e.message().contains("frame 1 (08:00)") && e.message().contains("gilded"), "{e}");
        let mut not_a_time = morning();
        not_a_time[3].elapsed_s = Some(f64::NAN);
        let e = wire::submit(&mut client, &bundle, &with(not_a_time)).await.unwrap_err();
        assert!(e.message().contains("frame 3 (10:00): elapsed_s NaN"), "{e}");
        let e = wire::submit(&mut client, &bundle, &with(morning())).await.unwrap_err();
        assert_eq!(e.code(), tonic::Code::ResourceExhausted);
        assert!(e.message().contains("--max-frames"), "{e}");
        // Five frames of 4 × 3 tiles of 16 px: 60 tiles; in tiles of 8 px, 240.
        let five = with(morning()[..5].to_vec());
        let small_tiles = restauro_scene::job::JobSpec {
            render: restauro_scene::plan::RenderOptions {
                tile: std::num::NonZeroU32::new(8),
                ..five.render.clone()
            },
            ..five.clone()
        };
        let e = wire::submit(&mut client, &bundle, &small_tiles).await.unwrap_err();
        assert_eq!(e.code(), tonic::Code::ResourceExhausted);
        assert!(e.message().contains("--max-job-tiles"), "{e}");
        let status = wire::submit(&mut client, &bundle, &five).await.unwrap();
        assert_eq!((status.frames_total, status.tiles_total), (5, 60));
        let mut work = wire::work_client(&coordinator.url).await;
        let session = wire::register(&mut work, "w").await;
        let asked = |frame| pb::pb::FetchJobRequest {
            session: Some(session.clone()),
            job_id: status.job_id.clone(),
            frame,
        };
        let e = work.fetch_job(asked(5)).await.unwrap_err();
        assert_eq!(e.code(), tonic::Code::NotFound);
        let third = work.fetch_job(asked(2)).await.unwrap().into_inner();
        assert_eq!(third.first_tile, 24);
        assert!(third.manifest_json.contains("2026-07-15T09:00:00+02:00"));
    });
}

/// The bay's calculation grid under the CIE clear sky through three hours: a column of lux per
/// hour for each of its points, each hour's grid the scene at that hour computed alone, and a
/// chart.
#[test]
fn a_grid_through_the_day_is_each_hour_computed_alone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let summer = aosta_scene(d, 32, 18);
    let clear = Path::new(&summer).with_file_name("aosta-clear.toml");
    let clear = clear.to_str().unwrap();
    let out = d.join("bay");
    let o = restauro(&[
        "illuminance",
        clear,
        "--sun-from",
        "12:00",
        "--to",
        "14:00",
        "--every",
        "1h",
        "--spp",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let csv = std::fs::read_to_string(out.join("bay-4-day.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows[0], "index,x_m,y_m,z_m,lux 12:00,lux 13:00,lux 14:00");
    assert_eq!(rows.len(), 1 + 12 * 42);
    let alone = at_time(clear, "2026-07-15T13:00:00+02:00", "alone.toml");
    let alone_out = d.join("alone");
    let o = restauro(&[
        "illuminance",
        &alone,
        "--in-process",
        "--spp",
        "2",
        "--out",
        alone_out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let a = bytes(&alone_out.join("alone-illuminance.exr"));
    assert!(a == bytes(&out.join("aosta-clear-illuminance-0001.exr")), "13:00 differs alone");
    // The day's 13:00 column is the lone computation's lux column, point by point.
    let lone = std::fs::read_to_string(alone_out.join("bay-4.csv")).unwrap();
    for (day, lone) in rows[1..].iter().zip(lone.lines().skip(1)) {
        let day: Vec<&str> = day.split(',').collect();
        let lone: Vec<&str> = lone.split(',').collect();
        assert_eq!(day[5], lone[7], "point {}", day[0]);
    }
    let chart = bytes(&out.join("bay-4-day.png"));
    assert!(chart.starts_with(b"\x89PNG"));
}
