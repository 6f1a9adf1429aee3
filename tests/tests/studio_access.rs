//! The studio audited as a person with a keyboard, a screen reader or low vision meets it, in a
//! real browser against a real coordinator and worker: axe-core (vendored for these tests only,
//! `tests/vendor/axe-core/`) finds no serious or critical violation of WCAG 2.x A and AA in each
//! state the page is used in (colour contrast at AA among them); every control shows where the
//! keyboard's focus is; every control says what it does on hover. And what a first visit meets:
//! the demo's facade offered beside "open a folder", an error shown where the action was taken
//! in the server's words, and the view moved by the keyboard alone.

use restauro_tests::browser::{Browser, available};
use restauro_tests::{CLIENT_TOKEN, Coordinator, Worker, aosta_scene, submit};
use serde_json::{Value, json};
use std::path::PathBuf;

/// Screenshots go to `<target>/tmp/studio/`.
fn shots() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("studio")
}

/// axe-core's engine, as its package ships it.
const AXE: &str = include_str!("../vendor/axe-core/axe.min.js");

/// Runs axe-core over the page as it now is; the serious and critical violations, each as
/// "rule: what it asks (the elements)".
fn violations(b: &mut Browser) -> Vec<String> {
    if b.eval("typeof window.axe") != "object" {
        b.eval(&format!("{AXE}\n;true"));
    }
    let found = b.eval(
        "axe.run(document, { runOnly: { type: 'tag', values: ['wcag2a', 'wcag2aa', 'wcag21a', 'wcag21aa'] } })
           .then(r => r.violations.filter(v => v.impact === 'serious' || v.impact === 'critical')
             .map(v => `${v.id} (${v.impact}): ${v.help}: ` +
               v.nodes.slice(0, 6).map(n => n.target.join(' ') + ' [' + n.failureSummary.replace(/\\s+/g, ' ') + ']').join('; ')))",
    );
    serde_json::from_value(found).unwrap()
}

fn audit(b: &mut Browser, state: &str) {
    let found = violations(b);
    assert!(
        found.is_empty(),
        "{state}: axe-core finds {} violations:\n{}",
        found.len(),
        found.join("\n")
    );
}

/// Every control on the page that a person can reach and that is in sight, as the list of those
/// failing `check` (a JavaScript function of the element, true when it passes).
fn controls_failing(b: &mut Browser, check: &str) -> Vec<String> {
    let failing = b.eval(&format!(
        "(() => {{ const ok = {check}; \
           return [...document.querySelectorAll('button, input, select, textarea, a[href], summary')] \
             .filter(e => e.checkVisibility() && !e.disabled && e.type !== 'hidden' && !ok(e)) \
             .map(e => e.id || `${{e.tagName}} \"${{e.textContent.trim().slice(0, 40)}}\"`); }})()"
    ));
    serde_json::from_value(failing).unwrap()
}

/// Tabs through the page from its start; at each stop, whether the focus shows: an outline or a
/// ring of at least 2 px, in a colour that is not the element's background.
fn focus_not_shown(b: &mut Browser, stops: usize) -> Vec<String> {
    b.eval("document.activeElement && document.activeElement.blur()");
    let mut missing = Vec::new();
    for _ in 0..stops {
        b.press("Tab");
        let seen = b.eval(
            "(() => { const e = document.activeElement; if (!e || e === document.body) return null; \
               const s = getComputedStyle(e); \
               const outline = s.outlineStyle !== 'none' && parseFloat(s.outlineWidth) >= 2; \
               const ring = /\\d+px \\d+px 0px [2-9]px|\\d+px \\d+px \\d+px [2-9]px/.test(s.boxShadow); \
               return [(e.id || e.tagName + ' ' + e.textContent.trim().slice(0, 30)) + ` (outline ${s.outlineStyle} ${s.outlineWidth}, shadow ${s.boxShadow})`, outline || ring]; })()",
        );
        if let Value::Array(pair) = seen
            && pair[1] == false
        {
            missing.push(pair[0].as_str().unwrap_or_default().to_owned());
        }
    }
    missing.sort();
    missing.dedup();
    missing
}

