//! Sequences in the studio, against a real coordinator and worker: a sun study started from the
//! page, its frames arriving on the timeline as each is ready and scrubbed there (the picture
//! shown is the farm's file of that frame), the expansion's refusals shown beside the form, and
//! two hypotheses compared on the before/after slider at a frame (headless Chromium over CDP);
//! and the HTTP route's refusals, each a 400 in the expansion's words that leaves no job behind.
//! Screenshots go to `<target>/tmp/studio/`.

use restauro_tests::browser::{Browser, available, png_rgb};
use restauro_tests::http::request;
use restauro_tests::{CLIENT_TOKEN, Coordinator, Worker, aosta_scene, client, submit, text};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

fn shots() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("studio")
}

const BEARER: &str = "Bearer client-token-for-tests";

/// Job `id`'s files, fetched with the command line into `d/<id>`: the folder.
fn fetch(c: &Coordinator, d: &Path, token: &Path, id: &str) -> PathBuf {
    let out = d.join(id);
    let o = client(&["fetch", id, "--out", out.to_str().unwrap()], &c.url, token);
    assert!(o.status.success(), "{}", text(&o));
    out
}

/// The seen picture of frame `k` in a sequence's fetched files (`<name>-000k-retinex.png`,
/// the farm's naming), as RGB.
fn seen_frame(files: &Path, k: usize) -> Vec<[u8; 3]> {
    let suffix = format!("-{k:04}-retinex.png");
    let path = std::fs::read_dir(files)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_string_lossy().ends_with(&suffix))
        .unwrap_or_else(|| panic!("no *{suffix} in {}", files.display()));
    png_rgb(&std::fs::read(path).unwrap()).0
}

/// The pixels of the page's image `id` as the browser decoded them (RGB), its width, and its
/// `src`.
fn decoded(b: &mut Browser, id: &str) -> (Vec<[u8; 3]>, usize, String) {
    let v = b.eval(&format!(
        "(async () => {{ const i = document.getElementById('{id}'); await i.decode(); \
           const c = document.createElement('canvas'); c.width = i.naturalWidth; c.height = i.naturalHeight; \
           const g = c.getContext('2d'); g.drawImage(i, 0, 0); \
           return [c.width, i.getAttribute('src'), Array.from(g.getImageData(0, 0, c.width, c.height).data)]; }})()"
    ));
    let rgba: Vec<u8> =
        v[2].as_array().unwrap().iter().map(|x| x.as_u64().unwrap() as u8).collect();
    let rgb = rgba.chunks(4).map(|p| [p[0], p[1], p[2]]).collect();
    (rgb, v[0].as_u64().unwrap() as usize, v[1].as_str().unwrap().to_owned())
}

/// The mean absolute difference of two pictures of one size, 0–255.
fn difference(a: &[[u8; 3]], b: &[[u8; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: u64 = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| u64::from(p[k].abs_diff(q[k]))))
        .sum();
    sum as f64 / (3 * a.len()) as f64
}

/// A coordinator serving the studio, on `d/data`, with the flags `extra` too.
fn studio_coordinator(d: &Path, extra: &[&str]) -> Coordinator {
    let flags = [&["--studio-listen", "127.0.0.1:0"], extra].concat();
    Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &flags)
}

/// Moves the range input `id` to `value`, as a drag does.
fn set_range(b: &mut Browser, id: &str, value: usize) {
    b.eval(&format!(
        "(() => {{ const s = document.getElementById('{id}'); s.value = {value}; s.dispatchEvent(new Event('input')); }})()"
    ));
}

/// Sets the form field `id` to `value` (a string), as typing does.
fn fill(b: &mut Browser, id: &str, value: &str) {
    let v = serde_json::to_string(value).unwrap();
    b.eval(&format!(
        "(() => {{ const e = document.getElementById('{id}'); e.value = {v}; e.dispatchEvent(new Event('change')); }})()"
    ));
}

/// The sequence form's fields for a day from `from` to `to` every `every`, at `width × height`
/// px and 1 sample a pixel.
fn ask_for_a_day(
    b: &mut Browser,
    (from, to, every): (&str, &str, &str),
    (width, height): (u32, u32),
) {
    b.click("#seq-kind-day");
    for (id, value) in [
        ("seq-from", from.to_owned()),
        ("seq-to", to.to_owned()),
        ("seq-every", every.to_owned()),
        ("seq-width", width.to_string()),
        ("seq-height", height.to_string()),
        ("seq-spp", "1".to_owned()),
    ] {
        fill(b, id, &value);
    }
}

