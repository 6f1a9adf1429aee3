//! The studio in a real browser (headless Chromium, driven over CDP) against a real coordinator
//! and two workers: signing in, the farm as it stands, a render followed live and its image as
//! the page shows it. Screenshots of each step are written to `<target>/tmp/studio/`.

use restauro_tests::browser::{Browser, available, png_rgb};
use std::path::PathBuf;

/// Screenshots go to `<target>/tmp/studio/`.
fn shots() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("studio")
}
use restauro_tests::{CLIENT_TOKEN, Coordinator, Worker, aosta_scene, client, submit, text};

/// The mean of the RGB channels of a PNG file, 0–255.
fn png_mean(bytes: &[u8]) -> [f64; 3] {
    let (rgb, _) = png_rgb(bytes);
    let mut sum = [0.0; 3];
    for p in &rgb {
        for k in 0..3 {
            sum[k] += f64::from(p[k]);
        }
    }
    sum.map(|s| s / rgb.len() as f64)
}

/// The view's background (`#9fb4c8`, the page's sky colour), within rounding.
fn is_background(p: [u8; 3]) -> bool {
    p.iter().zip([0x9f, 0xb4, 0xc8]).all(|(&a, b): (&u8, i32)| (i32::from(a) - b).abs() <= 2)
}

#[test]
fn a_restorer_signs_in_follows_a_render_and_sees_its_image() {
    if !available("studio_browser") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (c, studio) = Coordinator::with_studio(d);
    let _workers =
        [Worker::start(d, &c.url, "local-1", &[]), Worker::start(d, &c.url, "local-2", &[])];
    let mut b = Browser::launch(1280, 720);
    sign_in_refused_then_accepted(&mut b, &studio);

    // A render sent from the command line appears, progresses and ends done.
    let scene = aosta_scene(d, 320, 180);
    let token = d.join("client.token");
    let id = submit(&scene, &["--spp", "2", "--tile", "32"], &c.url, &token);
    let row = format!("document.querySelector('#jobs tr[data-job=\"{id}\"]')");
    b.wait_for("the job's row", &row);
    b.wait_for("the job to finish", &format!("{row}.children[1].textContent === 'done'"));
    let o =
        client(&["fetch", &id, "--out", d.join("fetched-first").to_str().unwrap()], &c.url, &token);
    assert!(o.status.success(), "{}", text(&o));
    let progress = b.eval(&format!("{row}.children[2].textContent"));
    assert_eq!(progress, " 60/60 tiles", "{progress}");
    the_model_fills_the_view_below_the_sky(&mut b);
    the_clicked_stone_is_coloured_as_restauro_colours_it(&mut b, &scene);
    a_snapshot_is_the_cli_render_bit_for_bit(&mut b, &c, d, &token, &id);
    the_page_shows_the_png_the_farm_wrote(&mut b, &c, d, &token, &id);
    // `?` lists the keyboard shortcuts.
    b.press("?");
    b.wait_for("the shortcuts", "document.getElementById('shortcuts').open");
}

/// Without a session the page asks for the token; a wrong token is refused, in the server's
/// words; the right one opens the studio, where the farm's two workers are listed, live.
fn sign_in_refused_then_accepted(b: &mut Browser, studio: &str) {
    b.goto(studio);
    b.wait_for("the sign-in dialog", "document.getElementById('sign-in').open");
    b.screenshot(&shots().join("01-sign-in.png"));
    // A wrong token is refused, in the server's words.
    b.click("#token");
    b.type_text("not-the-token");
    b.click("#sign-in-form button[type=submit]");
    b.wait_for("the refusal", "document.getElementById('sign-in-error').textContent.length > 0");
    let said = b.eval("document.getElementById('sign-in-error').textContent");
    assert_eq!(said, "the client token is not valid", "{said}");
    assert_eq!(b.eval("document.getElementById('sign-in').open"), true);
    b.screenshot(&shots().join("02-wrong-token.png"));
    // The right one opens the studio: the farm's two workers are listed, live.
    b.eval("document.getElementById('token').value = ''");
    b.click("#token");
    b.type_text(CLIENT_TOKEN);
    b.press("Enter");
    b.wait_for("the dialog to close", "!document.getElementById('sign-in').open");
    b.wait_for("both workers", "document.querySelectorAll('#workers tbody tr').length === 2");
    let names = b.eval("[...document.querySelectorAll('#workers tbody tr td:first-child')].map(td => td.textContent)");
    assert_eq!(names, serde_json::json!(["local-1", "local-2"]));
    b.wait_for("the live status", "document.getElementById('connection').textContent === 'live'");
    assert_eq!(b.eval("document.getElementById('no-jobs').hidden"), false);
    b.screenshot(&shots().join("03-farm.png"));
}

/// The rendered scene is listed and drawn in real time from the scene's camera: the model
/// fills the middle of the view, the sky is above it.
fn the_model_fills_the_view_below_the_sky(b: &mut Browser) {
    b.wait_for("the scene in the picker", "document.getElementById('scene-picker').selectedOptions[0].textContent.startsWith('aosta')");
    b.wait_for("the model", "document.getElementById('view').dataset.scene");
    let shot = b.screenshot(&shots().join("04-scene.png"));
    let [x, y, w, h] = b.rect("#view");
    let (rgb, width) = png_rgb(&shot);
    let at = |fx: f64, fy: f64| rgb[(y + fy * h) as usize * width + (x + fx * w) as usize];
    assert!(!is_background(at(0.5, 0.5)), "the middle of the view is sky: {:?}", at(0.5, 0.5));
    assert!(is_background(at(0.5, 0.03)), "the top of the view is not sky: {:?}", at(0.5, 0.03));
    let model = (0..40 * 40)
        .filter(|i| {
            !is_background(at(
                0.1 + 0.8 * f64::from(i % 40) / 40.0,
                0.1 + 0.8 * f64::from(i / 40) / 40.0,
            ))
        })
        .count();
    assert!(model > 400, "the model covers only {model} of 1600 samples of the view");
}

