//! The tracer against closed forms. Tolerances are stated with each test.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, camera_ray, pixel, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::colorimetry::{Observer, absolute_xyz};
use restauro_spectral::keyed_random::KeyedRng;
use std::f64::consts::PI;
use std::path::Path;

mod shapes;
use shapes::inward_sphere;

/// A scene folder: a flat grey reflectance, a mesh, and the scene file around them.
fn scene(dir: &Path, mesh: &str, camera: &str, lights: &str, render: &str) -> LoadedScene {
    scene_of_grey(dir, "{ file = \"grey.csv\" }", mesh, camera, lights, render)
}

/// [`scene`] with the grey's spectrum given (`{ constant = 0.95 }`, say).
fn scene_of_grey(
    dir: &Path,
    grey: &str,
    mesh: &str,
    camera: &str,
    lights: &str,
    render: &str,
) -> LoadedScene {
    std::fs::write(dir.join("grey.csv"), "380,0.5\n780,0.5\n").unwrap();
    std::fs::write(dir.join("mesh.obj"), mesh).unwrap();
    let photometric = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scene/tests/data/photometric/lambertian_cos_1000cd.ies"
    );
    std::fs::copy(photometric, dir.join("cos.ies")).unwrap();
    let toml = format!(
        r#"format = 1
{camera}
{render}
[spectra]
grey = {grey}
daylight = {{ illuminant = "D65" }}
lamp = {{ illuminant = "A" }}
[materials.grey]
model = "lambert"
reflectance = "grey"
[[objects]]
name = "thing"
mesh = "mesh.obj"
material = "grey"
{lights}
"#
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

const PLANE: &str = "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nf 1 2 3 4\n";
const LOOK_DOWN: &str = "[camera]\nposition = [0.0, 0.0, 10.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvertical_fov_deg = 60.0\nwidth = 9\nheight = 9";

fn settings(scene: &LoadedScene) -> Settings {
    let r = &scene.file.render;
    Settings {
        integrator: r.integrator,
        samples_per_pixel: r.samples_per_pixel,
        max_depth: r.max_depth,
        seed: r.seed,
        grids: false,
        noise_target: 0.0,
    }
}

fn luminance(l: &restauro_spectral::Spectrum) -> f64 {
    absolute_xyz(l, Observer::Cie1931TwoDegree).y
}

/// Where the one-sample ray of pixel (x, y) meets the plane z = 0.
fn plane_point(scene: &PreparedScene, x: u32, y: u32) -> Vec3A {
    let (d, _) = camera_ray(scene, x, y, 0);
    let o = scene.camera.origin;
    o + d * (-o.z / d.z)
}

/// A Lambertian plane of reflectance ρ under a perpendicular sun of E_v lux has luminance
/// ρ·E_v/π everywhere (relative error below 1e-4).
#[test]
fn lambertian_plane_under_the_sun() {
    let dir = tempfile::tempdir().unwrap();
    let lights = "[[lights]]\nkind = \"sun\"\nilluminance_lux = 100000.0\nazimuth_deg = 0.0\nelevation_deg = 90.0\nspectrum = \"daylight\"";
    let render = "[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 1\nmax_depth = 1";
    let loaded = scene(dir.path(), PLANE, LOOK_DOWN, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
    let expect = 0.5 * 100_000.0 / PI;
    for (x, y) in [(4, 4), (0, 0), (8, 3)] {
        let l = luminance(&pixel(&prepared, x, y));
        assert!((l / expect - 1.0).abs() < 1e-4, "pixel ({x}, {y}): {l} cd/m² vs {expect}");
    }
}

/// Below a point luminaire of I cd at height h the illuminance follows I·cos α / r² (inverse
/// square and cosine laws): the plane's luminance is ρ/π of it — relative error below 1e-4 for
/// an isotropic source; for an IES file tabulating I0·cos γ every 2.5°, below 2.5e-4, the
/// error of interpolating cos γ linearly between its samples (at most Δγ²/8 = 2.4e-4). Without
/// `intensity_cd` the file is rendered at its own absolute photometry: its table says 1000 cd at
/// the nadir, so the image is the same.
#[test]
fn inverse_square_and_cosine_laws() {
    let intensity = "intensity_cd = 1000.0\n";
    let file = "ies = \"cos.ies\"";
    for (given, light, ies) in [(intensity, "", false), (intensity, file, true), ("", file, true)] {
        let dir = tempfile::tempdir().unwrap();
        let lights = format!(
            "[[lights]]\nkind = \"point\"\nposition = [0.0, 0.0, 2.0]\n{given}spectrum = \"lamp\"\n{light}"
        );
        let render = "[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 1\nmax_depth = 1";
        let loaded = scene(dir.path(), PLANE, LOOK_DOWN, &lights, render);
        let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
        for (x, y) in [(4, 4), (0, 0), (8, 2), (2, 7)] {
            let p = plane_point(&prepared, x, y);
            let r2 = f64::from(p.x * p.x + p.y * p.y + 4.0);
            let cos = 2.0 / r2.sqrt();
            let intensity = if ies { 1000.0 * cos } else { 1000.0 };
            let expect = 0.5 / PI * intensity * cos / r2;
            let l = luminance(&pixel(&prepared, x, y));
            let tolerance = if ies { 2.5e-4 } else { 1e-4 };
            assert!(
                (l / expect - 1.0).abs() < tolerance,
                "ies {ies}, pixel ({x}, {y}): {l} vs {expect}"
            );
        }
    }
}

/// A UV sphere of radius 1 (the "furnace"), inside it an isotropic source of I cd and walls of
/// reflectance ρ = 0.5: every bounce inside a diffuse sphere spreads uniformly, so the wall
/// luminance is ρ·(I/R²)/(π(1 − ρ)) = I/π. The path tracer's image mean must come within 2 %
/// (Monte Carlo noise and the facets of the sphere).
#[test]
fn path_tracer_converges_to_the_furnace_value() {
    let obj = inward_sphere();
    let dir = tempfile::tempdir().unwrap();
    let camera = "[camera]\nposition = [0.0, 0.0, 0.0]\ntarget = [1.0, 0.3, 0.2]\nvertical_fov_deg = 90.0\nwidth = 16\nheight = 16";
    let lights = "[[lights]]\nkind = \"point\"\nposition = [0.0, 0.0, 0.0]\nintensity_cd = 100.0\nspectrum = \"daylight\"";
    let render =
        "[render]\nintegrator = \"path\"\nsamples_per_pixel = 32\nmax_depth = 40\nseed = 5";
    let loaded = scene(dir.path(), &obj, camera, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 16, height: 16 }, false);
    let mean: f64 = tile.xyz.iter().map(|p| f64::from(p[1])).sum::<f64>() / tile.xyz.len() as f64;
    let expect = 100.0 / PI;
    assert!((mean / expect - 1.0).abs() < 0.02, "{mean} vs {expect}");
    // Whitted, which stops after the direct light, gives only the first bounce: ρ·E/π.
    let whitted = PreparedScene::new(
        &loaded,
        None,
        Settings { integrator: Integrator::Whitted, ..settings(&loaded) },
    )
    .unwrap();
    let tile = render_tile(&whitted, Rect { x: 0, y: 0, width: 16, height: 16 }, false);
    let mean: f64 = tile.xyz.iter().map(|p| f64::from(p[1])).sum::<f64>() / tile.xyz.len() as f64;
    assert!((mean / (0.5 * 100.0 / PI) - 1.0).abs() < 0.02, "{mean}");
}

/// A closed sphere of reflectance 0.95 (given as a number): light is reflected twenty times on
/// average before it is absorbed, so a cap on the bounces biases the image, and only a path
/// ended by the roulette alone (`max_depth = 0`) converges. The wall luminance is
/// ρ·(I/R²)/(π(1 − ρ)) = 19·I/π (the integrating sphere's law): the mean of the
/// image within 1.5 % (Monte Carlo noise and the facets). With five surfaces at most, the
/// first five terms of the series: ρ·(I/R²)/π · (1 − ρ⁵)/(1 − ρ), under a quarter of it.
#[test]
fn an_uncapped_path_converges_in_a_sphere_of_reflectance_095() {
    let dir = tempfile::tempdir().unwrap();
    let camera = "[camera]\nposition = [0.0, 0.0, 0.0]\ntarget = [1.0, 0.3, 0.2]\nvertical_fov_deg = 90.0\nwidth = 16\nheight = 16";
    let lights = "[[lights]]\nkind = \"point\"\nposition = [0.0, 0.0, 0.0]\nintensity_cd = 100.0\nspectrum = \"daylight\"";
    let render =
        "[render]\nintegrator = \"path\"\nsamples_per_pixel = 512\nmax_depth = 0\nseed = 7";
    let rho = 0.95;
    let loaded =
        scene_of_grey(dir.path(), "{ constant = 0.95 }", &inward_sphere(), camera, lights, render);
    let mean_of = |settings: Settings| {
        let prepared = PreparedScene::new(&loaded, None, settings).unwrap();
        let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 16, height: 16 }, false);
        tile.xyz.iter().map(|p| f64::from(p[1])).sum::<f64>() / tile.xyz.len() as f64
    };
    let direct = rho * 100.0 / PI;
    let uncapped = mean_of(settings(&loaded));
    let expect = direct / (1.0 - rho);
    assert!((uncapped / expect - 1.0).abs() < 0.015, "{uncapped} vs {expect} cd/m²");
    let capped = mean_of(Settings { max_depth: 5, ..settings(&loaded) });
    let five = direct * (1.0 - rho.powi(5)) / (1.0 - rho);
    assert!((capped / five - 1.0).abs() < 0.015, "{capped} vs {five} cd/m²");
    assert!(capped < 0.25 * uncapped, "{capped} vs {uncapped}");
}

