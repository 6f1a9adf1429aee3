//! Adaptive sampling (`restauro_render::adaptive`) against closed forms: a pixel's mean is its
//! own samples' mean whatever their count, its error is what its estimate says, and the image is
//! bit-identical whatever the tiles and threads.

use restauro_render::adaptive::BATCH;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, TileResult, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use std::f64::consts::PI;
use std::path::Path;

mod shapes;
use shapes::inward_sphere;

/// A scene folder with a flat grey of reflectance 0.5 on `mesh`.
fn scene(dir: &Path, mesh: &str, camera: &str, lights: &str, render: &str) -> LoadedScene {
    std::fs::write(dir.join("grey.csv"), "380,0.5\n780,0.5\n").unwrap();
    std::fs::write(dir.join("mesh.obj"), mesh).unwrap();
    let toml = format!(
        "format = 1\n{camera}\n{render}\n[spectra]\ngrey = {{ file = \"grey.csv\" }}\n\
         daylight = {{ illuminant = \"D65\" }}\nlamp = {{ illuminant = \"A\" }}\n\
         [materials.grey]\nmodel = \"lambert\"\nreflectance = \"grey\"\n[[objects]]\n\
         name = \"thing\"\nmesh = \"mesh.obj\"\nmaterial = \"grey\"\n{lights}\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

fn settings(scene: &LoadedScene, noise_target: f32) -> Settings {
    Settings { noise_target, ..Settings::from(&scene.file.render) }
}

fn whole(prepared: &PreparedScene) -> Rect {
    Rect { x: 0, y: 0, width: prepared.camera.width, height: prepared.camera.height }
}

fn counts(tile: &TileResult) -> &[u32] {
    tile.samples.as_deref().expect("an adaptive render carries each pixel's count")
}

const PLANE: &str = "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nf 1 2 3 4\n";
const LOOK_DOWN: &str = "[camera]\nposition = [0.0, 0.0, 10.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvertical_fov_deg = 60.0\nwidth = 9\nheight = 9";

/// Under a sun at the zenith every sample of a Lambertian plane has the same luminance ρ·E/π:
/// a pixel that sees no spread stops as soon as the prior's doubt, 1/n, is within the target
/// (at 5 %: after 24 samples, three batches), and its mean, divided by the samples it took (not
/// by the cap), is the closed form within 1e-4.
#[test]
fn a_quiet_pixel_stops_early_at_the_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let lights = "[[lights]]\nkind = \"sun\"\nilluminance_lux = 100000.0\nazimuth_deg = 0.0\nelevation_deg = 90.0\nspectrum = \"daylight\"";
    let render = "[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 64\nmax_depth = 1";
    let loaded = scene(dir.path(), PLANE, LOOK_DOWN, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded, 0.05)).unwrap();
    let tile = render_tile(&prepared, whole(&prepared), false);
    assert!(counts(&tile).iter().all(|&n| n == 3 * BATCH), "{:?}", counts(&tile));
    let expect = 0.5 * 100_000.0 / PI;
    for p in &tile.xyz {
        assert!((f64::from(p[1]) / expect - 1.0).abs() < 1e-4, "{} vs {expect}", p[1]);
    }
    // Without a target the same render takes every sample and carries no counts.
    let fixed = PreparedScene::new(&loaded, None, settings(&loaded, 0.0)).unwrap();
    assert!(render_tile(&fixed, whole(&fixed), false).samples.is_none());
}

