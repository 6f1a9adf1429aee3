//! Editing a scene in the studio, in a real browser against a real coordinator: a stone's
//! spectrum swapped for another shipped one (the panel and the real-time view change as the
//! spectra say they must), the sun set by date and time on its day's path, a view saved and
//! flown to, an earlier revision opened again, and a refused edit shown in the server's words.
//! Screenshots in `<target>/tmp/studio/`.

use restauro_image::image_files::{MAX_PIXELS, read_exr};
use restauro_tests::browser::{Browser, available, png_rgb};
use std::path::PathBuf;

/// Screenshots go to `<target>/tmp/studio/`.
fn shots() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("studio")
}
use restauro_tests::{CLIENT_TOKEN, Coordinator, client, download_shown, submit, text};

/// IEC 61966-2-1: an 8-bit sRGB value to linear.
fn linear(v: u8) -> f64 {
    let c = f64::from(v) / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// The linear RGB of the 21 × 21 pixels the view draws around the point last clicked (the view
/// may have moved since), read from the view's canvas right after it draws (a screenshot, saved
/// as `name` for people, is resampled when the page puts the canvas at a fraction of a pixel).
fn around_pick(b: &mut Browser, name: &str) -> Vec<[f64; 3]> {
    b.eval("document.getElementById('view').scrollIntoView({ block: 'nearest' })");
    b.screenshot(&shots().join(name));
    let read = b.eval(
        "(() => { const v = window.studioViewer, c = v.canvas; v.draw(); \
         const q = v.picked.clone().project(v.camera); \
         const x = Math.round((q.x + 1) / 2 * c.width), y = Math.round((1 - q.y) / 2 * c.height); \
         const t = document.createElement('canvas'); t.width = 21; t.height = 21; \
         const g = t.getContext('2d'); g.drawImage(c, x - 10, y - 10, 21, 21, 0, 0, 21, 21); \
         return Array.from(g.getImageData(0, 0, 21, 21).data); })()",
    );
    let bytes: Vec<u8> = serde_json::from_value(read).unwrap();
    bytes.chunks_exact(4).map(|p| [linear(p[0]), linear(p[1]), linear(p[2])]).collect()
}

/// Per channel, the median of after/before over the pixels whose colour changed: those of the
/// edited material (a click may land on the edge of a block, so a window is read, and the
/// pixels of other materials, which do not change, are left out).
fn scaled(before: &[[f64; 3]], after: &[[f64; 3]]) -> [f64; 3] {
    let changed: Vec<usize> = (0..before.len())
        .filter(|&i| (0..3).any(|k| (after[i][k] - before[i][k]).abs() > 0.01))
        .collect();
    assert!(changed.len() >= 40, "only {} pixels changed around the click", changed.len());
    std::array::from_fn(|k| {
        let mut r: Vec<f64> = changed.iter().map(|&i| after[i][k] / before[i][k]).collect();
        r.sort_by(f64::total_cmp);
        r[r.len() / 2]
    })
}

/// `restauro color`'s linear sRGB and L*a*b* of a shipped spectrum under D65.
fn restauro_colour(spectrum: &str) -> ([f64; 3], [f64; 3]) {
    let o = restauro_tests::restauro(&["color", spectrum, "--json"]);
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rgb = std::array::from_fn(|k| c["sample"]["rgb_linear"][k].as_f64().unwrap());
    let lab = ["l", "a", "b"].map(|k| c["sample"]["lab"][k].as_f64().unwrap());
    (rgb, lab)
}

/// The material panel shows `lab` (what `restauro color` gives under `light`) for the base
/// state, to the 0.1 it prints.
fn base_lab_is(b: &mut Browser, lab: [f64; 3], light: &str) {
    let row = b.eval("[...document.querySelector('#material tr[data-state=base]').cells].map(c => c.textContent)");
    for k in 0..3 {
        let shown: f64 = row[3 + k].as_str().unwrap().parse().unwrap();
        assert!(
            (shown - lab[k]).abs() <= 0.051,
            "L*a*b*[{k}] under {light}: shown {shown}, restauro color {}",
            lab[k]
        );
    }
}

fn set_value(b: &mut Browser, id: &str, value: &str) {
    b.eval(&format!(
        "(() => {{ const e = document.getElementById('{id}'); e.value = {value:?}; \
         e.dispatchEvent(new Event('input')); e.dispatchEvent(new Event('change')); }})()"
    ));
}

/// Clicks `button` and finds the edit refused: the page shows the server's words, with
/// `words` among them, beside the button, and stays at revision `revision`.
fn refused(b: &mut Browser, button: &str, words: &str, revision: &str) {
    b.click(button);
    let problem = b.refusal_beside(button);
    assert!(problem.contains(words), "{problem}");
    assert_eq!(b.eval("document.getElementById('view').dataset.revision"), revision);
}

/// The studio with the Aosta scene (160 × 90 px) rendered once, open in a browser signed in:
/// the farm, the browser and the first job.
fn opened(d: &std::path::Path) -> (restauro_tests::StudioFarm, Browser, String) {
    let farm = Coordinator::studio_farm(d, 160, 90);
    let c = &farm.coordinator;
    let first = submit(&farm.scene, &["--spp", "1", "--tile", "32"], &c.url, &farm.token);
    let mut b = Browser::launch(1280, 900);
    b.goto(&format!("{}#token={CLIENT_TOKEN}", farm.page));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    (farm, b, first)
}

#[test]
fn a_restorer_swaps_a_stone_sets_the_sun_and_keeps_a_view() {
    if !available("studio_editing") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (farm, mut b, first) = opened(d);
    let c = &farm.coordinator;
    let (scene, token) = (farm.scene.clone(), farm.token.clone());
    b.wait_for("the sun's path", "document.querySelector('#sun-chart svg polyline')");

    let (before, old) = click_the_stone_under_d65(&mut b, &scene);
    let brick = "brick_building_darkred__usgs_GDS350";
    let (brick_rgb, after) = assign_the_brick_and_check_the_view(&mut b, brick, &before, &old);
    colour_the_brick_under_the_sun(&mut b, d, brick, brick_rgb, &after);
    snapshot_is_the_cli_render_of_the_download(&mut b, c, d, &token, &first);
    set_the_sun_after_sunset(&mut b);
    save_a_view_and_fly_to_it(&mut b);
    open_revision_0_again(&mut b, brick);
    walk_until_the_buttress_stops_the_walker(&mut b);
}

/// The page colours under the scene's own daylight first; D65 is chosen, as `restauro
/// color`'s, and the facade clicked: the view's colours around the click, and the spectrum the
/// clicked stone's reflectance names in `scene`.
fn click_the_stone_under_d65(b: &mut Browser, scene: &str) -> (Vec<[f64; 3]>, String) {
    let lights = b.eval("[...document.getElementById('preview-light').options].map(o => o.value)");
    assert_eq!(
        lights,
        serde_json::json!(["scene", "spectrum:sunlight", "spectrum:skylight", "cie:D65"])
    );
    set_value(b, "preview-light", "cie:D65");
    // Click the facade; the material panel opens with the controls that change it.
    b.click("#view");
    b.wait_for("the material editor", "document.getElementById('material-search')");
    // (The panel narrows the view: the colour before is read with it open.)
    let before = around_pick(b, "11-edit-before.png");
    let stone =
        b.eval("document.querySelector('#material .body > table tr:nth-child(3) td').textContent");
    let stone = stone.as_str().unwrap().to_owned();
    let toml: toml::Table = toml::from_str(&std::fs::read_to_string(scene).unwrap()).unwrap();
    let alias = toml["materials"][stone.as_str()]["reflectance"].as_str().unwrap().to_owned();
    let old = toml["spectra"][alias.as_str()].as_str().unwrap().to_owned();
    (before, old)
}

/// Searches the shipped spectra, chooses a red brick and assigns it to the base state: the
/// panel gives its L*a*b*, and the view's stone scales per channel as the colours restauro
/// computes for `old` and the brick do. The brick's linear sRGB and the view's colours after.
fn assign_the_brick_and_check_the_view(
    b: &mut Browser,
    brick: &str,
    before: &[[f64; 3]],
    old: &str,
) -> ([f64; 3], Vec<[f64; 3]>) {
    set_value(b, "material-search", "brick darkred");
    let listed =
        b.eval("[...document.getElementById('material-spectrum').options].map(o => o.value)");
    assert_eq!(listed, serde_json::json!([brick]), "{listed}");
    set_value(b, "material-spectrum", brick);
    b.wait_for(
        "the candidate plotted",
        "document.querySelector('#material polyline.state-candidate')",
    );
    b.click("#material-assign");
    b.wait_for("revision 1", "document.getElementById('view').dataset.revision === '1'");
    b.wait_for(
        "the panel redrawn",
        &format!("document.querySelector('#material tr[data-state=base]').cells[1].textContent === '{brick}'"),
    );
    let (brick_rgb, brick_lab) = restauro_colour(brick);
    base_lab_is(b, brick_lab, "D65");
    // The real-time view shades the stone with its new colour under the same light: each
    // channel of the clicked surface scales as the colours restauro computes do.
    let after = around_pick(b, "12-edit-after.png");
    let (old_rgb, _) = restauro_colour(old);
    let expected: Vec<f64> = (0..3).map(|k| brick_rgb[k] / old_rgb[k]).collect();
    let seen = scaled(before, &after);
    for k in 0..3 {
        assert!(
            (seen[k] / expected[k] - 1.0).abs() < 0.05,
            "channel {k}: the view's colour scaled by {:.3}, the spectra say {:.3}",
            seen[k],
            expected[k]
        );
    }
    assert!(seen[0] / seen[2] > 1.5, "the stone turned red: {seen:?}");
    (brick_rgb, after)
}

/// Coloured under the sun's light alone (D55): the panel gives `restauro color -i D55`'s
/// L*a*b*, and the view's stone changes from D65 as restauro's colours under the two lights
/// do (each light's white scaled to a brightest channel of 1, as the page shows whites).
fn colour_the_brick_under_the_sun(
    b: &mut Browser,
    d: &std::path::Path,
    brick: &str,
    brick_rgb: [f64; 3],
    after: &[[f64; 3]],
) {
    let d55 = |spectrum: &str| {
        let o = restauro_tests::restauro(&[
            "color", spectrum, "-i", "D55", "--adapt", "none", "--json",
        ]);
        let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let rgb: [f64; 3] = std::array::from_fn(|k| c["sample"]["rgb_linear"][k].as_f64().unwrap());
        (rgb, ["l", "a", "b"].map(|k| c["sample"]["lab"][k].as_f64().unwrap()))
    };
    let white_csv = d.join("white.csv");
    std::fs::write(
        &white_csv,
        (380..=780).step_by(5).map(|nm| format!("{nm},1\n")).collect::<String>(),
    )
    .unwrap();
    let (white, _) = d55(white_csv.to_str().unwrap());
    let top = white.iter().copied().fold(1.0, f64::max);
    let (brick_d55, brick_d55_lab) = d55(brick);
    set_value(b, "preview-light", "spectrum:sunlight");
    b.wait_for(
        "the panel under the sun",
        "document.querySelector('#material table.states caption').textContent.includes('sunlight')",
    );
    base_lab_is(b, brick_d55_lab, "D55");
    let under_sun = around_pick(b, "12b-under-the-sun.png");
    let seen = scaled(after, &under_sun);
    for k in 0..3 {
        let expected = brick_d55[k] / top / brick_rgb[k];
        assert!(
            (seen[k] / expected - 1.0).abs() < 0.05,
            "channel {k}: D65 to D55 scaled the view by {:.3}, the spectra say {expected:.3}",
            seen[k]
        );
    }
    set_value(b, "preview-light", "cie:D65");
}

/// A snapshot of revision 1 from the scene's camera: changed from the render of revision 0
/// (job `first`) as the spectra say, and bit for bit what the command line renders of the
/// revision downloaded as a folder.
fn snapshot_is_the_cli_render_of_the_download(
    b: &mut Browser,
    c: &Coordinator,
    d: &std::path::Path,
    token: &std::path::Path,
    first: &str,
) {
    b.click("#home");
    b.eval("document.getElementById('snap-spp').value = 1");
    b.click("#take-snapshot");
    b.wait_for("the snapshot's row", "document.querySelectorAll('#jobs tbody tr').length === 2");
    let snap = b.eval(&format!(
        "[...document.querySelectorAll('#jobs tbody tr')].map(r => r.dataset.job).find(j => j !== '{first}')"
    ));
    let snap = snap.as_str().unwrap().to_owned();
    let row = format!("document.querySelector('#jobs tr[data-job=\"{snap}\"]')");
    b.wait_for("the snapshot done", &format!("{row}.children[1].textContent === 'done'"));
    let fetched = |job: &str, out: &str| {
        let o = client(&["fetch", job, "--out", d.join(out).to_str().unwrap()], &c.url, token);
        assert!(o.status.success(), "{}", text(&o));
        read_exr(&d.join(out).join("aosta.exr"), MAX_PIXELS).unwrap().pixels
    };
    let (shot, original) = (fetched(&snap, "snapshot"), fetched(first, "original"));
    // Brick is darker than the conglomerate and reflects less of the short waves: the image's
    // total Y falls, and Z (short waves) falls further than X.
    let total = |px: &[[f32; 3]], k: usize| px.iter().map(|p| f64::from(p[k])).sum::<f64>();
    let ratio = |k: usize| total(&shot, k) / total(&original, k);
    let (x, y, z) = (ratio(0), ratio(1), ratio(2));
    assert!(y < 0.99 && z < x, "X, Y, Z of the snapshot over the original: {x}, {y}, {z}");
    let folder = download_shown(b, c, d);
    assert!(folder.ends_with("aosta-revision-1/scene.toml"), "{}", folder.display());
    let o = restauro_tests::restauro(&["scene", "check", folder.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let out = d.join("rendered");
    let o = restauro_tests::restauro(&[
        "render",
        folder.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--integrator",
        "path",
        "--width",
        "160",
        "--height",
        "90",
        // The snapshot form's noise target, 15 %: the same adaptive render, bit for bit.
        "--noise",
        "0.15",
        "--progress",
        "none",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rendered = read_exr(&out.join("scene.exr"), MAX_PIXELS).unwrap().pixels;
    let differing = rendered.iter().zip(&shot).filter(|(p, q)| p != q).count();
    assert_eq!(
        (rendered.len(), differing),
        (shot.len(), 0),
        "the CLI render of the download differs"
    );
}

/// The sun at 17:00 on 21 December: after sunset at Aosta, on the day's path (revision 2). A
/// latitude off the Earth is then refused, in the server's words, and shown.
fn set_the_sun_after_sunset(b: &mut Browser) {
    set_value(b, "sun-date", "2026-12-21");
    set_value(b, "sun-offset", "+01:00");
    set_value(b, "sun-time", "1020");
    b.wait_for(
        "the day's path",
        "document.getElementById('sun-time-shown').textContent === '17:00' && \
         document.getElementById('sun-position').textContent.includes('below the horizon')",
    );
    b.click("#set-sun");
    b.wait_for("revision 2", "document.getElementById('view').dataset.revision === '2'");
    let now = b.eval("document.getElementById('sun-now').textContent");
    assert!(now.as_str().unwrap().contains("(2026-12-21T17:00:00+01:00)"), "{now}");
    assert!(now.as_str().unwrap().contains("elevation -"), "{now}");
    b.screenshot(&shots().join("13-sun-at-dusk.png"));
    b.eval("document.getElementById('sun-latitude').value = '100'");
    refused(b, "#set-sun", "lights[0].site", "2");
    set_value(b, "sun-latitude", "45.7371");
}

/// A view saved under a name (revision 3), then flown to from the scene's camera.
fn save_a_view_and_fly_to_it(b: &mut Browser) {
    let pose = "JSON.stringify(window.studioViewer.pose().position.map(v => v.toFixed(6)))";
    b.eval("window.studioViewer.camera.position.x += 2; window.studioViewer.controls.update()");
    let saved = b.eval(pose);
    set_value(b, "view-name", "portal, closer");
    b.click("#save-view");
    b.wait_for("revision 3", "document.getElementById('view').dataset.revision === '3'");
    let names = b.eval("[...document.getElementById('view-picker').options].map(o => o.value)");
    assert_eq!(names, serde_json::json!(["", "portal, closer"]));
    b.click("#home");
    assert_ne!(b.eval(pose), saved);
    set_value(b, "view-picker", "portal, closer");
    assert_eq!(b.eval(pose), saved, "flown to the saved view");
}

/// Revision 0 opened again: the stone as submitted, and the four revisions listed (the first
/// edit naming `brick`).
fn open_revision_0_again(b: &mut Browser, brick: &str) {
    set_value(b, "revision-picker", "0");
    b.wait_for("revision 0", "document.getElementById('view').dataset.revision === '0'");
    assert_eq!(b.eval("document.getElementById('revert').hidden"), false);
    b.click("#home");
    b.screenshot(&shots().join("14-revision-0.png"));
    let revisions =
        b.eval("[...document.getElementById('revision-picker').options].map(o => o.textContent)");
    assert_eq!(revisions.as_array().unwrap().len(), 4, "{revisions}");
    assert!(revisions[1].as_str().unwrap().contains(brick), "{revisions}");
}

/// Walking. From 5 m up, 9 m in front of the middle buttress (its face at y = −0.9 m, the
/// paving at z = 0 to 0.005 m), G stands the eye 1.6 m over the paving; holding ↑ walks north
/// and the buttress stops the walker its body's radius (0.3 m) short.
fn walk_until_the_buttress_stops_the_walker(b: &mut Browser) {
    let world = "(() => { const v = window.studioViewer, p = v.camera.position, o = v.view.offset_m; \
                 return [p.x + o[0], -p.z + o[1], p.y + o[2]]; })()";
    b.eval(
        "(() => { const v = window.studioViewer, o = v.view.offset_m; \
         const glb = (x, y, z) => [x - o[0], z - o[2], -(y - o[1])]; \
         v.fly({ position: glb(0, -9, 5), target: glb(0, 0, 5), up: [0, 1, 0], vertical_fov_deg: 60 }); })()",
    );
    b.press("g");
    b.wait_for(
        "walking",
        "document.getElementById('walk').getAttribute('aria-pressed') === 'true'",
    );
    let at = b.eval(world);
    let (x, y, z) = (at[0].as_f64().unwrap(), at[1].as_f64().unwrap(), at[2].as_f64().unwrap());
    assert!(x.abs() < 1e-6 && (y + 9.0).abs() < 1e-6, "{at}");
    assert!((1.6..=1.606).contains(&z), "eye at {z} m, not 1.6 m over the paving");
    let frames = "window.studioViewer.frames";
    let at = b.hold_until_still("ArrowUp", world, frames, std::time::Duration::from_secs(90));
    let y = at[1].as_f64().unwrap();
    // A step is refused when the wall is nearer than the step and the body's radius (0.3 m),
    // at the eye or at a step's height (0.45 m); a step is at most 0.14 m (1.4 m/s over the
    // longest frame counted, 0.1 s). So the walker stops 0.3 to 0.44 m short of the nearer of
    // what those two rays meet: the buttress's face, or a block or base proud of it.
    let ahead = b.eval(
        "(() => { const v = window.studioViewer, p = v.camera.position, o = v.view.offset_m; \
         const north = p.clone().set(0, 0, -1); \
         return [1.6, 0.45].map(h => { const from = p.clone(); from.y = p.y - 1.6 + h; \
           const hit = v.walker.hit(from, north, 10); \
           return hit ? [hit.distance, -hit.point.z + o[1]] : null; }); })()",
    );
    let nearest = ahead
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|h| h.as_array().map(|h| (h[0].as_f64().unwrap(), h[1].as_f64().unwrap())))
        .fold((f64::MAX, 0.0), |a, h| if h.0 < a.0 { h } else { a });
    let (distance, wall_y) = nearest;
    assert!((0.3..=0.44 + 1e-9).contains(&distance), "stopped {distance} m short: {ahead}");
    assert!((-0.96..=-0.9).contains(&wall_y), "stopped by something at y = {wall_y} m: {ahead}");
    assert!(y < -1.19, "stopped at y = {y} m, not short of the buttress: {at}");
    // Over the paving's slabs (up to 5 mm high) and its mortar bed (−20 mm) between them.
    assert!((1.58..=1.606).contains(&at[2].as_f64().unwrap()), "{at}");
    b.screenshot(&shots().join("15-walked-to-the-wall.png"));
    b.hold("ArrowUp", std::time::Duration::from_secs(1));
    assert_eq!(b.eval(world)[1], at[1], "the wall still stops the walker");
    b.press("g");
    assert_eq!(b.eval("document.getElementById('walk').getAttribute('aria-pressed')"), "false");
}

/// A note pinned to the facade in the page is kept with the scene: its pin is drawn where it
/// was clicked, a link that is not a web address is refused in the server's words, and after
/// the coordinator restarts the note is listed and opens with its text, its link, the
/// photograph attached to it (its pixels as sent) and its view.
#[test]
fn a_note_pinned_to_the_facade_survives_a_restart() {
    if !available("studio_editing") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let farm = Coordinator::studio_farm(d, 160, 90);
    submit(&farm.scene, &["--spp", "1", "--tile", "32"], &farm.coordinator.url, &farm.token);
    let mut b = Browser::launch(1280, 900);
    b.goto(&format!("{}#token={CLIENT_TOKEN}", farm.page));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    b.click("#view");
    b.wait_for("the surface clicked", "!document.getElementById('material').hidden");
    set_value(&mut b, "note-new-title", "crack above the third arch");
    set_value(&mut b, "note-new-text", "Opened 2 mm since the 2019 survey.");
    set_value(&mut b, "note-new-links", "javascript:alert(1)");
    let photo_rgb = [30u8, 90, 200];
    let photo = d.join("arch-3.png");
    std::fs::write(&photo, restauro_tests::browser::solid_png(40, 30, photo_rgb)).unwrap();
    b.choose_file("#note-new-images", &photo.canonicalize().unwrap());
    b.click("#note-save");
    let problem = b.refusal_beside("#note-save");
    assert!(problem.contains("is not a web address"), "{problem}");
    let link = "https://example.org/survey/2019/arch-3.pdf";
    set_value(&mut b, "note-new-links", link);
    b.click("#note-save");
    b.wait_for("revision 1", "document.getElementById('view').dataset.revision === '1'");
    let listed =
        b.eval("[...document.querySelectorAll('#notes-list button')].map(b => b.textContent)");
    assert_eq!(listed, serde_json::json!(["crack above the third arch"]));
    // The pin stands where the click landed, and is drawn there in the note's red.
    let gap = b.eval(
        "(() => { const v = window.studioViewer; return v.pins.children[0].position.distanceTo(v.picked); })()",
    );
    assert!(gap.as_f64().unwrap() < 1e-3, "{gap}");
    b.eval("document.getElementById('view').scrollIntoView({ block: 'center' })");
    let at = b.eval("window.studioViewer.onScreen(window.studioViewer.pins.children[0].position)");
    let (x, y) = (at[0].as_f64().unwrap() as usize, at[1].as_f64().unwrap() as usize);
    let (rgb, width) = png_rgb(&b.screenshot(&shots().join("16-note-pinned.png")));
    let [r, g, bl] = rgb[y * width + x];
    assert!(r > 150 && g < 80 && bl < 80, "the pin's pixel is {:?}", [r, g, bl]);
    let pose = b.eval("JSON.stringify(window.studioViewer.pose().position.map(v => v.toFixed(5)))");

    // Restarted on the same store, the note is there.
    drop(farm);
    let (_c, page) = Coordinator::with_studio(d);
    b.goto(&format!("{page}#token={CLIENT_TOKEN}"));
    b.wait_for("the note", "document.querySelectorAll('#notes-list button').length === 1");
    b.eval("window.studioViewer.camera.position.x += 7; window.studioViewer.controls.update()");
    b.click("#notes-list button");
    b.wait_for("the note shown", "!document.getElementById('note-shown').hidden");
    assert_eq!(
        b.eval("document.getElementById('note-text').textContent"),
        "Opened 2 mm since the 2019 survey."
    );
    assert_eq!(b.eval("document.querySelector('#note-links a').href"), link);
    assert_eq!(b.eval("document.querySelector('#note-links a').rel"), "noopener noreferrer");
    b.wait_for(
        "the photograph",
        "(() => { const i = document.querySelector('#note-images img'); return i && i.complete && i.naturalWidth > 0; })()",
    );
    let shown = b.eval(
        "(() => { const i = document.querySelector('#note-images img'); const c = document.createElement('canvas'); \
         c.width = i.naturalWidth; c.height = i.naturalHeight; const x = c.getContext('2d'); x.drawImage(i, 0, 0); \
         return [i.naturalWidth, i.naturalHeight, ...[...x.getImageData(20, 15, 1, 1).data].slice(0, 3), i.alt]; })()",
    );
    assert_eq!(
        &shown.as_array().unwrap()[..5],
        &serde_json::json!([40, 30, photo_rgb[0], photo_rgb[1], photo_rgb[2]]).as_array().unwrap()
            [..],
        "{shown}"
    );
    assert!(shown[5].as_str().unwrap().contains("crack above the third arch"), "{shown}");
    assert!(
        b.eval("document.getElementById('note-part').textContent")
            .as_str()
            .unwrap()
            .starts_with("About facade/")
    );
    assert_eq!(
        b.eval("JSON.stringify(window.studioViewer.pose().position.map(v => v.toFixed(5)))"),
        pose,
        "flown to the note's view"
    );
    b.screenshot(&shots().join("17-note-after-restart.png"));
    add_a_second_photograph_and_remove_the_first(&mut b, d);
}

/// A second photograph added to the open note, then the first removed: the note keeps the
/// second, and its view.
fn add_a_second_photograph_and_remove_the_first(b: &mut Browser, d: &std::path::Path) {
    let second = d.join("arch-3-detail.png");
    std::fs::write(&second, restauro_tests::browser::solid_png(12, 10, [240, 200, 20])).unwrap();
    b.choose_file("#note-add-images", &second.canonicalize().unwrap());
    b.wait_for("revision 2", "document.getElementById('view').dataset.revision === '2'");
    let count = "document.querySelectorAll('#note-images img').length";
    assert_eq!(b.eval(count), 2);
    b.click("#note-images figure button");
    b.wait_for("revision 3", "document.getElementById('view').dataset.revision === '3'");
    assert_eq!(b.eval(count), 1);
    b.wait_for(
        "the second photograph",
        "(() => { const i = document.querySelector('#note-images img'); return i.complete && i.naturalWidth === 12; })()",
    );
    assert_eq!(
        b.eval("document.getElementById('note-text').textContent"),
        "Opened 2 mm since the 2019 survey."
    );
}

/// The linear RGB, over the 21 × 21 pixels of `after`, of the pixels that were within 2 % of
/// the clicked pixel's colour in `before` (the clicked part, in the same light), as the ratio
/// `after / before` per channel (the median).
fn part_ratio(before: &[[f64; 3]], after: &[[f64; 3]]) -> [f64; 3] {
    let centre = before[before.len() / 2];
    let same: Vec<usize> = (0..before.len())
        .filter(|&i| (0..3).all(|k| (before[i][k] / centre[k] - 1.0).abs() < 0.02))
        .collect();
    assert!(same.len() >= 20, "only {} pixels of the clicked part", same.len());
    std::array::from_fn(|k| {
        let mut r: Vec<f64> = same.iter().map(|&i| after[i][k] / before[i][k]).collect();
        r.sort_by(f64::total_cmp);
        r[r.len() / 2]
    })
}

/// Hypotheses built in the page: a new one puts every part in one state and the real-time
/// view shows each part in that state's colour; the clicked part alone is then set to another
/// state; a name that is taken is refused in the server's words; the hypothesis is renamed,
/// downloaded in the scene file that `scene check` accepts, and deleted.
#[test]
fn a_restorer_builds_a_hypothesis_part_by_part() {
    if !available("studio_editing") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (farm, mut b, _) = opened(d);
    let c = &farm.coordinator;
    b.click("#view");
    b.wait_for("the material panel", "document.querySelector('#material .variant-part')");
    let picked = b.eval("(() => { const r = [...document.querySelectorAll('#material .body > table:first-child tr')].map(r => r.cells[1].textContent); return r; })()");
    let (object, part, material) = (
        picked[0].as_str().unwrap().to_owned(),
        picked[1].as_str().unwrap().to_owned(),
        picked[2].as_str().unwrap().to_owned(),
    );
    // Up close (1.5 m from the point clicked), so that the pixels read are of that part.
    b.eval(
        "(() => { const v = window.studioViewer, p = v.picked.clone(); \
         const from = v.camera.position.clone().sub(p).normalize().multiplyScalar(1.5).add(p); \
         v.fly({ position: from.toArray(), target: p.toArray(), up: [0, 1, 0], vertical_fov_deg: 40 }); })()",
    );
    let before = around_pick(&mut b, "31-hypothesis-before.png");
    // The colours restauro gives the clicked material's states under the light the preview
    // colours under (the scene's own), from the scene's view.
    let state_rgb = |b: &mut Browser, state: &str| -> [f64; 3] {
        let rgb = b.eval(&format!(
            "(() => {{ const m = window.studioViewer.view.materials.find(m => m.name === '{material}'); \
             const s = m.states.find(s => s.state === '{state}') || m.states[0]; \
             return s.under[document.getElementById('preview-light').value].colour_linear_srgb; }})()"
        ));
        std::array::from_fn(|k| rgb[k].as_f64().unwrap())
    };
    let (base, degraded) = (state_rgb(&mut b, "base"), state_rgb(&mut b, "degraded"));
    assert_ne!(base, degraded, "{material} has a degraded state in the Aosta scene");

    // A new hypothesis, every part as found: the clicked part takes its degraded colour.
    set_value(&mut b, "variant-name", "first campaign");
    set_value(&mut b, "variant-state", "degraded");
    b.click("#new-variant");
    b.wait_for("revision 1", "document.getElementById('view').dataset.revision === '1'");
    b.wait_for("it chosen", "document.getElementById('snap-variant').value === 'first campaign'");
    let options = b.eval("[...document.getElementById('snap-variant').options].map(o => o.value)");
    assert_eq!(options, serde_json::json!(["", "as-found", "cleaned", "first campaign"]));
    let after = around_pick(&mut b, "32-hypothesis-degraded.png");
    let seen = part_ratio(&before, &after);
    for k in 0..3 {
        let expected = degraded[k] / base[k];
        assert!(
            (seen[k] / expected - 1.0).abs() < 0.05,
            "channel {k}: the part's colour scaled by {:.3}, its degraded state by {expected:.3}",
            seen[k]
        );
    }
    b.wait_for("the part's state", "document.getElementById('part-state-now')");
    assert_eq!(b.eval("document.getElementById('part-state-now').textContent"), "degraded");

    // The clicked part alone set to its base state in this hypothesis: its colour as before.
    set_value(&mut b, "part-state", "base");
    b.click("#part-state-part");
    b.wait_for("revision 2", "document.getElementById('view').dataset.revision === '2'");
    b.wait_for(
        "the panel redrawn",
        "document.getElementById('part-state-now') && document.getElementById('part-state-now').textContent === 'base'",
    );
    let after2 = around_pick(&mut b, "33-hypothesis-part.png");
    let back = part_ratio(&before, &after2);
    assert!(back.iter().all(|r| (r - 1.0).abs() < 0.02), "{back:?}");
    let variant =
        b.eval("window.studioViewer.view.variants.find(v => v.name === 'first campaign')");
    assert_eq!(variant["state"], "degraded", "{variant}");
    assert_eq!(variant["states"], serde_json::json!({ format!("{object}/{part}"): "base" }));

    // "As the scene is" shows every part in its base state; V steps to the next hypothesis.
    set_value(&mut b, "snap-variant", "");
    let plain = part_ratio(&before, &around_pick(&mut b, "34-as-the-scene-is.png"));
    assert!(plain.iter().all(|r| (r - 1.0).abs() < 0.02), "{plain:?}");
    b.press("v");
    assert_eq!(b.eval("document.getElementById('snap-variant').value"), "as-found");
    let found = part_ratio(&before, &around_pick(&mut b, "35-as-found.png"));
    assert!((found[1] / (degraded[1] / base[1]) - 1.0).abs() < 0.05, "{found:?}");

    // A name that is taken is refused, in the server's words, and nothing changes.
    set_value(&mut b, "snap-variant", "first campaign");
    set_value(&mut b, "variant-name", "cleaned");
    refused(&mut b, "#rename-variant", "a hypothesis named `cleaned` exists", "2");

    rename_the_hypothesis_and_check_the_download(&mut b, c, d, &object, &part);
    double_click_centres_the_orbit_on_the_stone(&mut b);

    // Deleted: the picker goes back to the scene as it is.
    b.click("#delete-variant");
    b.wait_for("revision 4", "document.getElementById('view').dataset.revision === '4'");
    b.wait_for("none chosen", "document.getElementById('snap-variant').value === ''");
    let options = b.eval("[...document.getElementById('snap-variant').options].map(o => o.value)");
    assert_eq!(options, serde_json::json!(["", "as-found", "cleaned"]));
}

/// Renamed to "portal first" (revision 3); the downloaded scene holds it, with the part
/// `object/part` in its base state, and `scene check` accepts it.
fn rename_the_hypothesis_and_check_the_download(
    b: &mut Browser,
    c: &Coordinator,
    d: &std::path::Path,
    object: &str,
    part: &str,
) {
    set_value(b, "variant-name", "portal first");
    b.click("#rename-variant");
    b.wait_for("revision 3", "document.getElementById('view').dataset.revision === '3'");
    b.wait_for("it chosen", "document.getElementById('snap-variant').value === 'portal first'");
    b.screenshot(&shots().join("36-hypothesis-renamed.png"));
    let folder = download_shown(b, c, d);
    assert!(folder.ends_with("aosta-revision-3/scene.toml"), "{}", folder.display());
    let toml: toml::Table = toml::from_str(&std::fs::read_to_string(&folder).unwrap()).unwrap();
    let saved = &toml["variants"]["portal first"];
    assert_eq!(saved["state"].as_str(), Some("degraded"), "{saved}");
    assert_eq!(saved["states"][&format!("{object}/{part}")].as_str(), Some("base"), "{saved}");
    assert!(toml["variants"].get("first campaign").is_none());
    let o = restauro_tests::restauro(&["scene", "check", folder.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
}

/// A double-click on the middle of the view makes the surface there the centre of orbiting:
/// the camera stands 1.5 m from the stone (flown there before) with the centre put 5 m behind
/// it; afterwards the centre is on the stone, 1.5 m away, still straight ahead.
fn double_click_centres_the_orbit_on_the_stone(b: &mut Browser) {
    let distance = "(() => { const v = window.studioViewer, t = v.controls.target, q = t.clone().project(v.camera); \
                    return [t.distanceTo(v.camera.position), q.x, q.y]; })()";
    b.eval(
        "(() => { const v = window.studioViewer, d = v.controls.target.clone().sub(v.camera.position).normalize(); \
         v.controls.target.copy(v.camera.position).addScaledVector(d, 6.5); v.controls.update(); })()",
    );
    let far = b.eval(distance)[0].as_f64().unwrap();
    assert!((far - 6.5).abs() < 1e-6, "{far}");
    b.double_click("#view");
    let orbit = b.eval(distance);
    let near = orbit[0].as_f64().unwrap();
    assert!((near - 1.5).abs() < 0.1, "the centre is {near} m away, not on the stone 1.5 m away");
    let (x, y) = (orbit[1].as_f64().unwrap(), orbit[2].as_f64().unwrap());
    assert!(x.abs() < 0.01 && y.abs() < 0.01, "{orbit}");
}

/// The text of cell `k` of each row of the luminaires' table.
fn luminaire_cells(b: &mut Browser) -> Vec<Vec<String>> {
    let rows = b.eval(
        "[...document.querySelectorAll('#luminaires tbody tr')].map(r => [...r.cells].map(c => c.textContent))",
    );
    serde_json::from_value(rows).unwrap()
}

/// A number as the page shows it (`12,345`).
fn shown_number(text: &str) -> f64 {
    text.replace(',', "").parse().unwrap_or_else(|_| panic!("`{text}` is not a number"))
}

/// Light set from the page: the sky's model and illuminance (a negative one refused in the
/// server's words), and a luminaire placed by hand, aimed at the point clicked, shaped by an
/// EULUMDAT file read by the server, with a CIE illuminant by name. Its figures in the page
/// are `scene check`'s for the downloaded scene, its photometric solid is drawn in the view,
/// and it is deleted again.
#[test]
fn a_lighting_designer_sets_the_sky_and_aims_a_luminaire_with_its_file() {
    if !available("studio_editing") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (farm, mut b, _) = opened(d);
    let c = &farm.coordinator;

    // The sky: uniform, 20 000 lx.
    set_value(&mut b, "sky-model", "uniform");
    set_value(&mut b, "sky-lux", "20000");
    b.click("#set-sky");
    b.wait_for("revision 1", "document.getElementById('view').dataset.revision === '1'");
    let now = b.eval("document.getElementById('sky-now').textContent");
    assert!(now.as_str().unwrap().contains("uniform sky, 20,000 lx on the horizontal"), "{now}");
    set_value(&mut b, "sky-lux", "-5");
    refused(&mut b, "#set-sky", "illuminance_lux", "1");

    // A luminaire on the paving 8 m in front of the facade, aimed at the point clicked.
    b.click("#view");
    b.wait_for("the material panel", "!document.getElementById('material').hidden");
    for (id, v) in [("lum-x", "0"), ("lum-y", "-8"), ("lum-z", "0.3")] {
        set_value(&mut b, id, v);
    }
    b.click("#lum-aim");
    let picked = b.eval(
        "(() => { const v = window.studioViewer, p = v.picked, o = v.view.offset_m; \
         return [p.x + o[0], -p.z + o[1], p.y + o[2]]; })()",
    );
    let aim: Vec<f64> = (0..3).map(|k| picked[k].as_f64().unwrap()).collect();
    let ldt = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scene/tests/data/photometric/ldt_isym1_absolute.ldt")
        .canonicalize()
        .unwrap();
    b.choose_file("#lum-file", &ldt);
    b.wait_for(
        "the file read",
        "document.getElementById('lum-file-info').textContent.includes(' lm, peak ')",
    );
    set_value(&mut b, "lum-kind", "point");
    set_value(&mut b, "lum-spectrum", "cie:A");
    b.click("#lum-save");
    b.wait_for("revision 2", "document.getElementById('view').dataset.revision === '2'");
    let rows = luminaire_cells(&mut b);
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert_eq!((rows[0][1].as_str(), rows[0][2].as_str()), ("point", "0.00, -8.00, 0.30"));
    assert_eq!(rows[0][7], "cie_A");
    let (peak, flux, beam) =
        (shown_number(&rows[0][4]), shown_number(&rows[0][5]), shown_number(&rows[0][6]));

    downloaded_luminaire_is_as_the_page_shows(&mut b, c, d, &aim, [peak, flux, beam]);

    // Its photometric solid is drawn, in orange, around the bulb.
    b.eval(
        "(() => { const v = window.studioViewer, p = v.lamps.children[0].position; \
         v.fly({ position: [p.x + 3, p.y + 4, p.z + 9], target: p.toArray(), up: [0, 1, 0], vertical_fov_deg: 50 }); })()",
    );
    b.eval("document.getElementById('view').scrollIntoView()");
    let (rgb, _) = png_rgb(&b.screenshot(&shots().join("37-luminaire.png")));
    let orange =
        rgb.iter().filter(|p| p[0] > 230 && (110..=160).contains(&p[1]) && p[2] < 60).count();
    assert!(orange > 100, "{orange} orange pixels: the solid is not drawn");

    // Deleted: no luminaire left.
    b.click("#luminaires tbody button[aria-label='Delete luminaire 2']");
    b.wait_for("revision 3", "document.getElementById('view').dataset.revision === '3'");
    assert!(luminaire_cells(&mut b).is_empty());

    // A bare lamp given by its flux, as a data sheet gives it: 1000 lm in every direction is
    // 1000/4π = 79.6 cd, shown to the candela, and its flux is listed.
    set_value(&mut b, "lum-cd", "");
    set_value(&mut b, "lum-lm", "1000");
    b.click("#lum-save");
    b.wait_for("revision 4", "document.getElementById('view').dataset.revision === '4'");
    let rows = luminaire_cells(&mut b);
    let (cd, lm) = (shown_number(&rows[0][4]), shown_number(&rows[0][5]));
    assert_eq!((cd, lm), ((1000.0 / (4.0 * std::f64::consts::PI)).round(), 1000.0), "{rows:?}");
}

/// The downloaded scene (revision 2) holds the luminaire as the file says, aimed at `aim`, and
/// `scene check` gives the figures the page shows: `flux` lm, `peak` cd, a `beam`° beam.
fn downloaded_luminaire_is_as_the_page_shows(
    b: &mut Browser,
    c: &Coordinator,
    d: &std::path::Path,
    aim: &[f64],
    [peak, flux, beam]: [f64; 3],
) {
    let folder = download_shown(b, c, d);
    assert!(folder.ends_with("aosta-revision-2/scene.toml"), "{}", folder.display());
    let toml: toml::Table = toml::from_str(&std::fs::read_to_string(&folder).unwrap()).unwrap();
    let lights = toml["lights"].as_array().unwrap();
    let lamp = lights.iter().find(|l| l["kind"].as_str() == Some("point")).unwrap();
    let coords = |key: &str| -> Vec<f64> {
        lamp[key].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect()
    };
    assert_eq!(coords("position"), [0.0, -8.0, 0.3]);
    for (k, (got, want)) in coords("aim").iter().zip(aim).enumerate() {
        assert!((got - want).abs() < 1e-3, "aim[{k}]: {got} in the file, {want} clicked");
    }
    assert!(lamp["ies"].as_str().unwrap().ends_with(".ldt"), "{lamp}");
    assert_eq!(toml["spectra"]["cie_A"]["illuminant"].as_str(), Some("A"));
    let o = restauro_tests::restauro(&["scene", "check", folder.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let said = text(&o);
    let line =
        said.lines().find(|l| l.contains("photometric file:")).unwrap_or_else(|| panic!("{said}"));
    let figures: Vec<f64> = line
        .split("photometric file: ")
        .nth(1)
        .unwrap()
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter(|t| !t.is_empty() && t != &".")
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(figures[..3], [flux, peak, beam], "page {flux} lm, {peak} cd, {beam}°; {line}");
}

/// A measured reflectance sent from the page as a CSV file: a flat 50 % grey card is plotted
/// with its L*a*b* (CIE 1976: L* = 116 · 0.5^(1/3) − 16 = 76.07, neutral), assigned to the stone
/// clicked and kept in the scene as a file; a file with a reflectance above 1 is refused in the
/// reader's words, naming the file and the line.
#[test]
fn a_restorer_assigns_a_measured_spectrum_from_a_csv_file() {
    if !available("studio_editing") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (farm, mut b, _) = opened(d);
    b.click("#view");
    b.wait_for("the material editor", "document.getElementById('material-csv')");
    let stone =
        b.eval("document.querySelector('#material .body > table tr:nth-child(3) td').textContent");
    let grey = d.join("grey-card.csv");
    let rows: String = (380..=780).step_by(10).map(|nm| format!("{nm},0.5\n")).collect();
    std::fs::write(&grey, format!("# a grey card\nwavelength_nm,reflectance\n{rows}")).unwrap();
    let bad = d.join("too-bright.csv");
    std::fs::write(&bad, rows.replace("600,0.5", "600,1.5")).unwrap();

    b.choose_file("#material-csv", &bad);
    b.wait_for(
        "the refusal",
        "(() => { const t = document.getElementById('material-candidate').textContent; \
         return t.includes('too-bright.csv') && !t.startsWith('reading'); })()",
    );
    let said = b.eval("document.getElementById('material-candidate').textContent");
    assert!(
        said.as_str().unwrap().contains("too-bright.csv:23: the reflectance 1.5 is above 1"),
        "{said}"
    );

    b.choose_file("#material-csv", &grey);
    b.wait_for(
        "the candidate",
        "document.getElementById('material-candidate').textContent.startsWith('grey-card.csv, under D65: L* 76.1, a* 0.0, b* 0.0')",
    );
    assert!(b.eval("document.querySelector('#material polyline.state-candidate')").is_object());
    b.click("#material-assign");
    b.wait_for("revision 1", "document.getElementById('view').dataset.revision === '1'");
    let row = b.eval("[...document.querySelector('#material tr[data-state=base]').cells].map(c => c.textContent)");
    assert_eq!(row[1], "grey-card", "{row}");
    assert_eq!(
        (row[3].as_str(), row[4].as_str(), row[5].as_str()),
        (Some("76.1"), Some("0.0"), Some("0.0"))
    );
    let folder = download_shown(&mut b, &farm.coordinator, d);
    let toml: toml::Table = toml::from_str(&std::fs::read_to_string(&folder).unwrap()).unwrap();
    let file = toml["spectra"]["grey-card"]["file"].as_str().unwrap();
    assert!(file.ends_with(".csv"), "{file}");
    assert_eq!(
        toml["materials"][stone.as_str().unwrap()]["reflectance"].as_str(),
        Some("grey-card")
    );
    let kept = std::fs::read(folder.parent().unwrap().join(file)).unwrap();
    assert_eq!(kept, std::fs::read(&grey).unwrap(), "the file is kept as sent");
    let o = restauro_tests::restauro(&["scene", "check", folder.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
}