/// The BVH finds the same closest hits as testing every triangle, on the Aosta facade.
#[test]
fn bvh_hits_match_brute_force() {
    let dir = tempfile::tempdir().unwrap();
    let generated = restauro_demo::scenes::aosta::generate(64, 36, 3);
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::write(dir.path().join("meshes/facade.obj"), &generated.facade_obj).unwrap();
    std::fs::write(dir.path().join("aosta.toml"), &generated.scene_toml).unwrap();
    let loaded = load_folder(&dir.path().join("aosta.toml"), &Limits::default()).unwrap();
    let prepared = PreparedScene::new(&loaded, Some("as-found"), settings(&loaded)).unwrap();
    let mut r = KeyedRng::new(9);
    let mut hits = 0;
    for _ in 0..300 {
        let o =
            Vec3A::new(r.next_f32() * 60.0 - 30.0, r.next_f32() * 30.0 - 25.0, r.next_f32() * 25.0);
        let d = Vec3A::new(r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.5).normalize();
        let bvh = prepared.intersect(o, d, f32::INFINITY).map(|h| h.t);
        let brute = prepared.intersect_brute_force(o, d);
        match (bvh, brute) {
            (Some(a), Some(b)) => {
                assert!((a - b).abs() <= 1e-4 * b.max(1.0), "{a} vs {b}");
                hits += 1;
            }
            (None, None) => {}
            other => panic!("{other:?}"),
        }
    }
    assert!(hits > 100, "{hits}");
}

