//! The Retinex on rendered images: a single firefly (or a glint) is not the white.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, load_scene};
use restauro_spectral::appearance::{ChannelSpace, retinex_xyz};
use restauro_spectral::retinex::RetinexParams;

const W: u32 = 96;
const H: u32 = 64;

/// A grey ground, a white tile and a wall under a summer sun and a clear sky, path traced at 4
/// samples per pixel (so with Monte Carlo noise), in absolute XYZ.
fn render() -> Vec<[f32; 3]> {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("grey.csv"), "380,0.3\n780,0.3\n").unwrap();
    std::fs::write(d.join("white.csv"), "380,0.8\n780,0.8\n").unwrap();
    std::fs::write(
        d.join("ground.obj"),
        "v -20 -20 0\nv 20 -20 0\nv 20 20 0\nv -20 20 0\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(
        d.join("tile.obj"),
        "v -1 -1 0.01\nv 1 -1 0.01\nv 1 1 0.01\nv -1 1 0.01\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(d.join("wall.obj"), "v -6 3 0\nv 6 3 0\nv 6 3 3\nv -6 3 3\nf 1 2 3 4\n")
        .unwrap();
    let toml = format!(
        r#"format = 1
[camera]
position = [0.0, -9.0, 5.0]
target = [0.0, 0.0, 0.5]
width = {W}
height = {H}
[render]
integrator = "path"
samples_per_pixel = 4
max_depth = 4
seed = 5
[spectra]
grey = {{ file = "grey.csv" }}
white = {{ file = "white.csv" }}
daylight = {{ illuminant = "D65" }}
[materials.grey]
model = "lambert"
reflectance = "grey"
[materials.white]
model = "lambert"
reflectance = "white"
[[objects]]
name = "ground"
mesh = "ground.obj"
material = "grey"
[[objects]]
name = "tile"
mesh = "tile.obj"
material = "white"
[[objects]]
name = "wall"
mesh = "wall.obj"
material = "grey"
[[lights]]
kind = "sun"
illuminance_lux = 80000.0
azimuth_deg = 200.0
elevation_deg = 50.0
spectrum = "daylight"
[[lights]]
kind = "sky"
illuminance_lux = 15000.0
model = "uniform"
spectrum = "daylight"
"#
    );
    std::fs::write(d.join("scene.toml"), toml).unwrap();
    let loaded = load_scene(&d.join("scene.toml"), &Limits::default()).unwrap();
    let r = &loaded.file.render;
    let settings = Settings {
        integrator: r.integrator,
        samples_per_pixel: r.samples_per_pixel,
        max_depth: r.max_depth,
        seed: r.seed,
    };
    let prepared = PreparedScene::new(&loaded, None, settings).unwrap();
    render_tile(&prepared, Rect { x: 0, y: 0, width: W, height: H }, false).xyz
}

/// A firefly 10⁴ times the brightest pixel, put into a rendered image, changes the Retinex
/// output nowhere else by as much as 1 % (relative, in every channel).
#[test]
fn a_firefly_does_not_become_the_white() {
    let image = render();
    let brightest = image.iter().map(|p| p[1]).fold(0.0f32, f32::max);
    let firefly = (H as usize / 2) * W as usize + W as usize / 3;
    let mut with_firefly = image.clone();
    with_firefly[firefly] = [1e4 * brightest; 3];
    let params = RetinexParams { seed: 8, ..Default::default() };
    let run = |img: &[[f32; 3]]| {
        retinex_xyz(img, W as usize, H as usize, &params, ChannelSpace::default(), &|_, _| {})
            .unwrap()
            .0
    };
    let (before, after) = (run(&image), run(&with_firefly));
    let mut worst = 0.0f64;
    for (i, (a, b)) in before.iter().zip(&after).enumerate() {
        if i == firefly {
            continue;
        }
        for c in 0..3 {
            let change = (f64::from(b[c]) / f64::from(a[c]) - 1.0).abs();
            if a[c] > 0.0 {
                worst = worst.max(change);
            }
        }
    }
    eprintln!("largest relative change away from the firefly: {worst:.2e}");
    assert!(worst < 0.01, "{worst}");
    // The paper's rule takes the firefly as the white: the same image darkens by orders of
    // magnitude (the premise of the test).
    let paper =
        RetinexParams { white: restauro_spectral::retinex::WhiteReference::Paper, ..params };
    let darkened = retinex_xyz(
        &with_firefly,
        W as usize,
        H as usize,
        &paper,
        ChannelSpace::default(),
        &|_, _| {},
    )
    .unwrap()
    .0;
    let mean =
        |img: &[[f32; 3]]| img.iter().map(|p| f64::from(p[1])).sum::<f64>() / img.len() as f64;
    assert!(mean(&darkened) < 0.1 * mean(&before), "{} vs {}", mean(&darkened), mean(&before));
}
