//! How fast the studio opens and draws a survey-sized model: a scene of 1 000 000 triangles (a
//! relief of 500 × 1000 quads, binary PLY), opened in headless Chromium with software GL
//! against a real coordinator. Measured, not asserted: it prints a JSON line with the time
//! from opening the page to the model drawn, and the frames per second while orbiting.
//!
//! `cargo test --release -p restauro-tests --test studio_speed -- --ignored --nocapture`
//! (`RESTAURO_SPEED_QUADS=316x158` for a model of 100 000 triangles).

use restauro_tests::browser::{Browser, available};
use restauro_tests::{CLIENT_TOKEN, Coordinator, Worker, submit};
use std::io::Write;
use std::time::Instant;

/// A binary PLY of a relief `nx × ny` quads (2 triangles each) over 50 m × 25 m, 2 m high.
fn relief(path: &std::path::Path, nx: usize, ny: usize) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let vertices = (nx + 1) * (ny + 1);
    let faces = 2 * nx * ny;
    write!(
        f,
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nelement face {faces}\n\
         property list uchar int vertex_indices\nend_header\n"
    )
    .unwrap();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, z) = (50.0 * i as f32 / nx as f32, 25.0 * j as f32 / ny as f32);
            let y = -(2.0 * ((x * 1.3).sin() * (z * 0.7).cos()).abs());
            for v in [x - 25.0, y, z] {
                f.write_all(&v.to_le_bytes()).unwrap();
            }
        }
    }
    let at = |i: usize, j: usize| (j * (nx + 1) + i) as i32;
    for j in 0..ny {
        for i in 0..nx {
            for t in [
                [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
            ] {
                f.write_all(&[3u8]).unwrap();
                for v in t {
                    f.write_all(&v.to_le_bytes()).unwrap();
                }
            }
        }
    }
}

#[test]
#[ignore = "a measurement: run it by name with --ignored"]
fn a_model_of_a_million_triangles_opens_and_orbits() {
    if !available("studio_speed") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = d.join("relief");
    std::fs::create_dir_all(&scene).unwrap();
    let quads = std::env::var("RESTAURO_SPEED_QUADS").unwrap_or_else(|_| "1000x500".into());
    let (nx, ny) = quads.split_once('x').expect("RESTAURO_SPEED_QUADS: NXxNY, e.g. 1000x500");
    relief(&scene.join("relief.ply"), nx.parse().unwrap(), ny.parse().unwrap());
    std::fs::write(
        scene.join("scene.toml"),
        "format = 1\n[camera]\nposition = [0.0, -60.0, 12.0]\ntarget = [0.0, 0.0, 12.0]\n\
         width = 160\nheight = 90\n[spectra]\nstone = \"travertine_tufa_solid__eco_ward73\"\n\
         sun = { illuminant = \"D55\" }\n[materials.stone]\nmodel = \"lambert\"\nreflectance = \"stone\"\n\
         [[objects]]\nname = \"relief\"\nmesh = \"relief.ply\"\nmaterial = \"stone\"\n\
         [[lights]]\nkind = \"sun\"\npreset = \"sun\"\nspectrum = \"sun\"\n",
    )
    .unwrap();
    let (c, page) = Coordinator::with_studio(d);
    let _worker = Worker::start(d, &c.url, "local-1", &[]);
    let file = scene.join("scene.toml");
    submit(file.to_str().unwrap(), &["--spp", "1"], &c.url, &d.join("client.token"));
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
            "browser": "headless chromium, software GL (SwiftShader), 1280 × 720",
        })
    ));
}
