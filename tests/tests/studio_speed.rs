//! How fast the studio opens and draws a survey-sized model: a scene of 1 000 000 triangles (a
//! relief of 500 × 1000 quads, binary PLY), opened in headless Chromium with software GL
//! against a real coordinator. Measured, not asserted: it prints a JSON line with the time
//! from opening the page to the model drawn, the frames per second while orbiting (the coarse
//! copy a big model carries, at the screen's resolution) and still (the model itself, at twice
//! it).
//!
//! `cargo test --release -p restauro-tests --test studio_speed -- --ignored --nocapture`
//! (`RESTAURO_SPEED_QUADS=316x158` for a model of 100 000 triangles).

use restauro_tests::CLIENT_TOKEN;
use restauro_tests::browser::{Browser, available};
use std::time::Instant;

#[test]
#[ignore = "a measurement: run it by name with --ignored"]
fn a_model_of_a_million_triangles_opens_and_orbits() {
    if !available("studio_speed") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let quads = std::env::var("RESTAURO_SPEED_QUADS").unwrap_or_else(|_| "1000x500".into());
    let (nx, ny) = quads.split_once('x').expect("RESTAURO_SPEED_QUADS: NXxNY, e.g. 1000x500");
    let (_c, page, _worker) =
        restauro_tests::relief::relief_studio(d, nx.parse().unwrap(), ny.parse().unwrap());
    let mut b = Browser::launch(1280, 720);
    let start = Instant::now();
    b.goto(&format!("{page}#token={CLIENT_TOKEN}"));
    b.wait_for("the model", "window.studioViewer && window.studioViewer.frames > 0 && document.getElementById('view').dataset.scene");
    let first_frame_s = start.elapsed().as_secs_f64();
    let triangles = b.eval("document.getElementById('scene-status').textContent");
    // Orbit for 5 s as a drag does (the view in motion), a frame at each animation frame, and
    // count them.
    let fps = b.eval(
        "new Promise((done) => { const v = window.studioViewer, t0 = performance.now(); let n = 0; \
         v.moving(true); \
         const step = () => { v.camera.position.applyAxisAngle(v.camera.up, 0.01); \
           v.camera.lookAt(v.controls.target); v.draw(); n += 1; \
           if (performance.now() - t0 < 5000) requestAnimationFrame(step); \
           else { const fps = n / ((performance.now() - t0) / 1000); v.moving(false); done(fps); } }; \
         requestAnimationFrame(step); })",
    );
    // Still: the model itself, at the still view's resolution, drawn again and again.
    let still_fps = b.eval(
        "new Promise((done) => { const v = window.studioViewer, t0 = performance.now(); let n = 0; \
         const step = () => { v.draw(); n += 1; \
           if (performance.now() - t0 < 3000) requestAnimationFrame(step); \
           else done(n / ((performance.now() - t0) / 1000)); }; \
         requestAnimationFrame(step); })",
    );
    // The measurement is this test's output (run with --nocapture).
    #[allow(clippy::print_stdout)]
    let print = |line: String| println!("{line}");
    print(format!(
        "{}",
        serde_json::json!({
            "measure": "studio_speed",
            "triangles": triangles,
            "open_to_first_frame_s": first_frame_s,
            "orbit_fps": fps,
            "still_fps": still_fps,
            "browser": "headless chromium, software GL (SwiftShader), 1280 × 720",
        })
    ));
}

/// How long a restorer waits for a snapshot of the demo's facade: the Aosta scene at 1280 × 720
/// on a coordinator with two workers of one thread each (`restauro studio` on two cores),
/// the snapshot form's defaults (a cap of 16 samples, a 15 % noise target), from the click on
/// "Take snapshot" to the seen image shown over the view. Measured, not asserted: it prints a
/// JSON line.
///
/// `cargo test --release -p restauro-tests --test studio_speed -- --ignored --nocapture snapshot`
#[test]
#[ignore = "a measurement: run it by name with --ignored"]
fn a_snapshot_of_the_facade_from_the_click_to_the_seen_image() {
    if !available("studio_speed") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let farm = restauro_tests::Coordinator::studio_farm(dir.path(), 1280, 720);
    // A second worker of one thread beside the farm's first, as `restauro studio`'s embedded
    // cluster has on two cores.
    let _second = restauro_tests::Worker::start(dir.path(), &farm.coordinator.url, "local-2", &[]);
    // The scene reaches the farm with a quick render from the command line, as in every
    // studio test; it is waited for, so that its time is not the snapshot's.
    let c = &farm.coordinator;
    let first = restauro_tests::submit(&farm.scene, &["--spp", "1"], &c.url, &farm.token);
    let o = restauro_tests::client(&["watch", &first], &c.url, &farm.token);
    assert!(o.status.success(), "{}", restauro_tests::text(&o));
    let mut b = farm.page_in_browser(1280, 720);
    let shown = "(() => { const i = document.getElementById('result-image'); \
        return !document.getElementById('result').hidden && i.complete && i.naturalWidth === 1280; })()";
    let start = Instant::now();
    b.click("#take-snapshot");
    b.wait_for("the snapshot's seen image", shown);
    let seconds = start.elapsed().as_secs_f64();
    let spp = b.eval("document.getElementById('snap-spp').value");
    let noise = b.eval("document.getElementById('snap-noise').value");
    #[allow(clippy::print_stdout)]
    let print = |line: String| println!("{line}");
    print(format!(
        "{}",
        serde_json::json!({
            "measure": "studio_snapshot",
            "scene": "aosta 1280 × 720",
            "samples_per_pixel_cap": spp,
            "noise_target_percent": noise,
            "click_to_seen_image_s": seconds,
            "farm": "one coordinator, two workers of one thread, on this machine",
        })
    ));
}