/// The same image, bit for bit, for tile sizes 16 and 64 and for 1 and 2 threads.
#[test]
fn images_are_bit_identical_across_tiles_and_threads() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = format!("{PLANE}v -1 -1 0\nv 1 -1 0\nv 1 -1 2\nv -1 -1 2\nf 5 6 7 8\n");
    let camera =
        "[camera]\nposition = [3.0, -6.0, 3.0]\ntarget = [0.0, 0.0, 0.5]\nwidth = 70\nheight = 40";
    let lights = "[[lights]]\nkind = \"sun\"\nilluminance_lux = 50000.0\nazimuth_deg = 200.0\nelevation_deg = 40.0\nspectrum = \"daylight\"\n[[lights]]\nkind = \"point\"\nposition = [0.5, -3.0, 1.0]\nintensity_cd = 500.0\nspectrum = \"lamp\"";
    let render = "[render]\nintegrator = \"path\"\nsamples_per_pixel = 4\nmax_depth = 6\nseed = 12";
    let loaded = scene(dir.path(), &mesh, camera, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
    let render_in_tiles = |size: u32| {
        let mut image = vec![[0.0f32; 3]; 70 * 40];
        for ty in (0..40).step_by(size as usize) {
            for tx in (0..70).step_by(size as usize) {
                let rect =
                    Rect { x: tx, y: ty, width: size.min(70 - tx), height: size.min(40 - ty) };
                let tile = render_tile(&prepared, rect, false);
                for (i, p) in tile.xyz.iter().enumerate() {
                    let (x, y) = (rect.x + i as u32 % rect.width, rect.y + i as u32 / rect.width);
                    image[(y * 70 + x) as usize] = *p;
                }
            }
        }
        image
    };
    let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
    let a = pool(1).install(|| render_in_tiles(16));
    let b = pool(2).install(|| render_in_tiles(64));
    assert!(
        a.iter().zip(&b).all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits)),
        "images differ"
    );
    assert!(a.iter().any(|p| p[1] > 0.0));
}