/// A click on the facade names what is there and what it is made of; its base state's
/// L*a*b* under the sky's light alone (CIE daylight at 12 000 K in the `scene`) is the one
/// `restauro color` gives for the spectrum the scene binds it to.
fn the_clicked_stone_is_coloured_as_restauro_colours_it(b: &mut Browser, scene: &str) {
    b.click("#view");
    b.wait_for("the material panel", "!document.getElementById('material').hidden");
    let facts = b.eval(
        "[...document.querySelectorAll('#material .body > table:first-child tr')].map(r => [r.cells[0].textContent, r.cells[1].textContent])",
    );
    let fact = |name: &str| {
        facts
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f[0] == name)
            .map(|f| f[1].as_str().unwrap().to_owned())
    };
    assert_eq!(fact("Object").as_deref(), Some("facade"), "{facts}");
    let stone = fact("Material").unwrap();
    assert!(["travertine", "puddinga", "mortar"].contains(&stone.as_str()), "{facts}");
    let toml: toml::Table = toml::from_str(&std::fs::read_to_string(scene).unwrap()).unwrap();
    let alias = toml["materials"][stone.as_str()]["reflectance"].as_str().unwrap().to_owned();
    let library = toml["spectra"][alias.as_str()].as_str().unwrap().to_owned();
    b.eval(
        "(() => { const e = document.getElementById('preview-light'); e.value = 'spectrum:skylight'; \
         e.dispatchEvent(new Event('change')); })()",
    );
    let caption = b.eval("document.querySelector('#material table.states caption').textContent");
    assert!(caption.as_str().unwrap().starts_with("Under skylight (the sky alone)"), "{caption}");
    let o = restauro_tests::restauro(&["color", &library, "-i", "daylight:12000", "--json"]);
    let color: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let row = b.eval("[...document.querySelector('#material tr[data-state=base]').cells].map(c => c.textContent)");
    assert_eq!(row[1], alias.as_str(), "{row}");
    for (k, key) in ["l", "a", "b"].iter().enumerate() {
        let shown: f64 = row[3 + k].as_str().unwrap().parse().unwrap();
        let want = color["sample"]["lab"][key].as_f64().unwrap();
        assert!((shown - want).abs() <= 0.051, "{key}: shown {shown}, restauro color {want}");
    }
    assert_eq!(
        b.eval("document.querySelectorAll('#material svg.spectrum polyline').length"),
        row_count(b)
    );
    b.screenshot(&shots().join("05-material.png"));
}

/// A snapshot of the view as it stands (the scene's camera) renders on the farm and is shown
/// when done: the image the command line rendered of the scene (job `id`, fetched to
/// `d/fetched-first`), bit for bit (the camera's trip through the preview's coordinates is
/// exact).
fn a_snapshot_is_the_cli_render_bit_for_bit(
    b: &mut Browser,
    c: &Coordinator,
    d: &std::path::Path,
    token: &std::path::Path,
    id: &str,
) {
    b.eval("document.getElementById('snap-spp').value = 2");
    // The command line's render took every sample: so does this one.
    b.eval("document.getElementById('snap-noise').value = 0");
    assert_eq!(b.eval("document.getElementById('snap-width').value"), "320");
    assert_eq!(
        b.eval("[...document.getElementById('snap-variant').options].map(o => o.value)"),
        serde_json::json!(["", "as-found", "cleaned"])
    );
    b.click("#take-snapshot");
    b.wait_for("the snapshot's row", "document.querySelectorAll('#jobs tbody tr').length === 2");
    let snap = b.eval(&format!("[...document.querySelectorAll('#jobs tbody tr')].map(r => r.dataset.job).find(j => j !== '{id}')"));
    let snap = snap.as_str().unwrap().to_owned();
    b.wait_for(
        "the snapshot shown",
        &format!("(() => {{ const i = document.getElementById('result-image'); return i.src.includes('{snap}') && i.complete && i.naturalWidth === 320; }})()"),
    );
    b.screenshot(&shots().join("06-snapshot-taken.png"));
    let taken = d.join("taken");
    let o = client(&["fetch", &snap, "--out", taken.to_str().unwrap()], &c.url, token);
    assert!(o.status.success(), "{}", text(&o));
    let exr = |dir: &std::path::Path| {
        restauro_image::image_files::read_exr(
            &dir.join("aosta.exr"),
            restauro_image::image_files::MAX_PIXELS,
        )
        .unwrap()
        .pixels
    };
    let (a, r) = (exr(&taken), exr(&d.join("fetched-first")));
    assert_eq!(a.len(), r.len());
    let differing = a.iter().zip(&r).filter(|(p, q)| p != q).count();
    assert_eq!(differing, 0, "{differing} of {} pixels differ from the CLI render", a.len());
}