/// The furnace: inside a sphere of reflectance 0.5 around an isotropic source of I cd, every
/// wall pixel has luminance I/π exactly, so each pixel's true error is known. Path traced to a
/// noise target t, the pixels that stopped before the cap must have a root-mean-square relative
/// error within 1.5 t (their estimate said at most t; the estimate is itself noisy, and the
/// facets add a little), and a target ten times looser must give a larger error with fewer
/// samples.
#[test]
fn the_furnace_is_rendered_to_its_noise_target() {
    let dir = tempfile::tempdir().unwrap();
    let camera = "[camera]\nposition = [0.0, 0.0, 0.0]\ntarget = [1.0, 0.3, 0.2]\nvertical_fov_deg = 90.0\nwidth = 24\nheight = 24";
    let lights = "[[lights]]\nkind = \"point\"\nposition = [0.0, 0.0, 0.0]\nintensity_cd = 100.0\nspectrum = \"daylight\"";
    let render =
        "[render]\nintegrator = \"path\"\nsamples_per_pixel = 2048\nmax_depth = 40\nseed = 5";
    let loaded = scene(dir.path(), &inward_sphere(), camera, lights, render);
    let expect = 100.0 / PI;
    let measure = |target: f32| {
        let prepared = PreparedScene::new(&loaded, None, settings(&loaded, target)).unwrap();
        let tile = render_tile(&prepared, whole(&prepared), false);
        let n = counts(&tile);
        let stopped: Vec<f64> = tile
            .xyz
            .iter()
            .zip(n)
            .filter(|&(_, &n)| n < 2048)
            .map(|(p, _)| f64::from(p[1]) / expect - 1.0)
            .collect();
        assert!(stopped.len() * 10 > n.len() * 9, "{} of {} stopped", stopped.len(), n.len());
        let rms = (stopped.iter().map(|e| e * e).sum::<f64>() / stopped.len() as f64).sqrt();
        let mean_n = n.iter().map(|&n| f64::from(n)).sum::<f64>() / n.len() as f64;
        (rms, mean_n)
    };
    let (tight, tight_n) = measure(0.02);
    assert!(tight < 1.5 * 0.02, "RMS relative error {tight} at a target of 2 %");
    let (loose, loose_n) = measure(0.2);
    assert!(loose < 1.5 * 0.2, "RMS relative error {loose} at a target of 20 %");
    assert!(
        loose > 2.0 * tight && loose_n * 4.0 < tight_n,
        "{loose} ({loose_n}) vs {tight} ({tight_n})"
    );
}

/// The same image, counts included, bit for bit, in tiles of 16 on one thread and of 64 on
/// two: each pixel decides from its own keyed samples alone.
#[test]
fn adaptive_images_are_bit_identical_across_tiles_and_threads() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = format!("{PLANE}v -1 -1 0\nv 1 -1 0\nv 1 -1 2\nv -1 -1 2\nf 5 6 7 8\n");
    let camera =
        "[camera]\nposition = [3.0, -6.0, 3.0]\ntarget = [0.0, 0.0, 0.5]\nwidth = 70\nheight = 40";
    let lights = "[[lights]]\nkind = \"sun\"\nilluminance_lux = 50000.0\nazimuth_deg = 200.0\nelevation_deg = 40.0\nspectrum = \"daylight\"\n[[lights]]\nkind = \"point\"\nposition = [0.5, -3.0, 1.0]\nintensity_cd = 500.0\nspectrum = \"lamp\"";
    let render =
        "[render]\nintegrator = \"path\"\nsamples_per_pixel = 32\nmax_depth = 6\nseed = 12";
    let loaded = scene(dir.path(), &mesh, camera, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded, 0.05)).unwrap();
    let render_in_tiles = |size: u32| {
        let mut image = vec![([0.0f32; 3], 0u32); 70 * 40];
        for ty in (0..40).step_by(size as usize) {
            for tx in (0..70).step_by(size as usize) {
                let rect =
                    Rect { x: tx, y: ty, width: size.min(70 - tx), height: size.min(40 - ty) };
                let tile = render_tile(&prepared, rect, false);
                for (i, (p, &n)) in tile.xyz.iter().zip(counts(&tile)).enumerate() {
                    let (x, y) = (rect.x + i as u32 % rect.width, rect.y + i as u32 / rect.width);
                    image[(y * 70 + x) as usize] = (*p, n);
                }
            }
        }
        image
    };
    let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
    let a = pool(1).install(|| render_in_tiles(16));
    let b = pool(2).install(|| render_in_tiles(64));
    let differ = a
        .iter()
        .zip(&b)
        .filter(|((p, n), (q, m))| p.map(f32::to_bits) != q.map(f32::to_bits) || n != m)
        .count();
    assert_eq!(differ, 0, "{differ} pixels differ");
    // Some pixels stopped early and some went on: the counts say something.
    let (least, most) = (a.iter().map(|p| p.1).min(), a.iter().map(|p| p.1).max());
    assert!(least < most, "every pixel took {least:?} samples");
}