/// The page, signed in, once it shows the scene the farm holds.
fn page(studio: &str) -> Browser {
    let mut b = Browser::launch(1280, 900);
    b.goto(&format!("http://{studio}/#token={CLIENT_TOKEN}"));
    b.wait_for("the model", "document.getElementById('view').dataset.scene");
    b
}

/// The text the page shows beside the sequence's start button (after its row of controls, where
/// the studio shows the refusal of an action taken there) once it contains `words`.
fn refusal_saying(b: &mut Browser, words: &str) -> String {
    let first = b.refusal_beside("#seq-start");
    if first.contains(words) {
        return first;
    }
    let shown =
        "document.getElementById('seq-start').closest('.actions').nextElementSibling.textContent";
    let quoted = serde_json::to_string(words).unwrap();
    b.wait_for(&format!("the refusal `{words}`"), &format!("{shown}.includes({quoted})"));
    b.eval(shown).as_str().unwrap().to_owned()
}

/// A sun study of three hours started from the page, on a coordinator whose store commits
/// slowly (so that frames are ready one after another, seconds apart): the frames come onto the
/// timeline in order as each is ready, before the job ends; scrubbing shows each frame's own
/// file as the farm wrote it, labelled with its time. A step of zero and a walk through a view
/// the scene does not have are refused beside the form, in the expansion's words, and start no
/// job.
#[test]
fn a_sun_study_arrives_frame_by_frame_and_the_timeline_scrubs_it() {
    if !available("studio_sequence") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let c = studio_coordinator(d, &["--fault-commit-delay-ms", "250"]);
    let _worker = Worker::start(d, &c.url, "local-1", &[]);
    let scene = aosta_scene(d, 160, 90);
    let token = d.join("client.token");
    // The scene reaches the farm with a render from the command line.
    submit(&scene, &["--spp", "1"], &c.url, &token);
    let studio = c.studio.clone().unwrap();
    let mut b = page(&studio);
    // Every state of the timeline, in order: a 1 for each frame shown ready.
    b.eval(
        "(() => { window.seqSeen = []; const record = () => { \
           const s = [...document.querySelectorAll('#seq-timeline li')].map(l => l.dataset.ready === 'true' ? '1' : '0').join(''); \
           if (s && window.seqSeen[window.seqSeen.length - 1] !== s) window.seqSeen.push(s); }; \
         new MutationObserver(record).observe(document.getElementById('seq-timeline'), { childList: true, subtree: true, attributes: true }); })()",
    );
    ask_for_a_day(&mut b, ("12:00", "14:00", "1h"), (96, 54));
    b.click("#seq-start");
    b.wait_for(
        "three frames ready on the timeline",
        "document.querySelectorAll('#seq-timeline li[data-ready=\"true\"]').length === 3",
    );
    let seen: Vec<String> = serde_json::from_value(b.eval("window.seqSeen")).unwrap();
    eprintln!("the timeline's states: {seen:?}");
    assert!(
        seen.iter().all(|s| s.len() == 3 && !s.contains("01")),
        "frames shown ready out of order: {seen:?}"
    );
    assert!(
        seen.iter().any(|s| s == "100" || s == "110"),
        "no frame was shown before the last was ready: {seen:?}"
    );
    assert_eq!(seen.last().map(String::as_str), Some("111"));
    let id = b.eval("document.getElementById('seq-a').value").as_str().unwrap().to_owned();
    let row = format!("document.querySelector('#jobs tr[data-job=\"{id}\"]')");
    b.wait_for("the job done", &format!("{row} && {row}.children[1].textContent === 'done'"));
    let status = b.eval("document.getElementById('seq-status').textContent");
    assert!(status.as_str().unwrap().contains("3 of 3 frames ready"), "{status}");
    let files = fetch(&c, d, &token, &id);
    let frames: Vec<Vec<[u8; 3]>> = (0..3).map(|k| seen_frame(&files, k)).collect();
    assert!(difference(&frames[0], &frames[2]) > 1.0, "12:00 and 14:00 look alike");

    // Scrubbed to each frame, the picture is that frame's file, labelled with its time.
    for k in [2, 0, 1] {
        set_range(&mut b, "seq-scrub", k);
        b.wait_for(
            "the frame shown",
            &format!(
                "(() => {{ const i = document.getElementById('seq-img-a'); \
                 return i.dataset.frame === '{k}' && i.complete && i.naturalWidth === 96; }})()"
            ),
        );
        let (pixels, width, src) = decoded(&mut b, "seq-img-a");
        assert_eq!(width, 96);
        assert!(src.ends_with(&format!("-{k:04}-retinex.png")), "frame {k} shows {src}");
        assert!(difference(&pixels, &frames[k]) < 0.5, "frame {k} is not its file");
        let label = b.eval("document.getElementById('seq-label').textContent");
        assert!(
            label.as_str().unwrap().starts_with(&format!("{}:00 (frame {} of 3)", 12 + k, k + 1)),
            "{label}"
        );
    }
    b.screenshot(&shots().join("80-sequence-timeline.png"));

    // Refusals, beside the form, in the expansion's words; no job is started by them.
    fill(&mut b, "seq-every", "0m");
    b.click("#seq-start");
    let said = refusal_saying(&mut b, "a step of zero");
    assert!(said.contains("15m"), "{said}");
    b.click("#seq-kind-walk");
    fill(&mut b, "seq-views", "nowhere, elsewhere");
    b.click("#seq-start");
    refusal_saying(&mut b, "unknown view `nowhere`");
    b.screenshot(&shots().join("81-sequence-refused.png"));
    let auth = [("Authorization", BEARER)];
    let jobs = request(&studio, "GET", "/api/jobs", &auth, b"").json();
    assert_eq!(jobs.as_array().unwrap().len(), 2, "a refusal left a job: {jobs}");
}