/// Job `id`'s image opened in the page is the PNG the farm wrote: the same mean colour, read
/// back from the image the page decoded. Then, as seen: the Retinex image.
fn the_page_shows_the_png_the_farm_wrote(
    b: &mut Browser,
    c: &Coordinator,
    d: &std::path::Path,
    token: &std::path::Path,
    id: &str,
) {
    b.click(&format!("#jobs tr[data-job=\"{id}\"] button"));
    b.wait_for(
        "the image",
        "(() => { const i = document.getElementById('result-image'); \
         return i.complete && i.naturalWidth === 320; })()",
    );
    b.screenshot(&shots().join("07-snapshot.png"));
    // What the page shows is the PNG the farm wrote: the same mean colour, read back from the
    // image the page decoded.
    let shown = b.eval(
        "(() => { const i = document.getElementById('result-image'); const c = document.createElement('canvas'); \
         c.width = i.naturalWidth; c.height = i.naturalHeight; const g = c.getContext('2d'); g.drawImage(i, 0, 0); \
         const d = g.getImageData(0, 0, c.width, c.height).data; const s = [0, 0, 0]; \
         for (let p = 0; p < d.length; p += 4) { s[0] += d[p]; s[1] += d[p + 1]; s[2] += d[p + 2]; } \
         return s.map(v => v / (c.width * c.height)); })()",
    );
    let out = d.join("fetched");
    let o = client(&["fetch", id, "--out", out.to_str().unwrap()], &c.url, token);
    assert!(o.status.success(), "{}", text(&o));
    let expected = png_mean(&std::fs::read(out.join("aosta.png")).unwrap());
    for k in 0..3 {
        let got = shown[k].as_f64().unwrap();
        assert!((got - expected[k]).abs() < 0.01, "channel {k}: page {got}, file {}", expected[k]);
    }
    assert!(expected.iter().sum::<f64>() > 30.0, "the render is not black: {expected:?}");
    // As seen: the Retinex image.
    b.click("#as-seen");
    b.wait_for(
        "the Retinex image",
        "(() => { const i = document.getElementById('result-image'); \
         return i.src.endsWith('aosta-retinex.png') && i.complete && i.naturalWidth === 320; })()",
    );
    assert_eq!(b.eval("document.getElementById('as-seen').getAttribute('aria-pressed')"), "true");
    b.screenshot(&shots().join("08-as-seen.png"));
}