fn mean_y(tile: &restauro_render::tile::TileResult) -> f64 {
    tile.xyz.iter().map(|p| f64::from(p[1])).sum::<f64>() / tile.xyz.len() as f64
}

fn sky(model: &str) -> String {
    format!(
        "[[lights]]\nkind = \"sky\"\nilluminance_lux = 10000.0\nmodel = \"{model}\"\nspectrum = \"daylight\""
    )
}

/// A horizontal Lambertian plane open to a sky that gives E_h lux on the horizontal has
/// luminance ρ·E_h/π, whatever the sky's distribution. Under a uniform sky the estimate
/// f·L·π of a cosine-distributed sample is the same for every sample (relative error below
/// 1e-4); under the CIE overcast sky, whose normalisation E_h = 7π L_z/9 this checks, it is a
/// Monte Carlo mean of 20 736 samples (within 1 %). No pixel sees the sky.
#[test]
fn lambertian_plane_under_the_sky() {
    for (model, tolerance) in [("uniform", 1e-4), ("cie-overcast", 0.01)] {
        let dir = tempfile::tempdir().unwrap();
        let render = "[render]\nintegrator = \"path\"\nsamples_per_pixel = 256\nmax_depth = 1";
        let loaded = scene(dir.path(), PLANE, LOOK_DOWN, &sky(model), render);
        let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
        let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 9, height: 9 }, false);
        let expect = 0.5 * 10_000.0 / PI;
        let mean = mean_y(&tile);
        assert!((mean / expect - 1.0).abs() < tolerance, "{model}: {mean} vs {expect}");
        assert_eq!(tile.sky.as_deref(), Some(&[0.0f32; 81][..]), "{model}");
    }
}

/// A vertical plane open to the sky (nothing below the horizon) receives E_v = E_h/2 from a
/// uniform sky, and from the CIE overcast sky
/// E_v = (2 L_z/3)·(π/4 + 2/3) = E_h·(π/6 + 4/9)/(7π/9) = 0.396·E_h
/// (the classical ratio for the overcast sky); its luminance is ρ·E_v/π (within 1.5 %).
#[test]
fn vertical_plane_under_the_sky() {
    let wall = "v 0 -50 -50\nv 0 50 -50\nv 0 50 50\nv 0 -50 50\nf 1 2 3 4\n";
    let camera = "[camera]\nposition = [-10.0, 0.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nvertical_fov_deg = 40.0\nwidth = 12\nheight = 12";
    let overcast = (PI / 6.0 + 4.0 / 9.0) / (7.0 * PI / 9.0);
    for (model, ratio) in [("uniform", 0.5), ("cie-overcast", overcast)] {
        let dir = tempfile::tempdir().unwrap();
        let render = "[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 256\nmax_depth = 1";
        let loaded = scene(dir.path(), wall, camera, &sky(model), render);
        let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
        let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 12, height: 12 }, false);
        let expect = 0.5 * ratio * 10_000.0 / PI;
        let mean = mean_y(&tile);
        assert!((mean / expect - 1.0).abs() < 0.015, "{model}: {mean} vs {expect}");
    }
}