/// The mean difference between what the page shows in `rect` (a screenshot's) and `png`
/// (`width` px wide) drawn into it, over the share `part` of its width (0–1 from the left):
/// each image pixel against the screen pixel at its middle, where the browser's scaling shows
/// that pixel's own colour.
fn shown_against(
    shot: &[u8],
    rect: [f64; 4],
    png: &[[u8; 3]],
    width: usize,
    part: (f64, f64),
) -> f64 {
    let (screen, sw) = png_rgb(shot);
    let height = png.len() / width;
    let [x, y, w, h] = rect;
    let (sx, sy) = (w / width as f64, h / height as f64);
    let columns = (part.0 * width as f64).ceil() as usize..(part.1 * width as f64) as usize;
    let (mut sum, mut n) = (0u64, 0u64);
    for iy in 1..height - 1 {
        for ix in columns.clone().filter(|&ix| ix > 0 && ix + 1 < width) {
            let (px, py) = (x + (ix as f64 + 0.5) * sx, y + (iy as f64 + 0.5) * sy);
            let (p, q) = (screen[py as usize * sw + px as usize], png[iy * width + ix]);
            sum += (0..3).map(|k| u64::from(p[k].abs_diff(q[k]))).sum::<u64>();
            n += 3;
        }
    }
    sum as f64 / n as f64
}

