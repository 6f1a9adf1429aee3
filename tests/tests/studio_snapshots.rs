//! Snapshots in place, in a real browser (headless Chromium over CDP) against a real coordinator
//! and worker: a finished snapshot stays over the view as an image layer lined up with the
//! model, zooms to 1:1, and reads out the pixel under the pointer (checked against the farm's
//! EXR files with the CIE formulas written out here, and the white `restauro compare` takes);
//! two snapshots compared over the whole view, with the ΔE00 under the pointer; the strip of
//! thumbnails. Screenshots go to `<target>/tmp/studio/`.

use restauro_image::image_files::{MAX_PIXELS, XyzImage, read_exr};
use restauro_tests::browser::{Browser, available, png_rgb};
use restauro_tests::{CLIENT_TOKEN, Coordinator, client, submit, text};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

fn shots() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("studio")
}

/// The view's background (`#9fb4c8`, the page's sky colour), within rounding.
fn is_background(p: [u8; 3]) -> bool {
    p.iter().zip([0x9f, 0xb4, 0xc8]).all(|(&a, b): (&u8, i32)| (i32::from(a) - b).abs() <= 2)
}

/// Job `id`'s files, fetched with the command line into `d/<id>`: the folder.
fn fetch(c: &Coordinator, d: &Path, token: &Path, id: &str) -> PathBuf {
    let out = d.join(id);
    let o = client(&["fetch", id, "--out", out.to_str().unwrap()], &c.url, token);
    assert!(o.status.success(), "{}", text(&o));
    out
}

/// The file of `dir` whose name ends with `suffix` (`.exr`, `-retinex.exr`, `.png`).
fn file(dir: &Path, suffix: &str) -> PathBuf {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            name.ends_with(suffix) && (suffix.starts_with('-') || !name.contains("-retinex"))
        })
        .unwrap_or_else(|| panic!("no *{suffix} in {}", dir.display()))
}

fn exr(path: &Path) -> XyzImage {
    read_exr(path, MAX_PIXELS).unwrap()
}

