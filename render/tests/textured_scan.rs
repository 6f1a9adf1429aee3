//! A textured scan as photogrammetry exports it (`data/scans/weathered-patch.glb`: a pitted
//! travertine face with black crust, a lichen colony and a rust stain in its photo, made by
//! `data/scans/make_patch.py`) renders with spectral detail over the measured spectrum it is
//! bound to: in luminance mode every point reflects the measured spectrum scaled, on average
//! by 1; in chromatic mode the spectrum's shape follows the photo's hue (greener texels reflect
//! more green against red); and the rendered face shows the photo, which it does not without.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_scene};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use std::path::Path;

const SCAN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/scans/weathered-patch.glb");
/// The bands of 550 nm and 650 nm on the 5 nm grid from 380 nm.
const GREEN: usize = 34;
const RED: usize = 54;

/// The scan, facing south (its file's +Z; the file is Y-up), seen from 1.2 m in front.
fn scene_in(dir: &Path, detail: &str) -> LoadedScene {
    std::fs::copy(SCAN, dir.join("scan.glb")).unwrap();
    let toml = format!(
        "format = 1\n[camera]\nposition = [0.0, -1.2, 0.0]\ntarget = [0.0, 0.0, 0.0]\nvertical_fov_deg = 20.0\nwidth = 32\nheight = 32\n\
         [render]\nintegrator = \"whitted\"\nsamples_per_pixel = 4\nmax_depth = 1\n\
         [spectra]\nday = {{ illuminant = \"D65\" }}\ntravertine = \"travertine_tufa_solid__eco_ward73\"\n\
         [materials.travertine]\nmodel = \"lambert\"\nreflectance = \"travertine\"\ndetail = \"{detail}\"\n\
         [[objects]]\nname = \"scan\"\nmesh = \"scan.glb\"\nmaterial = \"travertine\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 10000.0\nazimuth_deg = 180.0\nelevation_deg = 30.0\nspectrum = \"day\"\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_scene(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

fn prepare(scene: &LoadedScene) -> PreparedScene {
    let settings = Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: 4,
        max_depth: 1,
        seed: 3,
        grids: false,
    };
    PreparedScene::new(scene, None, settings).unwrap()
}

/// The reflectance where a ray from the south meets the face at (x, z), and the photo's
/// texel there (its u, v from the patch's corners: the patch spans ±0.25 m).
fn probe(prepared: &PreparedScene, scene: &LoadedScene, x: f32, z: f32) -> (Spectrum, [f32; 3]) {
    let hit = prepared.intersect(Vec3A::new(x, -1.0, z), Vec3A::Y, f32::INFINITY).unwrap();
    let mut buffer = Spectrum::ZERO;
    let rho = *prepared.reflectance(&hit, 0.0, &mut buffer);
    let photo = scene.objects[0].mesh.groups[0].photo.as_ref().expect("the scan's photo");
    let texel = |t: f32, n: u32| ((t * n as f32) as u32).min(n - 1);
    let (u, v) = (x / 0.5 + 0.5, 0.5 - z / 0.5);
    (rho, photo.linear_rgb(texel(u, photo.width), texel(v, photo.height)))
}

/// Points on a grid over the face, away from its edges.
fn grid() -> impl Iterator<Item = (f32, f32)> {
    (0..24).flat_map(|i| (0..24).map(move |j| (-0.23 + 0.02 * i as f32, -0.23 + 0.02 * j as f32)))
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let var = |v: &[f64], m: f64| v.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    cov / (var(a, ma) * var(b, mb)).sqrt()
}

#[test]
fn the_scans_photo_scales_the_measured_spectrum_by_its_luminance() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_in(dir.path(), "luminance");
    assert_eq!(scene.objects[0].mesh.triangles.len(), 8192);
    let prepared = prepare(&scene);
    // Without its photo the face reflects the measured spectrum everywhere.
    let plain_dir = tempfile::tempdir().unwrap();
    let plain = scene_in(plain_dir.path(), "none");
    let (measured, _) = probe(&prepare(&plain), &plain, 0.0, 0.0);
    let mut scales = Vec::new();
    for (x, z) in grid() {
        let (rho, _) = probe(&prepared, &scene, x, z);
        let scale = rho.0[GREEN] / measured.0[GREEN];
        for (band, (r, m)) in rho.0.iter().zip(measured.0).enumerate() {
            assert!(*r <= 1.0 && *r >= 0.0, "band {band}: {r}");
            assert!(
                (r / m - scale).abs() < 1e-4 * scale.max(1.0),
                "band {band}: {} against {scale}",
                r / m
            );
        }
        scales.push(f64::from(scale));
    }
    let mean = scales.iter().sum::<f64>() / scales.len() as f64;
    let (lo, hi) = scales.iter().fold((f64::MAX, f64::MIN), |(l, h), s| (l.min(*s), h.max(*s)));
    assert!((mean - 1.0).abs() < 0.06, "the detail averages {mean}, not 1");
    assert!(lo < 0.3 && hi > 1.1, "the pits and the stone differ: {lo} to {hi}");
}

#[test]
fn in_chromatic_mode_the_spectrum_follows_the_photos_hue() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_in(dir.path(), "chromatic");
    let prepared = prepare(&scene);
    let (mut greenness, mut green_over_red) = (Vec::new(), Vec::new());
    for (x, z) in grid() {
        let (rho, [r, g, _]) = probe(&prepared, &scene, x, z);
        if r < 0.02 {
            continue; // the black crust: no hue to speak of
        }
        greenness.push(f64::from(g / r));
        green_over_red.push(f64::from(rho.0[GREEN] / rho.0[RED]));
    }
    let c = correlation(&greenness, &green_over_red);
    assert!(c > 0.9, "the spectra's green/red follows the texels' by a correlation of only {c}");
}

/// Relative spread of the rendered luminance over the face's pixels.
fn spread(prepared: &PreparedScene) -> f64 {
    let tile = render_tile(prepared, Rect { x: 8, y: 8, width: 16, height: 16 }, false);
    let y: Vec<f64> = tile.xyz.iter().map(|p| f64::from(p[1])).collect();
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    assert!(mean > 0.0, "the face is lit");
    (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len() as f64).sqrt() / mean
}

#[test]
fn the_rendered_face_shows_the_photo() {
    let dir = tempfile::tempdir().unwrap();
    let with = spread(&prepare(&scene_in(dir.path(), "chromatic")));
    let without = spread(&prepare(&scene_in(dir.path(), "none")));
    assert!(with > 2.0 * without, "spread {with} with the photo, {without} without");
}