/// Two hypotheses of one day, started together from the page (the hypothesis chosen, and one
/// to compare with): two jobs of the same frames, and at any frame the slider shows that frame
/// of A on its left and of B on its right (each the farm's file of that frame of its job).
#[test]
fn two_hypotheses_of_a_day_compare_on_the_slider_at_a_frame() {
    if !available("studio_sequence") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let farm = Coordinator::studio_farm(d, 160, 90);
    let c = &farm.coordinator;
    submit(&farm.scene, &["--spp", "1"], &c.url, &farm.token);
    let mut b = farm.page_in_browser(1280, 900);
    fill(&mut b, "snap-variant", "as-found");
    ask_for_a_day(&mut b, ("10:00", "16:00", "3h"), (96, 54));
    fill(&mut b, "seq-compare-with", "\"cleaned\"");
    b.click("#seq-start");
    b.wait_for(
        "frame 3 of both",
        "document.getElementById('seq-b').value && \
         document.getElementById('seq-status').textContent.split('3 of 3 frames ready').length === 3",
    );
    let (a, bb) = (
        b.eval("document.getElementById('seq-a').value").as_str().unwrap().to_owned(),
        b.eval("document.getElementById('seq-b').value").as_str().unwrap().to_owned(),
    );
    let names = b.eval(&format!(
        "[document.querySelector('#jobs tr[data-job=\"{a}\"]').children[0].textContent, \
          document.querySelector('#jobs tr[data-job=\"{bb}\"]').children[0].textContent]"
    ));
    assert_eq!(names, json!(["aosta-day-as-found", "aosta-day-cleaned"]));
    for id in [&a, &bb] {
        let row = format!("document.querySelector('#jobs tr[data-job=\"{id}\"]')");
        b.wait_for("the job done", &format!("{row}.children[1].textContent === 'done'"));
    }
    let (fa, fb) = (fetch(c, d, &farm.token, &a), fetch(c, d, &farm.token, &bb));
    let k = 1;
    let (want_a, want_b) = (seen_frame(&fa, k), seen_frame(&fb, k));
    let apart = difference(&want_a, &want_b);
    eprintln!("frame 2 of A and B differ by {apart} (0–255)");
    assert!(apart > 1.0, "the two hypotheses look alike at 13:00");

    set_range(&mut b, "seq-scrub", k);
    b.wait_for(
        "frame 2 of both",
        "['seq-img-a', 'seq-img-b'].every(id => { const i = document.getElementById(id); \
           return i.dataset.frame === '1' && i.complete && i.naturalWidth === 96; })",
    );
    let label = b.eval("document.getElementById('seq-label').textContent");
    assert!(label.as_str().unwrap().starts_with("13:00 (frame 2 of 3)"), "{label}");
    for (img, job, want) in [("seq-img-a", &a, &want_a), ("seq-img-b", &bb, &want_b)] {
        let (pixels, _, src) = decoded(&mut b, img);
        assert!(src.contains(job.as_str()) && src.ends_with("-0001-retinex.png"), "{img}: {src}");
        assert!(difference(&pixels, want) < 0.5, "{img} is not frame 2 of its job");
    }
    // The frame's files, of A and B, to download: the farm's four of that frame of each.
    let links: Vec<String> = serde_json::from_value(b.eval(
        "[...document.querySelectorAll('#seq-downloads a')].map(a => decodeURIComponent(a.getAttribute('href')))",
    ))
    .unwrap();
    let mut want: Vec<String> = Vec::new();
    for (job, files) in [(&a, &fa), (&bb, &fb)] {
        let mut names: Vec<String> = std::fs::read_dir(files)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("-0001.") || n.contains("-0001-"))
            .collect();
        names.sort();
        want.extend(names.into_iter().map(|n| format!("/api/jobs/{job}/results/{n}")));
    }
    let mut got = links.clone();
    got.sort();
    want.sort();
    assert_eq!(got, want, "the downloads of frame 2");
    assert_eq!(want.len(), 8);

    // The slider: all A, then all B, then half of each.
    b.eval("document.getElementById('seq-view').scrollIntoView({ block: 'center' })");
    let rect = b.rect("#seq-view");
    let shown = |b: &mut Browser, v: usize, name: &str| {
        set_range(b, "seq-slider", v);
        let shot = b.screenshot(&shots().join(name));
        let whole = (0.0, 1.0);
        (
            shown_against(&shot, rect, &want_a, 96, whole),
            shown_against(&shot, rect, &want_b, 96, whole),
            shot,
        )
    };
    let (to_a, to_b, _) = shown(&mut b, 100, "82-sequence-slider-a.png");
    eprintln!("at 100 % A the view differs from A by {to_a}, from B by {to_b}");
    assert!(
        to_a * 2.0 < to_b,
        "at 100 % A the view is A's frame: {to_a} against A, {to_b} against B"
    );
    let (to_a, to_b, _) = shown(&mut b, 0, "83-sequence-slider-b.png");
    assert!(
        to_b * 2.0 < to_a,
        "at 0 % A the view is B's frame: {to_a} against A, {to_b} against B"
    );
    let (_, _, shot) = shown(&mut b, 50, "84-sequence-slider-half.png");
    let (left, right) = ((0.0, 0.47), (0.53, 1.0));
    let against = |part: (f64, f64), png: &[[u8; 3]]| shown_against(&shot, rect, png, 96, part);
    let (left_a, left_b) = (against(left, &want_a), against(left, &want_b));
    let (right_a, right_b) = (against(right, &want_a), against(right, &want_b));
    assert!(
        left_a < left_b && right_b < right_a,
        "at 50 %: left {left_a}/{left_b}, right {right_a}/{right_b} (A/B)"
    );
    assert_eq!(b.eval("document.getElementById('seq-slider-shown').textContent"), "50 % A");

    // Over the whole view, as large as it fits: still A's frame on the left of the slider and
    // B's on the right; Esc puts it back in the panel.
    b.click("#seq-over");
    let (stage, over) = (b.rect("#stage"), b.rect("#seq-view"));
    let fits_width = (over[2] - stage[2]).abs() <= 1.0 && over[3] <= stage[3] + 0.5;
    let fits_height = (over[3] - stage[3]).abs() <= 1.0 && over[2] <= stage[2] + 0.5;
    assert!(fits_width || fits_height, "over the view at {over:?}, the view at {stage:?}");
    assert!((over[2] / over[3] - 96.0 / 54.0).abs() < 0.02, "its aspect at {over:?}");
    set_range(&mut b, "seq-slider", 0);
    let shot = b.screenshot(&shots().join("85-sequence-over-the-view.png"));
    let (to_a, to_b) = (
        shown_against(&shot, over, &want_a, 96, (0.0, 1.0)),
        shown_against(&shot, over, &want_b, 96, (0.0, 1.0)),
    );
    assert!(to_b * 2.0 < to_a, "over the view at 0 % A: {to_a} against A, {to_b} against B");
    b.eval("document.activeElement.blur()");
    b.press("Escape");
    b.wait_for(
        "the frame back in the panel",
        "document.getElementById('seq-view').parentElement.id === 'seq-player' && document.getElementById('sequence-stage').hidden",
    );

    // Shown from the farm's table, B becomes the sequence shown.
    b.click(&format!("#jobs tr[data-job=\"{bb}\"] button"));
    b.wait_for("B shown as A", &format!("document.getElementById('seq-a').value === '{bb}'"));
    b.wait_for(
        "B's frame",
        &format!("document.getElementById('seq-img-a').getAttribute('src').includes('{bb}')"),
    );
}

