//! A textured scan as photogrammetry exports it (`data/scans/weathered-patch.glb`: a pitted
//! travertine face with black crust, a lichen colony and a rust stain in its photo, made by
//! `data/scans/make_patch.py`) renders with spectral detail over the measured spectrum it is
//! bound to: in luminance mode every point reflects the measured spectrum scaled, on average
//! by 1; in chromatic mode the spectrum's shape follows the photo's hue (greener texels reflect
//! more green against red); and the rendered face shows the photo, which it does not without.
//! The same patch as a laser scanner exports it (`weathered-patch.ply`: a colour per vertex, the
//! photo averaged over each vertex's share of it, and no photo) shows the same crust, lichen
//! and rust.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use std::path::Path;

const SCAN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/scans/weathered-patch.glb");
const COLOURED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/scans/weathered-patch.ply");
/// The bands of 550 nm and 650 nm on the 5 nm grid from 380 nm.
const GREEN: usize = 34;
const RED: usize = 54;

/// The scan, facing south (its file's +Z; the file is Y-up), seen from 1.2 m in front.
fn scene_in(dir: &Path, detail: &str) -> LoadedScene {
    scene_of(dir, SCAN, detail)
}

/// [`scene_in`] with the scan's file `mesh` (either of the patch's files: both are Y-up).
fn scene_of(dir: &Path, mesh: &str, detail: &str) -> LoadedScene {
    let file = format!("scan.{}", Path::new(mesh).extension().unwrap().to_str().unwrap());
    std::fs::copy(mesh, dir.join(&file)).unwrap();
    let toml = format!(
        "format = 1\n[camera]\nposition = [0.0, -1.2, 0.0]\ntarget = [0.0, 0.0, 0.0]\nvertical_fov_deg = 20.0\nwidth = 32\nheight = 32\n\
         [render]\nintegrator = \"whitted\"\nsamples_per_pixel = 4\nmax_depth = 1\n\
         [spectra]\nday = {{ illuminant = \"D65\" }}\ntravertine = \"travertine_tufa_solid__eco_ward73\"\n\
         [materials.travertine]\nmodel = \"lambert\"\nreflectance = \"travertine\"\ndetail = \"{detail}\"\n\
         [[objects]]\nname = \"scan\"\nmesh = \"{file}\"\nup_axis = \"y\"\nmaterial = \"travertine\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 10000.0\nazimuth_deg = 180.0\nelevation_deg = 30.0\nspectrum = \"day\"\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

fn prepare(scene: &LoadedScene) -> PreparedScene {
    let settings = Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: 4,
        max_depth: 1,
        seed: 3,
        grids: false,
        noise_target: 0.0,
    };
    PreparedScene::new(scene, None, settings).unwrap()
}

/// The reflectance where a ray from the south meets the face at (x, z), and the photo's
/// texel there (its u, v from the patch's corners: the patch spans ±0.25 m).
fn probe(prepared: &PreparedScene, scene: &LoadedScene, x: f32, z: f32) -> (Spectrum, [f32; 3]) {
    probe_over(prepared, scene, x, z, 0.0)
}

/// [`probe`] with the photo filtered over `footprint_m`.
fn probe_over(
    prepared: &PreparedScene,
    scene: &LoadedScene,
    x: f32,
    z: f32,
    footprint_m: f32,
) -> (Spectrum, [f32; 3]) {
    let hit = prepared.intersect(Vec3A::new(x, -1.0, z), Vec3A::Y, f32::INFINITY).unwrap();
    let mut buffer = Spectrum::ZERO;
    let rho = *prepared.reflectance(&hit, footprint_m, &mut buffer);
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

/// The laser scanner's export of the patch: its vertex colours, interpolated over 64 × 64
/// cells where the photo has 256 × 256 texels, scale the measured spectrum as the photo seen
/// at their spacing does (by about 1 on average), and in chromatic mode its spectra follow the
/// photo's hue; the rendered face shows them.
#[test]
fn the_scan_as_a_coloured_ply_shows_what_its_photo_shows() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, coloured) =
        (scene_in(dir.path(), "luminance"), scene_of(dir.path(), COLOURED, "luminance"));
    assert_eq!(coloured.objects[0].mesh.triangles.len(), 8192);
    assert!(coloured.objects[0].mesh.groups[0].photo.is_none());
    let (photo_prepared, coloured_prepared) = (prepare(&photo), prepare(&coloured));
    let plain = scene_of(dir.path(), COLOURED, "none");
    let plain_prepared = prepare(&plain);
    let (mut by_photo, mut by_colour) = (Vec::new(), Vec::new());
    for (x, z) in grid() {
        let (measured, _) = probe(&plain_prepared, &photo, x, z);
        let (rho, _) = probe(&coloured_prepared, &photo, x, z);
        // The photo filtered over the vertices' spacing, 0.5 m / 64.
        let (shown, _) = probe_over(&photo_prepared, &photo, x, z, 0.5 / 64.0);
        assert!(rho.0.iter().all(|r| (0.0..=1.0).contains(r)), "({x}, {z}): {rho:?}");
        by_colour.push(f64::from(rho.0[GREEN] / measured.0[GREEN]));
        by_photo.push(f64::from(shown.0[GREEN] / measured.0[GREEN]));
    }
    let mean = by_colour.iter().sum::<f64>() / by_colour.len() as f64;
    let c = correlation(&by_photo, &by_colour);
    eprintln!("vertex colours: mean scale {mean:.3}, correlation with the photo's {c:.3}");
    assert!((mean - 1.0).abs() < 0.06, "the vertex colours' detail averages {mean}, not 1");
    assert!(c > 0.9, "the vertex colours follow the photo by a correlation of only {c}");

    let chromatic = scene_of(dir.path(), COLOURED, "chromatic");
    let prepared = prepare(&chromatic);
    let (mut greenness, mut green_over_red) = (Vec::new(), Vec::new());
    for (x, z) in grid() {
        let (_, [r, g, _]) = probe(&photo_prepared, &photo, x, z);
        let (rho, _) = probe(&prepared, &photo, x, z);
        if r < 0.02 {
            continue;
        }
        greenness.push(f64::from(g / r));
        green_over_red.push(f64::from(rho.0[GREEN] / rho.0[RED]));
    }
    let c = correlation(&greenness, &green_over_red);
    eprintln!("chromatic: green/red correlation {c:.3}");
    assert!(c > 0.8, "the spectra's green/red follows the photo's by a correlation of only {c}");
    let (with, without) = (spread(&prepared), spread(&plain_prepared));
    eprintln!("spread {with:.3} with the colours, {without:.3} without");
    assert!(with > 2.0 * without, "spread {with} with the colours, {without} without");
}