#[test]
fn the_studio_passes_an_accessibility_audit_in_each_state() {
    if !available("studio_access") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (c, page) = Coordinator::with_studio(d);
    let mut b = Browser::launch(1280, 720);

    // The sign-in dialog, then the first visit: no scene yet.
    sign_in_dialog(&mut b, &page);
    audit(&mut b, "signing in");
    give_token(&mut b);
    b.wait_for("the first visit's offer", "document.getElementById('welcome').checkVisibility()");
    audit(&mut b, "the first visit, no scene");

    // A scene rendered once: every panel open, the farm listing the job.
    let _worker = Worker::start(d, &c.url, "local-1", &[]);
    let scene = aosta_scene(d, 80, 45);
    let id = submit(&scene, &["--spp", "1"], &c.url, &d.join("client.token"));
    let row = format!("document.querySelector('#jobs tr[data-job=\"{id}\"]')");
    b.wait_for("the job to finish", &format!("{row} && {row}.children[1].textContent === 'done'"));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    audit(&mut b, "a scene open, every panel open");

    let untitled = controls_failing(&mut b, "e => (e.title || '').trim().length > 0");
    assert!(untitled.is_empty(), "controls that say nothing on hover: {untitled:?}");
    let unitless = controls_failing(
        &mut b,
        "e => !['number', 'range'].includes(e.type) || /\\([^)]+\\)|\\bpx\\b|%|°|lux|cd|lm|\\bm\\b|\\bper\\b/.test( \
           [...(e.labels || [])].map(l => l.textContent).join(' ') + ' ' + (e.getAttribute('aria-label') || '') + ' ' + \
           ((e.closest('fieldset') || {}).querySelector?.('legend')?.textContent || ''))",
    );
    assert!(unitless.is_empty(), "numbers without their unit in their label: {unitless:?}");
    let unseen = focus_not_shown(&mut b, 60);
    assert!(unseen.is_empty(), "controls whose focus does not show: {unseen:?}");

    // The shortcuts dialog and the snapshot shown over the view (keys do nothing in a field).
    b.eval("document.activeElement.blur()");
    b.press("?");
    b.wait_for("the shortcuts", "document.getElementById('shortcuts').open");
    audit(&mut b, "the shortcuts dialog");
    b.press("Escape");
    b.wait_for("the shortcuts closed", "!document.getElementById('shortcuts').open");
    b.click(&format!("#jobs tr[data-job=\"{id}\"] button"));
    b.wait_for("the snapshot shown", "document.getElementById('result-image').complete");
    audit(&mut b, "a snapshot shown");
    b.click("#result-close");

    // A sequence of two hypotheses: its timeline, frame and slider.
    b.eval(
        "(() => { for (const [id, v] of [['seq-from', '12:00'], ['seq-to', '13:00'], ['seq-every', '1h'], \
           ['seq-width', '32'], ['seq-height', '18'], ['seq-spp', '1'], ['seq-compare-with', '\"cleaned\"']]) \
           document.getElementById(id).value = v; })()",
    );
    b.click("#seq-start");
    b.wait_for(
        "both frames of both",
        "document.getElementById('seq-b').value && ['seq-img-a', 'seq-img-b'].every(id => document.getElementById(id).complete) \
         && document.getElementById('seq-status').textContent.split('2 of 2 frames ready').length === 3",
    );
    audit(&mut b, "a sequence compared on its slider");
    let untitled = controls_failing(&mut b, "e => (e.title || '').trim().length > 0");
    assert!(untitled.is_empty(), "sequence controls that say nothing on hover: {untitled:?}");
}

/// Opens the page, which asks for the token.
fn sign_in_dialog(b: &mut Browser, page: &str) {
    b.goto(page);
    b.wait_for("the sign-in dialog", "document.getElementById('sign-in').open");
}

/// Types the token into the sign-in dialog and sends it, as a person with the token does.
fn give_token(b: &mut Browser) {
    b.click("#token");
    b.type_text(CLIENT_TOKEN);
    b.press("Enter");
    b.wait_for("signed in", "!document.getElementById('sign-in').open");
}

fn sign_in(b: &mut Browser, page: &str) {
    sign_in_dialog(b, page);
    give_token(b);
}