/// What the studio answers `body` on `POST /api/scenes/{scene}/sequences`.
fn start(studio: &str, scene: &str, body: &Value) -> restauro_tests::http::Response {
    let auth = [("Authorization", BEARER)];
    let path = format!("/api/scenes/{scene}/sequences");
    request(studio, "POST", &path, &auth, body.to_string().as_bytes())
}

/// The route's refusals: each a 400 in the words of the sequence's expansion (the command
/// line's), or naming the field; none leaves a job. One accepted: a job per hypothesis, of the
/// same frames, listed with their labels by `/api/jobs/{id}/frames`.
#[test]
fn a_sequence_request_is_refused_in_the_expansions_words() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let c = studio_coordinator(d, &["--max-frames", "4"]);
    let scene = aosta_scene(d, 32, 18);
    let token = d.join("client.token");
    let still = submit(&scene, &["--spp", "1"], &c.url, &token);
    let studio = c.studio.clone().unwrap();
    let auth = [("Authorization", BEARER)];
    let scenes = request(&studio, "GET", "/api/scenes", &auth, b"").json();
    let id = scenes[0]["id"].as_str().unwrap().to_owned();
    let day = |from: &str, to: &str, every: &str| {
        json!({
            "sequence": { "kind": "day", "from": from, "to": to, "every": every },
            "render": { "width": 32, "height": 18, "samples_per_pixel": 1 },
            "hypotheses": [null],
        })
    };
    let walk = |views: Value| {
        json!({
            "sequence": { "kind": "walk", "views": views, "fps": 2.0, "speed_m_s": 1.4 },
            "hypotheses": [null],
        })
    };
    let with = |mut body: Value, key: &str, value: Value| {
        match key.strip_prefix("render.") {
            Some(option) => body["render"][option] = value,
            None => body[key] = value,
        }
        body
    };
    let base = day("12:00", "13:00", "1h");
    for (body, words) in [
        (day("12:00", "13:00", "0m"), "a step of zero never moves the sun"),
        (day("25:00", "26:00", "1h"), "sequence.from: `25:00` is not a clock time"),
        (day("14:00", "12:00", "1h"), "backwards"),
        (day("22:00", "23:30", "30m"), "the sun never rises in this range"),
        (day("06:00", "21:00", "1h"), "16, over the limit of 4"),
        (with(base.clone(), "hypotheses", json!([])), "hypotheses: 0 given"),
        (with(base.clone(), "hypotheses", json!([null, "cleaned", "as-found"])), "3 given"),
        (with(base.clone(), "hypotheses", json!(["restored"])), "no variant `restored`"),
        (with(base.clone(), "hypotheses", json!(["cleaned", "cleaned"])), "the same hypothesis"),
        (with(base.clone(), "render.variant", json!("cleaned")), "render.variant"),
        (with(base.clone(), "render.samples_per_pixel", json!(0)), "render.samples_per_pixel"),
        (walk(json!(["nowhere", "elsewhere"])), "unknown view `nowhere`"),
        (walk(json!(["nowhere"])), "at least two saved views"),
    ] {
        let r = start(&studio, &id, &body);
        assert_eq!(r.status, 400, "{body}: {}", r.text());
        let said = r.json()["error"].as_str().unwrap().to_owned();
        assert!(said.contains(words), "{body}: `{said}` does not say `{words}`");
    }
    let jobs = request(&studio, "GET", "/api/jobs", &auth, b"").json();
    assert_eq!(jobs.as_array().unwrap().len(), 1, "a refusal left a job: {jobs}");

    // A still has no frames to list.
    let r = request(&studio, "GET", &format!("/api/jobs/{still}/frames"), &auth, b"");
    assert_eq!(r.status, 400, "{}", r.text());
    assert!(r.text().contains("is a still, not a sequence"), "{}", r.text());

    // Accepted: a job per hypothesis, in the order asked, of the same frames.
    let r = start(&studio, &id, &with(base, "hypotheses", json!([null, "cleaned"])));
    assert_eq!(r.status, 200, "{}", r.text());
    let started = r.json();
    assert_eq!(started["labels"], json!(["12:00", "13:00"]));
    let jobs = started["jobs"].as_array().unwrap();
    let names: Vec<&str> = jobs.iter().map(|j| j["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["aosta-day", "aosta-day-cleaned"]);
    for job in jobs {
        assert_eq!(job["frames_total"], 2);
        let path = format!("/api/jobs/{}/frames", job["id"].as_str().unwrap());
        let frames = request(&studio, "GET", &path, &auth, b"").json();
        let labels: Vec<&str> = frames["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["label"].as_str().unwrap())
            .collect();
        assert_eq!(labels, ["12:00", "13:00"], "{frames}");
        // No worker: nothing is ready, so no frame has files yet.
        assert_eq!(frames["frames_ready"], 0);
        assert!(frames["frames"].as_array().unwrap().iter().all(|f| f["files"] == json!([])));
        // From a frame on: the rest only, numbered as in the whole.
        let rest = request(&studio, "GET", &format!("{path}?from=1"), &auth, b"").json();
        assert_eq!(rest["frames"], json!([{"index": 1, "label": "13:00", "files": []}]));
        let r = request(&studio, "GET", &format!("{path}?from=-1"), &auth, b"");
        assert_eq!(r.status, 400, "{}", r.text());
        assert!(r.text().contains("from: `-1` is not a frame number"), "{}", r.text());
    }

    // A walk through two views saved in the studio (a new revision, the latest): 3 m at
    // 1.4 m/s and a frame a second, a frame at 0, 1.4 and 2.8 m.
    for (name, x) in [("west", 1.0), ("east", 4.0)] {
        let view = json!({"edit": "save-view", "view": {"name": name,
            "position": [x, 1.6, 8.0], "target": [x, 3.0, 0.0], "up": [0.0, 1.0, 0.0]}});
        let path = format!("/api/scenes/{id}/edits");
        let r = request(&studio, "POST", &path, &auth, view.to_string().as_bytes());
        assert_eq!(r.status, 200, "{}", r.text());
    }
    let mut walk = walk(json!(["west", "east"]));
    walk["sequence"]["fps"] = json!(1.0);
    let r = start(&studio, &id, &walk);
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["labels"], json!(["0.00 s, 0.0 m", "1.00 s, 1.4 m", "2.00 s, 2.8 m"]));
    assert_eq!(r.json()["jobs"][0]["name"], "aosta-walk");
}