/// The states listed in the material panel, as the number of rows.
fn row_count(b: &mut Browser) -> serde_json::Value {
    b.eval("document.querySelectorAll('#material tbody tr').length")
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

/// Moves the comparison's slider to `v` (100: all A, 0: all B).
fn slide(b: &mut Browser, v: u32) {
    b.eval(&format!(
        "(() => {{ const s = document.getElementById('compare-slider'); s.value = {v}; s.dispatchEvent(new Event('input')); }})()"
    ));
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

/// Two hypotheses compared in the page: the slider shows A at one end and B at the other, the
/// ΔE00 layer shows the server's map (the one `restauro compare` computes, see studio_api) with
/// its scale and statistics.
#[test]
fn a_restorer_compares_two_hypotheses_on_the_slider_and_the_delta_e_layer() {
    if !available("studio_browser") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let farm = Coordinator::studio_farm(d, 160, 90);
    let c = &farm.coordinator;
    let (studio, scene, token) = (farm.page.clone(), farm.scene.clone(), farm.token.clone());
    let found = submit(&scene, &["--spp", "1", "--variant", "as-found"], &c.url, &token);
    let cleaned = submit(&scene, &["--spp", "1", "--variant", "cleaned"], &c.url, &token);
    let mut b = Browser::launch(1280, 900);
    b.goto(&format!("{studio}#token={CLIENT_TOKEN}"));
    b.wait_for("both done", "document.getElementById('compare-b').options.length === 2");
    b.eval(&format!(
        "document.getElementById('compare-a').value = '{found}'; document.getElementById('compare-b').value = '{cleaned}'"
    ));
    b.click("#compare-go");
    b.wait_for("the statistics", "document.getElementById('compare-stats').dataset.mean");
    b.wait_for(
        "both images",
        "['compare-img-a', 'compare-img-b', 'compare-map'].every(id => { const i = document.getElementById(id); return i.complete && i.naturalWidth === 160; })",
    );
    let png_of = |job: &str| {
        let out = d.join(job);
        let o = client(&["fetch", job, "--out", out.to_str().unwrap()], &c.url, &token);
        assert!(o.status.success(), "{}", text(&o));
        let file = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| {
                p.extension().is_some_and(|x| x == "png")
                    && !p.to_string_lossy().contains("retinex")
            })
            .unwrap();
        png_rgb(&std::fs::read(file).unwrap()).0
    };
    let (a_png, b_png) = (png_of(&found), png_of(&cleaned));
    assert!(difference(&a_png, &b_png) > 2.0, "the hypotheses look alike");
    // Over the whole view, at 1:1: one image pixel to one screen pixel.
    b.click("#compare-one");
    let rect = b.rect("#compare-img-a");
    assert_eq!((rect[2], rect[3]), (160.0, 90.0), "shown at its own size");
    slide(&mut b, 100);
    let shown = pixels_in(&b.screenshot(&shots().join("21-compare-all-a.png")), rect);
    assert!(difference(&shown, &a_png) < 0.5, "slider at A: {}", difference(&shown, &a_png));
    slide(&mut b, 0);
    let shown = pixels_in(&b.screenshot(&shots().join("22-compare-all-b.png")), rect);
    assert!(difference(&shown, &b_png) < 0.5, "slider at B: {}", difference(&shown, &b_png));
    slide(&mut b, 50);
    b.screenshot(&shots().join("23-compare-half.png"));

    the_delta_e_layer_is_the_servers_map(&mut b, c, &found, &cleaned, rect);
    one_stop_brighter_then_in_false_colour(&mut b, c, &found, &a_png);
}

/// The ΔE00 layer in place of B (jobs `found` and `cleaned`), over `rect` of the page: the
/// server's map, its scale and its numbers.
fn the_delta_e_layer_is_the_servers_map(
    b: &mut Browser,
    c: &Coordinator,
    found: &str,
    cleaned: &str,
    rect: [f64; 4],
) {
    b.click("#compare-delta");
    slide(b, 0);
    let shown = pixels_in(&b.screenshot(&shots().join("24-compare-delta-e.png")), rect);
    let auth = [("Authorization", "Bearer client-token-for-tests")];
    let server = restauro_tests::http::request(
        c.studio.as_deref().unwrap(),
        "GET",
        &format!("/api/compare?a={found}&b={cleaned}"),
        &auth,
        b"",
    )
    .json();
    let map = restauro_tests::http::request(
        c.studio.as_deref().unwrap(),
        "GET",
        &format!("/api/compare/delta-e.png?a={found}&b={cleaned}"),
        &auth,
        b"",
    );
    let layer = png_rgb(&map.body).0;
    assert!(difference(&shown, &layer) < 0.5, "the layer shows {}", difference(&shown, &layer));
    let stats = b.eval("document.getElementById('compare-stats').textContent");
    let mean = server["delta_e00"]["mean"].as_f64().unwrap();
    assert!(stats.as_str().unwrap().contains(&format!("mean {mean:.2}")), "{stats}");
    let top = server["scale_max"].as_f64().unwrap();
    let label = b.eval(
        "[...document.querySelectorAll('#compare-scale text')].map(t => t.textContent).pop()",
    );
    assert_eq!(label, format!("{top} ΔE00"), "the scale's top");
}

/// A snapshot paints into the view as the farm renders it: while it runs, the picture over the
/// view holds whole tiles (opaque) where tiles are done and shows the preview through the rest
/// (transparent), with the progress and time left beside it; when it is done the picture goes
/// and the result is shown. The store is slowed (each commit 300 ms) so that it can be seen.
#[test]
fn a_snapshot_paints_into_the_view_tile_by_tile() {
    if !available("studio_browser") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let slow = ["--studio-listen", "127.0.0.1:0", "--fault-commit-delay-ms", "300"];
    let c = Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &slow);
    let _worker = Worker::start(d, &c.url, "local-1", &[]);
    let scene = aosta_scene(d, 160, 90);
    submit(&scene, &["--spp", "1", "--tile", "160"], &c.url, &d.join("client.token"));
    let mut b = Browser::launch(1280, 900);
    b.goto(&format!("http://{}/#token={CLIENT_TOKEN}", c.studio.as_deref().unwrap()));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    b.eval("document.getElementById('snap-spp').value = 1");
    b.click("#take-snapshot");
    b.wait_for(
        "a few tiles painted",
        "(() => { const i = document.getElementById('painting'); \
         return !i.hidden && i.complete && Number(i.dataset.tiles) >= 3; })()",
    );
    let caption = b.eval("document.getElementById('painting-progress').textContent");
    assert!(caption.as_str().unwrap().contains("/60 tiles, about"), "{caption}");
    let shown_tiles = b.eval("Number(document.getElementById('painting').dataset.tiles)");
    b.eval("document.getElementById('view').scrollIntoView()");
    b.screenshot(&shots().join("09-painting.png"));
    // Per tile (the snapshot's tiles: 16 px for 160 × 90), how many of its pixels are opaque,
    // and the spread of the opaque pixels' green.
    let edge = restauro_scene::plan::auto_tile(160, 90) as usize;
    // The picture is fetched again as tiles finish: read it when no fetch is under way (while
    // one is, the image has no pixels to read).
    let read_painting = format!(
        "(() => {{ const i = document.getElementById('painting'); \
         if (!i.complete || i.naturalWidth === 0) return null; const c = document.createElement('canvas'); \
         c.width = i.naturalWidth; c.height = i.naturalHeight; const g = c.getContext('2d'); g.drawImage(i, 0, 0); \
         const d = g.getImageData(0, 0, c.width, c.height).data; const tiles = {{}}; const greens = []; \
         for (let y = 0; y < c.height; y++) for (let x = 0; x < c.width; x++) {{ \
           const a = d[4 * (y * c.width + x) + 3]; const k = `${{Math.floor(x / {edge})}},${{Math.floor(y / {edge})}}`; \
           tiles[k] = tiles[k] || [0, 0]; tiles[k][a === 255 ? 0 : 1] += 1; \
           if (a !== 0 && a !== 255) return 'alpha ' + a; \
           if (a === 255) greens.push(d[4 * (y * c.width + x) + 1]); }} \
         const mean = greens.reduce((s, v) => s + v, 0) / greens.length; \
         const sd = Math.sqrt(greens.reduce((s, v) => s + (v - mean) ** 2, 0) / greens.length); \
         return [c.width, c.height, Object.values(tiles), sd]; }})()"
    );
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    let read = loop {
        let read = b.eval(&read_painting);
        if !read.is_null() || std::time::Instant::now() > deadline {
            break read;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    assert_eq!((read[0].as_u64(), read[1].as_u64()), (Some(160), Some(90)), "{read}");
    let tiles = read[2].as_array().unwrap();
    assert_eq!(tiles.len(), 60);
    let opaque = tiles.iter().filter(|t| t[1] == 0).count();
    let transparent = tiles.iter().filter(|t| t[0] == 0).count();
    assert_eq!(opaque + transparent, 60, "a tile is partly painted: {tiles:?}");
    let shown_tiles = shown_tiles.as_u64().unwrap() as usize;
    assert!((shown_tiles..60).contains(&opaque), "{opaque} tiles painted, {shown_tiles} done");
    assert!(read[3].as_f64().unwrap() > 5.0, "the painted tiles show the model: {read}");
    // Done: the picture goes, the result takes its place.
    b.wait_for(
        "the result",
        "document.getElementById('painting').hidden && !document.getElementById('result').hidden",
    );
    assert_eq!(b.eval("document.getElementById('painting-progress').hidden"), true);
}

/// One snapshot (job `found`) shown one stop brighter: the server's picture at half the
/// automatic white, as the page shows it (brighter than the farm's PNG, `a_png`); then in
/// false colour, with its scale in cd/m².
fn one_stop_brighter_then_in_false_colour(
    b: &mut Browser,
    c: &Coordinator,
    found: &str,
    a_png: &[[u8; 3]],
) {
    let auth = [("Authorization", "Bearer client-token-for-tests")];
    b.click(&format!("#jobs tr[data-job=\"{found}\"] button"));
    b.wait_for("the snapshot's luminances", "document.getElementById('fc-max').value !== ''");
    b.eval("(() => { const e = document.getElementById('exposure-ev'); e.value = 1; e.dispatchEvent(new Event('input')); })()");
    b.wait_for(
        "one stop brighter",
        "(() => { const i = document.getElementById('result-image'); return i.src.includes('display.png') && i.complete && i.naturalWidth === 160; })()",
    );
    assert_eq!(b.eval("document.getElementById('exposure-shown').textContent"), "+1 EV");
    let src = b.eval("new URL(document.getElementById('result-image').src).pathname + new URL(document.getElementById('result-image').src).search");
    // The layer over the view at 1:1: one image pixel to one screen pixel.
    b.click("#result-one");
    let rect = b.rect("#result-image");
    assert_eq!((rect[2], rect[3]), (160.0, 90.0), "1:1");
    let shown = pixels_in(&b.screenshot(&shots().join("25-one-stop-brighter.png")), rect);
    let served = restauro_tests::http::request(
        c.studio.as_deref().unwrap(),
        "GET",
        src.as_str().unwrap(),
        &auth,
        b"",
    );
    assert!(difference(&shown, &png_rgb(&served.body).0) < 0.5, "the page shows another picture");
    assert!(difference(&shown, a_png) > 2.0, "no brighter than the farm's PNG");
    b.click("#false-colour");
    b.wait_for(
        "false colour",
        "(() => { const i = document.getElementById('result-image'); return i.src.includes('luminance.png') && i.complete && i.naturalWidth === 160; })()",
    );
    let unit =
        b.eval("[...document.querySelectorAll('#fc-scale text')].map(t => t.textContent).pop()");
    assert_eq!(unit, "cd/m²");
    b.screenshot(&shots().join("26-false-colour.png"));
}

/// A scene folder opened from the page: a `.tar` of it chosen in the dialog is sent, checked and
/// opened in the view; and the tar the page itself packs of a picked folder holds each file
/// under its path in the folder (long paths too), as a tar reader reads it.
#[test]
fn a_scene_folder_is_opened_from_the_page() {
    if !available("studio_browser") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let farm = Coordinator::studio_farm(d, 160, 90);
    let c = &farm.coordinator;
    let first = submit(&farm.scene, &["--spp", "1"], &c.url, &farm.token);
    let mut b = farm.page_in_browser(1280, 900);
    let old = b.eval("document.getElementById('view').dataset.scene");

    // Another scene: the same facade under an overcast sky, as a tar of its folder.
    let folder = std::path::Path::new(&farm.scene).parent().unwrap();
    let toml = std::fs::read_to_string(&farm.scene).unwrap();
    let overcast = toml.replace("preset = \"clear\"", "preset = \"overcast\"");
    assert_ne!(overcast, toml);
    let other = d.join("overcast");
    std::fs::create_dir_all(other.join("meshes")).unwrap();
    std::fs::write(other.join("scene.toml"), overcast).unwrap();
    std::fs::copy(folder.join("meshes/facade.obj"), other.join("meshes/facade.obj")).unwrap();
    let mut t = tar::Builder::new(Vec::new());
    t.append_dir_all("overcast", &other).unwrap();
    let archive = d.join("overcast.tar");
    std::fs::write(&archive, t.into_inner().unwrap()).unwrap();

    b.click("#open-folder");
    b.wait_for("the dialog", "document.getElementById('open-folder-dialog').open");
    b.screenshot(&shots().join("27-open-folder.png"));
    b.choose_file("#upload-archive", &archive);
    b.wait_for(
        "the new scene in the view",
        &format!("(() => {{ const v = document.getElementById('view').dataset.scene; return v && v !== {old}; }})()"),
    );
    let picked = b.eval("document.getElementById('scene-picker').selectedOptions[0].textContent");
    assert!(picked.as_str().unwrap().starts_with("overcast"), "{picked}");
    assert_eq!(b.eval("document.getElementById('open-folder-dialog').open"), false);
    let row =
        b.eval("[...document.querySelectorAll('#jobs tbody tr')].map(r => r.cells[0].textContent)");
    assert!(row.as_array().unwrap().iter().any(|n| n == "overcast"), "{row} {first}");

    // The page's own tar of a picked folder.
    let long = format!("overcast/{}facade.obj", "very-long-folder-name/".repeat(6));
    let bytes = b.eval(&format!(
        "import('/static/upload.js').then(m => Array.from(m.tarOf([\
           {{ name: 'overcast/scene.toml', bytes: new TextEncoder().encode('format = 1\\n') }}, \
           {{ name: '{long}', bytes: new Uint8Array(1000).fill(7) }}])))"
    ));
    let bytes: Vec<u8> = serde_json::from_value(bytes).unwrap();
    let mut read = Vec::new();
    for entry in tar::Archive::new(bytes.as_slice()).entries().unwrap() {
        let mut entry = entry.unwrap();
        let name = entry.path().unwrap().to_string_lossy().into_owned();
        let mut data = Vec::new();
        std::io::Read::read_to_end(&mut entry, &mut data).unwrap();
        read.push((name, data));
    }
    assert_eq!(read.len(), 2);
    assert_eq!(read[0], ("overcast/scene.toml".to_owned(), b"format = 1\n".to_vec()));
    assert_eq!(read[1], (long, vec![7u8; 1000]));
}

/// The view's canvas, drawn now, shrunk to 64 × 36 pixels (RGB).
fn view_pixels(b: &mut Browser) -> Vec<[u8; 3]> {
    view_pixels_at(b, 64, 36)
}

/// The view's canvas, drawn now, shrunk to `width × height` pixels (RGB), rows from the top.
fn view_pixels_at(b: &mut Browser, width: u32, height: u32) -> Vec<[u8; 3]> {
    let read = b.eval(&format!(
        "(() => {{ const v = window.studioViewer; v.draw(); \
         const t = document.createElement('canvas'); t.width = {width}; t.height = {height}; \
         const g = t.getContext('2d'); g.drawImage(v.canvas, 0, 0, {width}, {height}); \
         return Array.from(g.getImageData(0, 0, {width}, {height}).data); }})()"
    ));
    let bytes: Vec<u8> = serde_json::from_value(read).unwrap();
    bytes.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect()
}

/// A model of more than 200 000 triangles is drawn from its coarse copy while a drag moves the
/// view, and from itself again when the drag ends; the two look alike (the same surface, a few
/// grey levels apart on average), and a click still finds the surface.
#[test]
fn a_big_model_is_drawn_coarse_while_the_view_moves() {
    if !available("studio_browser") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 330 × 330 quads: 217 800 triangles.
    let (_c, page, _worker) = restauro_tests::relief::relief_studio(d, 330, 330);
    let mut b = Browser::launch(1280, 720);
    b.goto(&format!("{page}#token={CLIENT_TOKEN}"));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    let status = b.eval("document.getElementById('scene-status').textContent");
    assert!(status.as_str().unwrap().contains("217,800 triangles ("), "{status}");
    assert!(status.as_str().unwrap().contains("while moving)"), "{status}");
    b.eval("document.getElementById('view').scrollIntoView({ block: 'center' })");
    let still = view_pixels(&mut b);
    let relief = still.iter().filter(|p| !is_background(**p)).count();
    assert!(relief > still.len() / 10, "the relief covers {relief} of {} pixels", still.len());

    // A drag: pressed, moved a little, and held.
    let [x, y, w, h] = b.rect("#view");
    let (x, y) = (x + w / 2.0, y + h / 2.0);
    let mouse = |b: &mut Browser, kind: &str, dx: f64| {
        b.call(
            "Input.dispatchMouseEvent",
            serde_json::json!({ "type": kind, "x": x + dx, "y": y, "button": "left", "buttons": 1, "clickCount": 1 }),
        );
    };
    mouse(&mut b, "mousePressed", 0.0);
    mouse(&mut b, "mouseMoved", 1.0);
    let shown = "[window.studioViewer.model.visible, window.studioViewer.coarse.visible]";
    assert_eq!(b.eval(shown), serde_json::json!([false, true]), "the coarse copy while dragging");
    let moving = view_pixels(&mut b);
    b.screenshot(&shots().join("40-big-model-moving.png"));
    mouse(&mut b, "mouseReleased", 1.0);
    assert_eq!(b.eval(shown), serde_json::json!([true, false]), "the model itself when still");
    let differing: f64 = still
        .iter()
        .zip(&moving)
        .map(|(a, b)| (0..3).map(|k| f64::from(a[k].abs_diff(b[k]))).sum::<f64>() / 3.0)
        .sum::<f64>()
        / still.len() as f64;
    assert!(
        differing < 12.0,
        "the coarse copy differs from the model by {differing:.1} grey levels a pixel"
    );
    // A click still finds the surface under it.
    b.click("#view");
    b.wait_for("the surface clicked", "!document.getElementById('material').hidden");
}

/// The spread of the hue of the view's pixels (`width` to a row) in columns `columns`, away
/// from the background (the pixel and its eight neighbours are the model's) and from the
/// darkest: the standard deviation of green over red, over its mean. Shading scales all three
/// alike and leaves it; lichen and rust move it.
fn hue_spread_in(pixels: &[[u8; 3]], width: usize, columns: std::ops::Range<usize>) -> f64 {
    let at = |x: usize, y: usize| pixels.get(y * width + x).copied().unwrap_or([0x9f, 0xb4, 0xc8]);
    let inside = |x: usize, y: usize| {
        (x.saturating_sub(1)..=x + 1)
            .all(|a| (y.saturating_sub(1)..=y + 1).all(|b| !is_background(at(a, b))))
    };
    let hue: Vec<f64> = (0..pixels.len())
        .map(|i| (i % width, i / width))
        .filter(|&(x, y)| {
            columns.contains(&x) && x > 0 && y > 0 && inside(x, y) && at(x, y)[0] > 60
        })
        .map(|(x, y)| f64::from(at(x, y)[1]) / f64::from(at(x, y)[0]))
        .collect();
    assert!(hue.len() > 200, "{} pixels of the patch in columns {columns:?}", hue.len());
    let mean = hue.iter().sum::<f64>() / hue.len() as f64;
    (hue.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / hue.len() as f64).sqrt() / mean
}

/// A laser scan's vertex colours and a photogrammetry export's photo show in the studio's view
/// as they will in a snapshot: the patch as a coloured PLY on the left and as a textured glb in
/// the middle, both with chromatic detail, and the PLY again on the right with
/// `detail = "none"`; the first two show the lichen and the rust, the third one hue, shaded.
#[test]
fn a_scans_photo_and_vertex_colours_show_in_the_view() {
    if !available("studio_browser") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let folder = d.join("scan");
    std::fs::create_dir_all(&folder).unwrap();
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scans");
    std::fs::copy(data.join("weathered-patch.ply"), folder.join("patch.ply")).unwrap();
    std::fs::copy(data.join("weathered-patch.glb"), folder.join("patch.glb")).unwrap();
    let toml = "format = 1\n[camera]\nposition = [0.0, -1.6, 0.0]\ntarget = [0.0, 0.0, 0.0]\nvertical_fov_deg = 30.0\nwidth = 160\nheight = 90\n\
        [spectra]\nday = { illuminant = \"D65\" }\ntravertine = \"travertine_tufa_solid__eco_ward73\"\n\
        [materials.coloured]\nmodel = \"lambert\"\nreflectance = \"travertine\"\ndetail = \"chromatic\"\n\
        [materials.plain]\nmodel = \"lambert\"\nreflectance = \"travertine\"\ndetail = \"none\"\n\
        [[objects]]\nname = \"coloured\"\nmesh = \"patch.ply\"\nup_axis = \"y\"\nmaterial = \"coloured\"\ntransform = { translate = [-0.6, 0.0, 0.0] }\n\
        [[objects]]\nname = \"photo\"\nmesh = \"patch.glb\"\nmaterial = \"coloured\"\n\
        [[objects]]\nname = \"plain\"\nmesh = \"patch.ply\"\nup_axis = \"y\"\nmaterial = \"plain\"\ntransform = { translate = [0.6, 0.0, 0.0] }\n\
        [[lights]]\nkind = \"sun\"\nilluminance_lux = 50000.0\nazimuth_deg = 190.0\nelevation_deg = 35.0\nspectrum = \"day\"\n";
    std::fs::write(folder.join("scene.toml"), toml).unwrap();
    let (c, page) = Coordinator::with_studio(d);
    let _worker = Worker::start(d, &c.url, "local-1", &[]);
    let scene = folder.join("scene.toml");
    submit(scene.to_str().unwrap(), &["--spp", "1"], &c.url, &d.join("client.token"));
    let mut b = Browser::launch(1280, 720);
    b.goto(&format!("{page}#token={CLIENT_TOKEN}"));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    b.eval("document.getElementById('view').scrollIntoView({ block: 'center' })");
    let pixels = view_pixels_at(&mut b, 256, 144);
    b.screenshot(&shots().join("45-vertex-colours.png"));
    // What each part carries: the photo as its map, the colours as vertex colours.
    let carried = b.eval(
        "(() => { const out = {}; window.studioViewer.model.traverse((o) => { if (o.isMesh) \
         out[o.name] = [o.material.map ? o.material.map.image.width : 0, o.material.vertexColors]; }); \
         return out; })()",
    );
    assert_eq!(
        carried,
        serde_json::json!({ "coloured": [0, true], "photo": [256, false], "plain": [0, false] })
    );
    let spread = |columns| hue_spread_in(&pixels, 256, columns);
    let (coloured, photo, plain) = (spread(0..96), spread(96..160), spread(160..256));
    eprintln!("hue spread: {coloured:.3} (colours), {photo:.3} (photo), {plain:.3} (neither)");
    assert!(coloured > 3.0 * plain, "hue spread {coloured} with the colours, {plain} without");
    assert!(photo > 3.0 * plain, "hue spread {photo} with the photo, {plain} without");
}

/// The share of the window the view's canvas covers (its rectangle within the window's).
fn view_share(b: &mut Browser) -> f64 {
    let share = b.eval(
        "(() => { const r = document.getElementById('view').getBoundingClientRect(); \
         const w = Math.max(0, Math.min(r.right, innerWidth) - Math.max(r.left, 0)); \
         const h = Math.max(0, Math.min(r.bottom, innerHeight) - Math.max(r.top, 0)); \
         return w * h / (innerWidth * innerHeight); })()",
    );
    share.as_f64().unwrap()
}

/// Whether the page itself scrolls (in either direction).
fn page_scrolls(b: &mut Browser) -> bool {
    b.eval(
        "(() => { const s = document.scrollingElement; \
         return s.scrollHeight > innerHeight || s.scrollWidth > innerWidth; })()",
    ) == serde_json::json!(true)
}

/// Waits until the view's renderer and camera follow the canvas's size on the page.
fn view_follows_its_size(b: &mut Browser) {
    b.wait_for(
        "the renderer and camera to follow the canvas",
        "(() => { const v = window.studioViewer, r = v.canvas.getBoundingClientRect(); \
         const ratio = v.renderer.getPixelRatio(); \
         return Math.abs(v.camera.aspect - r.width / r.height) < 1e-3 && \
           Math.abs(v.canvas.width - Math.floor(r.width * ratio)) <= 1; })()",
    );
}

/// The model in the whole window: at 1280 × 720 and at 1920 × 1080 the view covers most of the
/// window with the panels beside it and all of it with them folded away (P), the page itself
/// never scrolls, each panel's header folds and unfolds its body, a panel's key (1–6) brings
/// it back into sight, and Esc closes what shows over the view.
#[test]
fn the_model_has_the_whole_window_and_the_panels_fold_beside_it() {
    if !available("studio_browser") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The scene is held as soon as it is sent: no worker is needed to open it.
    let (c, page) = Coordinator::with_studio(d);
    let scene = aosta_scene(d, 160, 90);
    submit(&scene, &["--spp", "1"], &c.url, &d.join("client.token"));
    let mut b = Browser::launch(1280, 720);
    b.goto(&format!("{page}#token={CLIENT_TOKEN}"));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    let heads: Vec<String> = serde_json::from_value(b.eval(
        "[...document.querySelectorAll('#sidebar .panel-head button')].map(b => b.getAttribute('aria-controls'))",
    ))
    .unwrap();
    assert_eq!(heads.len(), 6, "{heads:?}");
    let listed = b.eval("document.getElementById('shortcuts').textContent");
    for key in ["P", "1", "2", "3", "4", "5", "6"] {
        let shown = b.eval(&format!(
            "[...document.querySelectorAll('#shortcuts kbd')].some(k => k.textContent === '{key}')"
        ));
        assert_eq!(shown, true, "{key} is not among the shortcuts: {listed}");
    }
    for (w, h) in [(1280u32, 720u32), (1920, 1080)] {
        the_panels_fold_at(&mut b, w, h, &heads);
    }

    // Esc closes what shows over the view, the one in front first.
    b.eval("document.getElementById('compare-stage').hidden = false");
    b.eval("document.getElementById('result').hidden = false");
    b.press("Escape");
    assert_eq!(
        b.eval("[document.getElementById('result').hidden, document.getElementById('compare-stage').hidden]"),
        serde_json::json!([true, false])
    );
    b.click("#compare-close");
    assert_eq!(b.eval("document.getElementById('compare-stage').hidden"), true);
}

/// At a `w × h` window: the view covers most of it with the panels open and all of it with the
/// side bar folded, the page never scrolls, each panel (`heads`: their bodies' ids) folds and
/// opens under its header, and P and a panel's key do what the shortcuts say.
fn the_panels_fold_at(b: &mut Browser, w: u32, h: u32, heads: &[String]) {
    let visible = |b: &mut Browser, id: &str| {
        b.eval(&format!("document.getElementById('{id}').checkVisibility()")) == true
    };
    b.window_size(w, h);
    view_follows_its_size(b);
    let open = view_share(b);
    assert!(open >= 0.6, "{w} × {h}: the view covers {:.0} % with the panels open", open * 100.0);
    assert!(!page_scrolls(b), "{w} × {h}: the page scrolls");
    let sideways = "(() => { const p = document.getElementById('panels'); return p.scrollWidth > p.clientWidth; })()";
    let wide = "(() => { const r = document.getElementById('panels').getBoundingClientRect().right; \
                return [...document.querySelectorAll('#panels *')].filter(e => e.getBoundingClientRect().right > r + 0.5) \
                  .map(e => e.id || e.tagName).slice(0, 8); })()";
    assert_eq!(
        b.eval(sideways),
        false,
        "{w} × {h}: the panels are wider than the side bar: {}",
        b.eval(wide)
    );
    b.screenshot(&shots().join(format!("50-window-{w}x{h}.png")));

    // Each panel's header folds its body and unfolds it again.
    for body in heads {
        let head = format!("#sidebar .panel-head button[aria-controls='{body}']");
        let expanded = format!("document.querySelector(\"{head}\").getAttribute('aria-expanded')");
        assert_eq!(b.eval(&expanded), "true", "{body}");
        assert!(visible(b, body), "{body} is not shown");
        b.click(&head);
        assert_eq!(b.eval(&expanded), "false", "{body}");
        assert!(!visible(b, body), "{body} is still shown, folded");
        assert!(!page_scrolls(b), "{w} × {h}: the page scrolls, {body} folded");
        b.click(&head);
        assert_eq!(b.eval(&expanded), "true", "{body}");
        assert!(visible(b, body), "{body} is not shown again");
    }

    // P folds the side bar away: the view has the whole window; P again brings it back.
    b.press("p");
    b.wait_for("the side bar folded", "!document.getElementById('sidebar').checkVisibility()");
    assert_eq!(
        b.eval("document.getElementById('sidebar-toggle').getAttribute('aria-expanded')"),
        "false"
    );
    view_follows_its_size(b);
    let folded = view_share(b);
    assert!(folded > 0.99, "{w} × {h}: the view covers {:.0} % folded", folded * 100.0);
    assert!(!page_scrolls(b), "{w} × {h}: the page scrolls, folded");
    b.screenshot(&shots().join(format!("51-window-{w}x{h}-folded.png")));
    b.press("p");
    b.wait_for("the side bar back", "document.getElementById('sidebar').checkVisibility()");
    view_follows_its_size(b);
    assert!((view_share(b) - open).abs() < 1e-9, "{w} × {h}: not as it was");

    // A panel's key, the side bar folded: the side bar opens, scrolled to that panel, its
    // header focused; the key again folds it, and once more opens it.
    b.press("p");
    b.wait_for("the side bar folded", "!document.getElementById('sidebar').checkVisibility()");
    b.press("6");
    b.wait_for("the side bar back", "document.getElementById('sidebar').checkVisibility()");
    let in_sight = b.eval(
        "(() => { const p = document.getElementById('panels').getBoundingClientRect(), \
         h = document.getElementById('farm').getBoundingClientRect(); \
         return document.activeElement.getAttribute('aria-controls') === 'farm-body' && \
           h.top >= p.top - 1 && h.top < p.bottom; })()",
    );
    assert_eq!(in_sight, true, "{w} × {h}: the farm is not in sight after its key");
    b.press("6");
    assert!(!visible(b, "farm-body"), "{w} × {h}: 6 did not fold the farm");
    b.press("6");
    assert!(visible(b, "farm-body"), "{w} × {h}: 6 did not open the farm");
    b.screenshot(&shots().join(format!("52-window-{w}x{h}-farm.png")));
    // The light panel, open but scrolled out of sight: its key brings it into sight.
    b.press("3");
    let light = "(() => { const p = document.getElementById('panels').getBoundingClientRect(), \
                 h = document.getElementById('light-panel').getBoundingClientRect(); \
                 return document.getElementById('light').checkVisibility() && h.top >= p.top - 1 && h.top < p.bottom; })()";
    assert_eq!(b.eval(light), true, "{w} × {h}: 3 did not bring the light panel into sight");
    b.screenshot(&shots().join(format!("53-window-{w}x{h}-light.png")));
}