/// A studio holding the Aosta scene (80 × 45 px, no worker), signed in at 1280 × 720 with the
/// model drawn: the coordinator, the browser, and the folder they live in.
fn scene_held() -> (Coordinator, Browser, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (c, page) = Coordinator::with_studio(d);
    submit(&aosta_scene(d, 80, 45), &["--spp", "1"], &c.url, &d.join("client.token"));
    let mut b = Browser::launch(1280, 720);
    sign_in(&mut b, &page);
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    (c, b, dir)
}

#[test]
fn a_first_visit_offers_the_demos_facade_and_opens_it() {
    if !available("studio_access") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (_c, page) = Coordinator::with_studio(dir.path());
    let mut b = Browser::launch(1920, 1080);
    sign_in(&mut b, &page);
    b.wait_for("the first visit's offer", "document.getElementById('welcome').checkVisibility()");
    for id in ["open-demo", "welcome-open-folder"] {
        let shown = b.eval(&format!("document.getElementById('{id}').checkVisibility()"));
        assert_eq!(shown, true, "{id} is not offered");
    }
    b.docs_picture(&shots(), "studio-first-visit.png");

    // "Open a folder" is the scene panel's own dialog.
    b.click("#welcome-open-folder");
    b.wait_for("the folder dialog", "document.getElementById('open-folder-dialog').open");
    b.click("#open-folder-dialog form[method=dialog] button");
    b.wait_for("the dialog closed", "!document.getElementById('open-folder-dialog').open");

    // The demo's facade: the scene restauro-demo writes for the demo, drawn in the view.
    let asked = b.eval("performance.now()").as_f64().unwrap();
    b.click("#open-demo");
    b.wait_for("the facade drawn", "document.getElementById('view').dataset.firstFrameMs");
    let waited_ms =
        b.eval("Number(document.getElementById('view').dataset.firstFrameMs)").as_f64().unwrap()
            - asked;
    b.wait_for(
        "the facade's figures",
        "/triangles/.test(document.getElementById('scene-status').textContent)",
    );
    assert_eq!(b.eval("document.getElementById('welcome').checkVisibility()"), false);
    let triangles = restauro_demo::scenes::aosta::generate(1280, 720, 1).triangles;
    let status = b.eval("document.getElementById('scene-status').textContent");
    let shown = format!("{} triangles", group_thousands(triangles));
    assert!(
        status.as_str().unwrap().starts_with(&shown),
        "{status} is not the demo's facade ({shown})"
    );
    let (width, height) = (
        b.eval("document.getElementById('snap-width').value"),
        b.eval("document.getElementById('snap-height').value"),
    );
    assert_eq!((width, height), (json!("1280"), json!("720")));
    b.docs_picture(&shots(), "studio.png");

    // Opened again, the page draws the facade without being asked: the time a restorer waits.
    b.goto(&page);
    b.wait_for("the facade drawn", "document.getElementById('view').dataset.firstFrameMs");
    let first_frame_ms = b.eval("Number(document.getElementById('view').dataset.firstFrameMs)");
    eprintln!(
        "studio_access: the demo's facade: {:.2} s from the click to its first frame; {first_frame_ms} ms \
         from opening the page (signed in, the scene held) to its first frame, at 1920 × 1080",
        waited_ms / 1000.0
    );
}

/// `n` with a comma between each group of three digits, as the page's `toLocaleString('en')`.
fn group_thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[test]
fn an_error_shows_where_the_action_was_taken_in_the_servers_words() {
    if !available("studio_access") {
        return;
    }
    let (_c, mut b, _dir) = scene_held();
    // The server's words, as the page received them: every reply's `error`, kept by the test.
    b.eval(
        "window.replies = []; const f = window.fetch; window.fetch = async (...a) => { \
           const r = await f(...a); r.clone().json().then(j => j && j.error && window.replies.push(j.error), () => {}); \
           return r; }; true",
    );
    b.eval("document.getElementById('sky-lux').value = '-5'");
    b.click("#set-sky");
    b.wait_for("the server's refusal", "window.replies.length > 0");
    let words = b.eval("window.replies[0]");
    b.wait_for("the refusal shown", "document.querySelector('#light .action-problem')");
    let shown = b.eval(
        "(() => { const p = document.querySelector('#light .action-problem'); \
           return [p.textContent, p.checkVisibility(), p.previousElementSibling.contains(document.getElementById('set-sky'))]; })()",
    );
    assert_eq!(shown, json!([words, true, true]), "the refusal is not shown beside Set the sky");
    assert_eq!(
        b.eval("document.getElementById('problem').hidden"),
        true,
        "shown over the view too"
    );
    let light = b.eval("document.getElementById('sky-lux').closest('section').id");
    assert_eq!(light, "light");
    b.screenshot(&shots().join("62-error-in-place.png"));

    // A good sky: the refusal goes.
    b.eval("document.getElementById('sky-lux').value = '10000'");
    b.click("#set-sky");
    b.wait_for("the refusal cleared", "!document.querySelector('#light .action-problem')");
}