/// CIE 1976 L*a*b* of `xyz` relative to a D65 white (x 0.3127, y 0.3290) of luminance
/// `white_y`: CIE 15:2004 Eqs. 8.1–8.3, written out here.
fn cielab(xyz: [f32; 3], white_y: f64) -> [f64; 3] {
    let (x, y) = (0.3127, 0.3290);
    let white = [x / y * white_y, white_y, (1.0 - x - y) / y * white_y];
    let d: f64 = 6.0 / 29.0;
    let f = |t: f64| if t > d.powi(3) { t.cbrt() } else { t / (3.0 * d * d) + 4.0 / 29.0 };
    let [fx, fy, fz] = std::array::from_fn(|k| f(f64::from(xyz[k]) / white[k]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// The reference white `restauro compare A B` takes (cd/m²), from its compare.json; with it,
/// the whole of that file.
fn cli_compare(d: &Path, a: &Path, b: &Path, name: &str) -> Value {
    let out = d.join(name);
    let o = restauro_tests::restauro(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    serde_json::from_slice(&std::fs::read(out.join("compare.json")).unwrap()).unwrap()
}

/// The `n` numbers that follow `key` in `text` (`1,234.5` read as 1234.5).
fn numbers_after(text: &str, key: &str, n: usize) -> Vec<f64> {
    let at = text.find(key).unwrap_or_else(|| panic!("no `{key}` in `{text}`")) + key.len();
    let values: Vec<f64> = text[at..]
        .split([' ', '|', '(', ')'])
        .map(|t| t.trim_end_matches(',').replace(',', ""))
        .filter(|t| !t.is_empty())
        .take(n)
        .map(|t| t.parse().unwrap_or_else(|_| panic!("`{t}` after `{key}` in `{text}`")))
        .collect();
    values
}

/// Moves the mouse to (`x`, `y`) of the page and waits for the readout `output` of image pixel
/// (`px`, `py`); its text.
fn point_at(b: &mut Browser, output: &str, (x, y): (f64, f64), (px, py): (usize, usize)) -> String {
    b.call("Input.dispatchMouseEvent", json!({ "type": "mouseMoved", "x": x, "y": y }));
    b.wait_for(
        "the readout of the pixel",
        &format!(
            "(() => {{ const o = document.getElementById('{output}'); \
             return o.dataset.x === '{px}' && o.dataset.y === '{py}'; }})()"
        ),
    );
    b.eval(&format!("document.getElementById('{output}').textContent")).as_str().unwrap().to_owned()
}

/// The screenshot's pixels inside `rect` (x, y, width, height), row by row.
fn pixels_in(shot: &[u8], rect: [f64; 4]) -> Vec<[u8; 3]> {
    let (rgb, width) = png_rgb(shot);
    let [x, y, w, h] = rect.map(|v| v.round() as usize);
    (y..y + h)
        .flat_map(|py| (x..x + w).map(move |px| (py, px)))
        .map(|(py, px)| rgb[py * width + px])
        .collect()
}

/// The mean absolute difference of two pictures of one size, 0–255.
fn difference(a: &[[u8; 3]], b: &[[u8; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: i64 = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (i64::from(p[k]) - i64::from(q[k])).abs()))
        .sum();
    sum as f64 / (3 * a.len()) as f64
}

fn pose(b: &mut Browser) -> Value {
    b.eval("(() => { const p = window.studioViewer.pose(); return [p.position, p.target]; })()")
}

fn close_poses(a: &Value, b: &Value) -> bool {
    let flat = |v: &Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .flat_map(|p| p.as_array().unwrap().clone())
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    flat(a).iter().zip(flat(b)).all(|(x, y)| (x - y).abs() < 1e-6)
}

const LAYER_LOADED: &str = "(() => { const i = document.getElementById('result-image'); \
    return !document.getElementById('result').hidden && i.complete && i.naturalWidth === 160; })()";

/// Where the layer's picture lies at fit: its left and top (page px), its scale (screen px an
/// image px), the stage's width, and the image rows clear of the bar and the foot.
struct Fit {
    x: f64,
    y: f64,
    s: f64,
    stage_width: f64,
    rows: std::ops::Range<usize>,
}

/// At fit the layer is the view's height, centred, and each image pixel's middle shows the
/// farm's PNG (160 × 90).
fn the_layer_at_fit_is_the_png(b: &mut Browser, png: &[[u8; 3]]) -> Fit {
    // At fit: the view's height, centred; each image pixel's middle shows the PNG's pixel.
    let stage = b.rect("#stage");
    let [x, y, w, h] = b.rect("#result-image");
    assert!((h - stage[3]).abs() < 0.5 && (w - 160.0 * h / 90.0).abs() < 0.5, "{:?}", [x, y, w, h]);
    assert!((x + w / 2.0 - (stage[0] + stage[2] / 2.0)).abs() < 0.5, "not centred: {x}");
    let shot = b.screenshot(&shots().join("60-snapshot-layer.png"));
    let (screen, sw) = png_rgb(&shot);
    let s = h / 90.0;
    let middle = |ix: usize, iy: usize| {
        let (sx, sy) = (x + (ix as f64 + 0.5) * s, y + (iy as f64 + 0.5) * s);
        screen[sy as usize * sw + sx as usize]
    };
    // (The rows clear of the bar over the top and the foot and strip along the bottom.)
    let (bar, foot) = (b.rect("#result .layer-bar"), b.rect("#result .layer-foot"));
    let rows =
        ((bar[1] + bar[3] - y) / s).ceil() as usize..((foot[1] - y) / s).floor() as usize - 1;
    assert!(rows.len() > 40, "{rows:?}");
    let mut off = 0;
    for iy in rows.clone() {
        for ix in 0..160 {
            let (p, q) = (middle(ix, iy), png[iy * 160 + ix]);
            off += usize::from((0..3).any(|k| p[k].abs_diff(q[k]) > 2));
        }
    }
    // (A few pixels' middles fall on the edge of a magnified pixel: the scale is not whole.)
    let checked = rows.len() * 160;
    assert!(off * 50 < checked, "{off} of {checked} pixels of the layer differ from the PNG");

    Fit { x, y, s, stage_width: stage[2], rows }
}

/// Moving the camera closes the layer; back at the snapshot's pose (`taken_at`), the model in
/// the view is where the render's surfaces are (`emitter`: the render's sky pixels).
fn the_model_lines_up_under_the_layer(
    b: &mut Browser,
    taken_at: &Value,
    fit: &Fit,
    emitter: &[bool],
) {
    let Fit { x, y, s, stage_width, ref rows } = *fit;
    // Moving the camera closes the layer; the model under it is where the render's surfaces are.
    b.eval(
        "(() => { const v = window.studioViewer, p = v.pose(); p.position[1] += 0.8; v.fly(p); })()",
    );
    assert_eq!(b.eval("document.getElementById('result').hidden"), true, "the camera moved");
    let back = format!(
        "(() => {{ const v = window.studioViewer, p = v.pose(), t = {taken_at}; \
         p.position = t[0]; p.target = t[1]; v.fly(p); v.draw(); }})()"
    );
    b.eval(&back);
    let model = b.screenshot(&shots().join("61-model-under-the-layer.png"));
    let (view, sw) = png_rgb(&model);
    let (mut agree, mut all) = (0, 0);
    for iy in rows.clone() {
        for ix in 2..158 {
            let (sx, sy) = (x + (ix as f64 + 0.5) * s, y + (iy as f64 + 0.5) * s);
            if sx < 0.0 || sx >= stage_width {
                continue;
            }
            let sky_in_view = is_background(view[sy as usize * sw + sx as usize]);
            agree += usize::from(sky_in_view == emitter[iy * 160 + ix]);
            all += 1;
        }
    }
    let share = agree as f64 / all as f64;
    eprintln!(
        "the model and the render's surfaces agree at {:.1} % of {all} pixels",
        share * 100.0
    );
    assert!(share > 0.9, "the layer does not line up with the model: {share}");
}

/// The readout of a pixel of the model (at 1:1): luminance, CIELAB as rendered and as seen, as
/// the farm's EXR files (`files`) give them.
fn the_readout_is_the_exrs(
    b: &mut Browser,
    d: &Path,
    files: &Path,
    rendered: &XyzImage,
    emitter: &[bool],
) {
    // The readout of a pixel of the model: luminance, CIELAB as rendered and as seen.
    let (px, py) = (0..160 * 90)
        .map(|i| (i % 160, i / 160))
        .find(|&(ix, iy)| iy > 40 && ix > 60 && !emitter[iy * 160 + ix])
        .unwrap();
    let rect = b.rect("#result-image");
    let said = point_at(
        b,
        "pixel-readout",
        (rect[0] + px as f64 + 0.5, rect[1] + py as f64 + 0.5),
        (px, py),
    );
    b.screenshot(&shots().join("63-readout.png"));
    let i = py * 160 + px;
    let luminance = f64::from(rendered.pixels[i][1]);
    let shown = numbers_after(&said, "luminance ", 1)[0];
    assert!((shown - luminance).abs() <= 1e-3 * luminance, "{said}: the EXR's Y is {luminance}");
    let exr_path = file(files, ".exr");
    let white = cli_compare(d, &exr_path, &exr_path, "self")["white_luminance"].as_f64().unwrap();
    let want = cielab(rendered.pixels[i], white);
    let got = numbers_after(&said, "as rendered ", 3);
    for k in 0..3 {
        assert!((got[k] - want[k]).abs() < 0.011, "{said}: L*a*b* as rendered {want:?}");
    }
    let seen = exr(&file(files, "-retinex.exr"));
    let want = cielab(seen.pixels[i], 1.0);
    let got = numbers_after(&said, "as seen ", 3);
    for k in 0..3 {
        assert!((got[k] - want[k]).abs() < 0.011, "{said}: L*a*b* as seen {want:?}");
    }
}

/// A snapshot taken in the page stays over the view when it is done: the view's camera at its
/// pose, the farm's PNG drawn at the view's height over the model (where the preview draws the
/// model, the render has no sky), and closes when the camera moves; its thumbnail brings it
/// back at its pose. At 1:1 each image pixel is one screen pixel, and the readout of a pixel is
/// its luminance and CIELAB as the EXR files give them.
#[test]
fn a_finished_snapshot_stays_over_the_model_and_reads_out_its_pixels() {
    if !available("studio_snapshots") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let farm = Coordinator::studio_farm(d, 160, 90);
    let c = &farm.coordinator;
    // The scene reaches the farm with a render from the command line.
    let first = submit(&farm.scene, &["--spp", "1"], &c.url, &farm.token);
    let mut b = farm.page_in_browser(1280, 720);
    // The panels folded away: the view has the whole window.
    b.press("p");
    // A snapshot of the view a little to the side of the scene's camera.
    b.eval(
        "(() => { const v = window.studioViewer, p = v.pose(); p.position[0] += 1.5; p.target[0] += 1.5; v.fly(p); })()",
    );
    let taken_at = pose(&mut b);
    b.eval("document.getElementById('snap-spp').value = 2");
    b.eval("document.getElementById('snapshot-form').requestSubmit()");
    b.wait_for("the snapshot's layer", LAYER_LOADED);
    let id = b.eval("document.getElementById('result').dataset.job").as_str().unwrap().to_owned();
    assert_eq!(b.eval("document.getElementById('result').dataset.aligned"), "true");
    assert!(close_poses(&pose(&mut b), &taken_at), "the view left the snapshot's pose");
    let files = fetch(c, d, &farm.token, &id);
    let (png, width) = png_rgb(&std::fs::read(file(&files, ".png")).unwrap());
    assert_eq!(width, 160);
    let rendered = exr(&file(&files, ".exr"));
    // The form's default noise target makes the snapshot adaptive: its EXR records each pixel's
    // samples, here all at the cap of 2 (a pixel's first look comes after 8).
    let counts = restauro_tests::exr_channel(&file(&files, ".exr"), "samples")
        .expect("a snapshot at the form's noise target records its samples");
    assert!(counts.iter().all(|&n| n == 2.0), "{:?}", &counts[..8]);

    let fit = the_layer_at_fit_is_the_png(&mut b, &png);
    let emitter = rendered.emitter.clone().expect("the render's emitter channel");
    the_model_lines_up_under_the_layer(&mut b, &taken_at, &fit, &emitter);

    // The strip lists the snapshot; its thumbnail shows it again, at its pose (from elsewhere).
    b.press("h");
    assert!(!close_poses(&pose(&mut b), &taken_at));
    let mut listed: Vec<String> = serde_json::from_value(
        b.eval("[...document.querySelectorAll('#strip-list li')].map(l => l.dataset.job)"),
    )
    .unwrap();
    listed.sort();
    let mut both = vec![first.clone(), id.clone()];
    both.sort();
    assert_eq!(listed, both, "the strip lists each finished snapshot");
    b.click(&format!("#strip-list li[data-job='{id}'] .thumb"));
    b.wait_for("the layer again", LAYER_LOADED);
    assert!(close_poses(&pose(&mut b), &taken_at), "the thumbnail did not fly back");

    // 1:1: one image pixel to one screen pixel, the PNG's own pixels.
    b.click("#result-one");
    let rect = b.rect("#result-image");
    assert_eq!((rect[2], rect[3]), (160.0, 90.0), "1:1 at {:?}", rect);
    assert_eq!(b.eval("document.getElementById('result-zoom').textContent"), "1:1");
    let shown = pixels_in(&b.screenshot(&shots().join("62-snapshot-1-1.png")), rect);
    assert!(difference(&shown, &png) < 0.5, "1:1 shows {}", difference(&shown, &png));
    // + doubles it.
    b.click("#result-in");
    assert_eq!(b.rect("#result-image")[2], 320.0);
    b.click("#result-one");

    the_readout_is_the_exrs(&mut b, d, &files, &rendered, &emitter);
}

/// The pixel endpoint refuses what it cannot read, naming the field.
fn bad_pixels_are_refused(c: &Coordinator, a: &str) {
    let auth = [("Authorization", format!("Bearer {CLIENT_TOKEN}"))];
    let auth: Vec<(&str, &str)> = auth.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let studio = c.studio.as_deref().unwrap();
    for (query, field) in [
        (format!("/api/jobs/{a}/pixel?x=160&y=0"), "x: 160 is outside the image"),
        (format!("/api/jobs/{a}/pixel?x=3&y=-1"), "y: `-1` is not a pixel index"),
        (format!("/api/jobs/{a}/pixel?x=3"), "y: missing"),
        (format!("/api/jobs/{a}/pixel?x=3&y=3&other=nope"), "other: `nope` is not a job id"),
        ("/api/jobs/nope/pixel?x=3&y=3".to_owned(), "job_id"),
    ] {
        let r = restauro_tests::http::request(studio, "GET", &query, &auth, b"");
        assert_eq!(r.status, 400, "{query}: {}", r.text());
        let words = r.json()["error"].as_str().unwrap().to_owned();
        assert!(words.contains(field), "{query}: {words}");
    }
}

/// Two hypotheses, chosen as A and B in the strip, compared over the whole view: the slider's
/// ends are the PNGs at 1:1, the ΔE00 layer the server's map, the statistics `restauro
/// compare`'s, and the ΔE00 read out under the pointer the CIEDE2000 of the two EXRs' pixels
/// in the white `restauro compare` takes, shown in the map's colour at that pixel.
#[test]
fn two_snapshots_chosen_in_the_strip_compare_over_the_whole_view() {
    if !available("studio_snapshots") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let farm = Coordinator::studio_farm(d, 160, 90);
    let c = &farm.coordinator;
    let found = submit(&farm.scene, &["--spp", "1", "--variant", "as-found"], &c.url, &farm.token);
    let cleaned = submit(&farm.scene, &["--spp", "1", "--variant", "cleaned"], &c.url, &farm.token);
    let mut b = Browser::launch(1280, 720);
    b.goto(&format!("{}#token={CLIENT_TOKEN}", farm.page));
    b.wait_for("both in the strip", "document.querySelectorAll('#strip-list li').length === 2");
    bad_pixels_are_refused(c, &found);
    b.click(&format!("#strip-list li[data-job='{found}'] .pick-a"));
    b.click(&format!("#strip-list li[data-job='{cleaned}'] .pick-b"));
    let pressed = |b: &mut Browser, job: &str, side: &str| {
        b.eval(&format!(
            "document.querySelector(\"#strip-list li[data-job='{job}'] .pick-{side}\").getAttribute('aria-pressed')"
        ))
    };
    assert_eq!(
        (pressed(&mut b, &found, "a"), pressed(&mut b, &cleaned, "b")),
        (json!("true"), json!("true"))
    );
    b.click("#strip-compare");
    b.wait_for("the statistics", "document.getElementById('compare-stats').dataset.mean");
    b.wait_for(
        "both images",
        "['compare-img-a', 'compare-img-b', 'compare-map'].every(id => { const i = document.getElementById(id); return i.complete && i.naturalWidth === 160; })",
    );
    // Over the whole view.
    assert_eq!(b.rect("#compare-viewport"), b.rect("#stage"));
    let (fa, fb) = (fetch(c, d, &farm.token, &found), fetch(c, d, &farm.token, &cleaned));
    let (a_png, b_png) = (
        png_rgb(&std::fs::read(file(&fa, ".png")).unwrap()).0,
        png_rgb(&std::fs::read(file(&fb, ".png")).unwrap()).0,
    );
    b.click("#compare-one");
    let rect = b.rect("#compare-img-a");
    assert_eq!((rect[2], rect[3]), (160.0, 90.0));
    let slide = |b: &mut Browser, v: u32| {
        b.eval(&format!(
            "(() => {{ const s = document.getElementById('compare-slider'); s.value = {v}; s.dispatchEvent(new Event('input')); }})()"
        ));
    };
    slide(&mut b, 100);
    let shown = pixels_in(&b.screenshot(&shots().join("64-compare-a.png")), rect);
    assert!(difference(&shown, &a_png) < 0.5, "A: {}", difference(&shown, &a_png));
    slide(&mut b, 0);
    let shown = pixels_in(&b.screenshot(&shots().join("65-compare-b.png")), rect);
    assert!(difference(&shown, &b_png) < 0.5, "B: {}", difference(&shown, &b_png));

    // The statistics are `restauro compare`'s.
    let (a_exr, b_exr) = (file(&fa, ".exr"), file(&fb, ".exr"));
    let cli = cli_compare(d, &a_exr, &b_exr, "a-b");
    let stats = b.eval("document.getElementById('compare-stats').textContent");
    let mean = cli["delta_e00"]["mean"].as_f64().unwrap();
    assert!(stats.as_str().unwrap().contains(&format!("mean {mean:.2}")), "{stats}: {cli}");

    the_delta_e_under_the_pointer_is_the_exrs(
        &mut b,
        c,
        &cli,
        [&a_exr, &b_exr],
        rect,
        [&found, &cleaned],
    );
}
/// The ΔE00 under the pointer, where the two snapshots differ most: the CIEDE2000 of the two
/// EXRs' pixels (`exrs`, A's and B's) in the white `restauro compare` took (`cli`, its
/// document), shown in the map's colour at that pixel. `rect`: the pictures at 1:1 on the page.
fn the_delta_e_under_the_pointer_is_the_exrs(
    b: &mut Browser,
    c: &Coordinator,
    cli: &Value,
    exrs: [&Path; 2],
    rect: [f64; 4],
    jobs: [&str; 2],
) {
    let ([a_exr, b_exr], [found, cleaned]) = (exrs, jobs);
    b.click("#compare-delta-here");
    let white = cli["white_luminance"].as_f64().unwrap();
    let (a, bb) = (exr(a_exr), exr(b_exr));
    let light = |m: &XyzImage, i: usize| m.emitter.as_ref().is_some_and(|e| e[i]);
    let lab = |p: [f32; 3]| {
        let [l, a, b] = cielab(p, white);
        restauro_spectral::Lab { l, a, b }
    };
    let delta =
        |i: usize| restauro_spectral::ciede2000::ciede2000(lab(a.pixels[i]), lab(bb.pixels[i]));
    let i = (0..160 * 90)
        .filter(|&i| !light(&a, i) && !light(&bb, i) && (10..80).contains(&(i / 160)))
        .max_by(|&i, &j| delta(i).total_cmp(&delta(j)))
        .unwrap();
    let (px, py) = (i % 160, i / 160);
    let said = point_at(
        b,
        "compare-readout",
        (rect[0] + px as f64 + 0.5, rect[1] + py as f64 + 0.5),
        (px, py),
    );
    let shot = b.screenshot(&shots().join("66-compare-readout.png"));
    let got = numbers_after(&said, "ΔE00 of B against A: ", 1)[0];
    assert!((got - delta(i)).abs() < 0.006, "{said}: CIEDE2000 of the EXRs {}", delta(i));
    assert!(got > 1.0, "the pixel differs little: {got}");
    // In the map's colour there, on the page.
    let auth = [("Authorization", "Bearer client-token-for-tests")];
    let studio = c.studio.as_deref().unwrap();
    let top = restauro_tests::http::request(
        studio,
        "GET",
        &format!("/api/compare?a={found}&b={cleaned}"),
        &auth,
        b"",
    )
    .json()["scale_max"]
        .as_f64()
        .unwrap();
    let want = restauro_image::delta_e::viridis(got / top);
    let (screen, sw) = png_rgb(&shot);
    let on_page = screen[(rect[1] as usize + py) * sw + rect[0] as usize + px];
    assert!(
        (0..3).all(|k| on_page[k].abs_diff(want[k]) <= 3),
        "{on_page:?} on the page, {want:?} for {got}"
    );
}