/// Looking up at the zenith through a narrow field, the camera sees the sky's zenith
/// luminance: E_h/π for the uniform sky, 9·E_h/(7π) for the CIE overcast sky (relative error
/// below 1e-4), and every pixel is marked as sky.
#[test]
fn the_camera_sees_the_sky() {
    let camera = "[camera]\nposition = [0.0, 0.0, 1.0]\ntarget = [0.0, 0.0, 2.0]\nup = [0.0, 1.0, 0.0]\nvertical_fov_deg = 0.5\nwidth = 4\nheight = 4";
    for (model, zenith) in
        [("uniform", 10_000.0 / PI), ("cie-overcast", 9.0 * 10_000.0 / (7.0 * PI))]
    {
        let dir = tempfile::tempdir().unwrap();
        let render = "[render]\nintegrator = \"path\"\nsamples_per_pixel = 4\nmax_depth = 3";
        let loaded = scene(dir.path(), PLANE, camera, &sky(model), render);
        let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
        let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 4, height: 4 }, false);
        let mean = mean_y(&tile);
        assert!((mean / zenith - 1.0).abs() < 1e-4, "{model}: {mean} vs {zenith}");
        assert_eq!(tile.sky.as_deref(), Some(&[1.0f32; 16][..]), "{model}");
    }
}

/// A 1 × 1 m area luminaire of L = 1000 cd/m² facing down 2 m above the plane. The camera sees
/// its luminance from below (to 1e-4), and nothing from behind it; the plane below its centre
/// has luminance ρE/π with E = 4 · L · ½ [X/√(1 + X²) atan(Y/√(1 + X²)) + (X ↔ Y)], the
/// illuminance below the corner of each a/2 × a/2 quarter (X = Y = a/2h; the rectangle's
/// configuration factor, Howell's catalogue B-3), to 1 % (4096 samples of the panel).
#[test]
fn an_area_luminaire_is_seen_and_lights_by_its_luminance() {
    let lights = "[[lights]]\nkind = \"area\"\ncorner = [-0.5, -0.5, 2.0]\nu = [1.0, 0.0, 0.0]\n\
                  v = [0.0, 1.0, 0.0]\nnormal = [0.0, 0.0, -1.0]\nluminance_cd_m2 = 1000.0\n\
                  spectrum = \"lamp\"";
    let render = "[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 4096\nmax_depth = 1";
    let below = "[camera]\nposition = [0.1, 0.0, 0.5]\ntarget = [0.0, 0.0, 2.0]\n\
                 vertical_fov_deg = 5.0\nwidth = 3\nheight = 3";
    let dir = tempfile::tempdir().unwrap();
    let loaded = scene(dir.path(), PLANE, below, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
    let seen = luminance(&pixel(&prepared, 1, 1));
    assert!((seen / 1000.0 - 1.0).abs() < 1e-4, "the panel seen from below: {seen} cd/m²");
    let above = "[camera]\nposition = [0.0, 0.0, 10.0]\ntarget = [0.0, 0.0, 0.0]\n\
                 up = [0.0, 1.0, 0.0]\nvertical_fov_deg = 2.0\nwidth = 3\nheight = 3";
    let dir = tempfile::tempdir().unwrap();
    let loaded = scene(dir.path(), PLANE, above, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
    assert_eq!(luminance(&pixel(&prepared, 1, 1)), 0.0, "its back is dark and hides the plane");
    let side = "[camera]\nposition = [3.0, 0.0, 0.5]\ntarget = [0.0, 0.0, 0.0]\n\
                vertical_fov_deg = 0.5\nwidth = 3\nheight = 3";
    let dir = tempfile::tempdir().unwrap();
    let loaded = scene(dir.path(), PLANE, side, lights, render);
    let prepared = PreparedScene::new(&loaded, None, settings(&loaded)).unwrap();
    let x = 0.5f64 / 2.0;
    let quarter = 0.5 * 2.0 * x / (1.0 + x * x).sqrt() * (x / (1.0 + x * x).sqrt()).atan();
    let expect = 0.5 / PI * 4.0 * 1000.0 * quarter;
    let l = luminance(&pixel(&prepared, 1, 1));
    assert!((l / expect - 1.0).abs() < 0.01, "the plane below it: {l} cd/m² against {expect}");
}