/// Presses `key` on the view with Shift held when `shift`.
fn key_on_view(b: &mut Browser, key: &str, shift: bool) {
    for kind in ["keyDown", "keyUp"] {
        b.call(
            "Input.dispatchKeyEvent",
            json!({ "type": kind, "key": key, "code": key, "modifiers": if shift { 8 } else { 0 } }),
        );
    }
}

/// The view's camera: its position and the point it orbits (`studioViewer.pose()`, in the
/// preview's frame).
fn pose(b: &mut Browser) -> ([f64; 3], [f64; 3]) {
    let p = b
        .eval("(() => { const p = window.studioViewer.pose(); return [p.position, p.target]; })()");
    serde_json::from_value(p).unwrap()
}

/// The camera's up, the vertical the view orbits about.
fn up(b: &mut Browser) -> [f64; 3] {
    serde_json::from_value(b.eval("window.studioViewer.pose().up")).unwrap()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The angle (degrees) from `a` to `b` seen along `axis` (a unit vector): both projected on the
/// plane at a right angle to it.
fn turn_about(axis: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let flat = |v: [f64; 3]| {
        let k = dot(v, axis);
        [v[0] - k * axis[0], v[1] - k * axis[1], v[2] - k * axis[2]]
    };
    let (a, b) = (flat(a), flat(b));
    let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    dot(cross, axis).atan2(dot(a, b)).to_degrees()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[test]
fn the_view_orbits_pans_and_zooms_by_keyboard() {
    if !available("studio_access") {
        return;
    }
    let (_c, mut b, _dir) = scene_held();
    b.eval("document.getElementById('view').focus()");
    let listed = b.eval("document.getElementById('shortcuts').textContent");
    for what in ["orbit", "pan", "zoom in"] {
        assert!(listed.as_str().unwrap().contains(what), "the shortcuts do not list {what}");
    }

    // ← orbits 5° about the vertical through the centre: the distance kept, the centre kept.
    let (p0, t0) = pose(&mut b);
    key_on_view(&mut b, "ArrowLeft", false);
    let (p1, t1) = pose(&mut b);
    assert!(norm(sub(t1, t0)) < 1e-9, "the centre moved: {t0:?} → {t1:?}");
    let (r0, r1) = (sub(p0, t0), sub(p1, t1));
    assert!((norm(r0) - norm(r1)).abs() < 1e-6 * norm(r0), "the distance changed");
    let vertical = up(&mut b);
    let turned = turn_about(vertical, r0, r1);
    assert!((turned.abs() - 5.0).abs() < 0.01, "turned {turned}° about the vertical, not 5°");

    // + goes 10 % nearer; − back.
    key_on_view(&mut b, "+", false);
    let (p2, t2) = pose(&mut b);
    let ratio = norm(sub(p2, t2)) / norm(r1);
    assert!((ratio - 1.0 / 1.1).abs() < 1e-6, "+ went to {ratio} of the distance");
    key_on_view(&mut b, "-", false);
    let (p3, t3) = pose(&mut b);
    assert!((norm(sub(p3, t3)) - norm(r1)).abs() < 1e-6 * norm(r1), "− did not go back");

    // Shift+→ pans: the camera and the centre move together.
    key_on_view(&mut b, "ArrowRight", true);
    let (p4, t4) = pose(&mut b);
    let (moved, camera_moved) = (sub(t4, t3), sub(p4, p3));
    assert!(norm(moved) > 1e-3, "Shift+→ did not pan");
    assert!(norm(sub(moved, camera_moved)) < 1e-6 * norm(moved).max(1.0), "a pan turned the view");
}
