//! Glazing against hand-computed Fresnel values. A clear pane (no absorption) of n = 1.52 at
//! 60° incidence: sin θt = sin 60°/1.52 = 0.56975, cos θt = 0.82181; per face
//! r_s = ((cos θi − n cos θt)/(cos θi + n cos θt))² = 0.18341 and
//! r_p = ((n cos θi − cos θt)/(n cos θi + cos θt))² = 0.0015266; through both faces and their
//! inter-reflections, T = ½ Σ (1 − r)/(1 + r) = 0.84349 and R = 1 − T. At normal incidence
//! the default pane (6 mm clear float) transmits 0.88.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, film_xyz, pixel, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;

const T_60: f64 = 0.84349;

/// A black floor at z = 0 and a 10 × 10 m pane at z = 1 over it.
const MESH: &str = "o floor\nv -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nusemtl floor\nf 1 2 3 4\n\
                    o pane\nv -5 -5 1\nv 5 -5 1\nv 5 5 1\nv -5 5 1\nusemtl pane\nf 5 6 7 8\n";

/// [`MESH`], its pane of `glass` keys.
fn load(dir: &std::path::Path, glass: &str, camera: &str, lights: &str) -> LoadedScene {
    load_mesh(dir, MESH, glass, camera, lights)
}

/// `obj` (with a floor and a pane part), the pane of `glass` keys.
fn load_mesh(
    dir: &std::path::Path,
    obj: &str,
    glass: &str,
    camera: &str,
    lights: &str,
) -> LoadedScene {
    std::fs::write(dir.join("mesh.obj"), obj).unwrap();
    let toml = format!(
        "format = 1\n{camera}\n[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 16384\n\
         max_depth = 4\n[spectra]\nday = {{ illuminant = \"D65\" }}\nblack = {{ constant = 0.0 }}\n\
         [materials.black]\nmodel = \"lambert\"\nreflectance = \"black\"\n\
         [materials.pane]\nmodel = \"glass\"\n{glass}\n\
         [[objects]]\nname = \"box\"\nmesh = \"mesh.obj\"\n\
         materials = {{ floor = \"black\", pane = \"pane\" }}\n{lights}\n\
         [[grids]]\nname = \"under\"\npoints = [[0.3, 0.1, 0.5]]\nnormal = [0.0, 0.0, 1.0]\n\
         [spectra.green]\nfile = \"green.csv\"\n"
    );
    std::fs::write(dir.join("green.csv"), green_csv()).unwrap();
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

fn settings(scene: &LoadedScene, grids: bool) -> Settings {
    let r = &scene.file.render;
    Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: if grids { 1 } else { r.samples_per_pixel },
        max_depth: r.max_depth,
        seed: 2,
        grids,
        noise_target: 0.0,
    }
}

/// The direct illuminance at the grid point under the pane.
fn under(scene: &LoadedScene) -> f64 {
    let prepared = PreparedScene::new(scene, None, settings(scene, true)).unwrap();
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 1, height: 2 }, false);
    f64::from(tile.xyz[0][1])
}

/// The direct spectral irradiance at the grid point under the pane.
fn under_spectrum(scene: &LoadedScene) -> Spectrum {
    let prepared = PreparedScene::new(scene, None, settings(scene, true)).unwrap();
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 1, height: 2 }, true);
    tile.spectral.unwrap()[0]
}

const CAMERA: &str =
    "[camera]\nposition = [0.0, -3.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 4\nheight = 4";

/// The sun through the pane: 0.88 of it at normal incidence through the default pane; through a
/// clear pane with the sun 30° high (60° incidence), T(60°) of its horizontal illuminance.
#[test]
fn the_sun_passes_through_a_pane_by_its_transmittance() {
    let dir = tempfile::tempdir().unwrap();
    let sun = |el: f64| {
        format!(
            "[[lights]]\nkind = \"sun\"\nilluminance_lux = 100000.0\nazimuth_deg = 180.0\nelevation_deg = {el}\nspectrum = \"day\""
        )
    };
    let scene = load(dir.path(), "", CAMERA, &sun(90.0));
    let e = under(&scene);
    assert!(
        (e / 88_000.0 - 1.0).abs() < 1e-4,
        "{e} lx through the default pane at normal incidence"
    );
    let clear = format!("transmittance = {}", restauro_render::glass::max_transmittance(1.52));
    let scene = load(dir.path(), &clear, CAMERA, &sun(30.0));
    let e = under(&scene);
    let expected = 100_000.0 * 0.5 * T_60;
    assert!((e / expected - 1.0).abs() < 1e-4, "{e} lx against {expected}");
}

/// A pane whose file gives it bent vertex normals (as a curved glazing's would) is traced
/// flat: the sun through it is the flat pane's, to the bit.
#[test]
fn a_pane_with_vertex_normals_is_traced_flat() {
    let dir = tempfile::tempdir().unwrap();
    let sun = "[[lights]]\nkind = \"sun\"\nilluminance_lux = 100000.0\nazimuth_deg = 180.0\n\
               elevation_deg = 60.0\nspectrum = \"day\"";
    let flat = under(&load(dir.path(), "", CAMERA, sun));
    let bent = MESH.replace(
        "usemtl pane\nf 5 6 7 8\n",
        "vn 0.3 0 1\nvn 0 0.3 1\nvn -0.3 0 1\nvn 0 -0.3 1\nusemtl pane\nf 5//1 6//2 7//3 8//4\n",
    );
    let curved = under(&load_mesh(dir.path(), &bent, "", CAMERA, sun));
    assert_eq!(flat, curved);
}

/// A uniform sky seen through a clear pane from below at 60° from the zenith: L · T(60°); and
/// seen in it from above (over a black floor): L · R(60°). Monte Carlo choice between the two:
/// 16 384 samples, tolerances 1 % and 4 %.
#[test]
fn the_camera_sees_the_sky_through_and_in_a_pane() {
    let dir = tempfile::tempdir().unwrap();
    let sky = "[[lights]]\nkind = \"sky\"\nilluminance_lux = 10000.0\nmodel = \"uniform\"\nspectrum = \"day\"";
    let clear = format!("transmittance = {}", restauro_render::glass::max_transmittance(1.52));
    let l = 10_000.0 / std::f64::consts::PI;
    let below = "[camera]\nposition = [0.0, 0.0, 0.5]\ntarget = [0.0, 0.866, 1.0]\n\
                 vertical_fov_deg = 0.5\nwidth = 1\nheight = 1";
    let scene = load(dir.path(), &clear, below, sky);
    let prepared = PreparedScene::new(&scene, None, settings(&scene, false)).unwrap();
    let y = f64::from(film_xyz(&pixel(&prepared, 0, 0))[1]);
    assert!((y / (l * T_60) - 1.0).abs() < 0.01, "through: {y} against {}", l * T_60);
    let above = "[camera]\nposition = [0.0, 0.0, 2.0]\ntarget = [0.0, 1.732, 1.0]\n\
                 vertical_fov_deg = 0.5\nwidth = 1\nheight = 1";
    let scene = load(dir.path(), &clear, above, sky);
    let prepared = PreparedScene::new(&scene, None, settings(&scene, false)).unwrap();
    let y = f64::from(film_xyz(&pixel(&prepared, 0, 0))[1]);
    let expected = l * (1.0 - T_60);
    assert!((y / expected - 1.0).abs() < 0.04, "reflected: {y} against {expected}");
}

/// A green tint, 0.2 in the blue and red rising to the clearest a pane of n = 1.52 can be at
/// 530 nm (band 30), as a spectrum file.
fn green(nm: f64) -> f64 {
    let most = restauro_render::glass::max_transmittance(1.52) - 1e-6;
    0.2 + (most - 0.2) * (-((nm - 530.0) / 50.0).powi(2)).exp()
}

fn green_csv() -> String {
    (0..81).map(|i| 380.0 + 5.0 * f64::from(i)).map(|nm| format!("{nm},{}\n", green(nm))).collect()
}

/// The transmittance at 60° incidence of a pane of n = 1.52 whose normal transmittance is
/// `t0`, from the hand-computed face reflectances in the header: τ₀ from the slab formula at
/// normal incidence (r = 0.0426), the path 1/cos θt longer at 60°.
fn t_60(t0: f64) -> f64 {
    let (rs, rp, cos_t): (f64, f64, f64) = (0.18341, 0.0015266, 0.82181);
    let r: f64 = (0.52f64 / 2.52).powi(2);
    let (a, b) = (r * r * t0, (1.0 - r).powi(2));
    let tau0 = ((b * b + 4.0 * a * t0).sqrt() - b) / (2.0 * a);
    let tau = tau0.powf(1.0 / cos_t);
    [rs, rp].iter().map(|f| 0.5 * (1.0 - f).powi(2) * tau / (1.0 - f * f * tau * tau)).sum()
}

/// A tinted pane passes the sun band by band: at normal incidence each band's irradiance is
/// the tint's transmittance over a clear pane's, and at 60° each band follows the slab formula
/// for its own absorption; the band where the tint is clear matches the clear pane.
#[test]
fn a_tinted_pane_passes_the_sun_band_by_band() {
    let dir = tempfile::tempdir().unwrap();
    let sun = |el: f64| {
        format!(
            "[[lights]]\nkind = \"sun\"\nilluminance_lux = 100000.0\nazimuth_deg = 180.0\nelevation_deg = {el}\nspectrum = \"day\""
        )
    };
    let most = restauro_render::glass::max_transmittance(1.52);
    let clear = format!("transmittance = {most}");
    for el in [90.0, 30.0] {
        let tinted =
            under_spectrum(&load(dir.path(), "transmittance = \"green\"", CAMERA, &sun(el)));
        let open = under_spectrum(&load(dir.path(), &clear, CAMERA, &sun(el)));
        for i in 0..81 {
            let t0 = green(380.0 + 5.0 * i as f64);
            let expected = if el == 90.0 { t0 / most } else { t_60(t0) / T_60 };
            let ratio = f64::from(tinted[i] / open[i]);
            assert!(
                (ratio / expected - 1.0).abs() < 2e-4,
                "{el}°, band {i}: {ratio} against {expected}"
            );
        }
        assert!((f64::from(tinted[30] / open[30]) - 1.0).abs() < 1e-4);
    }
}

/// The sky seen through a tinted pane, as in the test above it: band by band, the tint's
/// transmittance at 60° over the clear pane's. Monte Carlo choice between reflection and
/// transmission: 16 384 samples, tolerance 2 %.
#[test]
fn the_camera_sees_the_sky_through_a_tinted_pane_in_its_colour() {
    let dir = tempfile::tempdir().unwrap();
    let sky = "[[lights]]\nkind = \"sky\"\nilluminance_lux = 10000.0\nmodel = \"uniform\"\nspectrum = \"day\"";
    let below = "[camera]\nposition = [0.0, 0.0, 0.5]\ntarget = [0.0, 0.866, 1.0]\n\
                 vertical_fov_deg = 0.5\nwidth = 1\nheight = 1";
    let seen = |glass: &str| {
        let scene = load(dir.path(), glass, below, sky);
        let prepared = PreparedScene::new(&scene, None, settings(&scene, false)).unwrap();
        pixel(&prepared, 0, 0)
    };
    let clear =
        seen(&format!("transmittance = {}", restauro_render::glass::max_transmittance(1.52)));
    let tinted = seen("transmittance = \"green\"");
    for i in 0..81 {
        let expected = t_60(green(380.0 + 5.0 * i as f64)) / T_60;
        let ratio = f64::from(tinted[i] / clear[i]);
        assert!((ratio / expected - 1.0).abs() < 0.02, "band {i}: {ratio} against {expected}");
    }
}

/// Glass keys are checked: a reflectance on glass, glazing keys on stone, a transmittance more
/// than the faces let through.
#[test]
fn glass_keys_are_refused_where_they_do_not_belong() {
    let dir = tempfile::tempdir().unwrap();
    let sun = "[[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nelevation_deg = 50.0\nspectrum = \"day\"";
    for (glass, expected) in [
        ("reflectance = \"black\"", "glass has no reflectance"),
        ("transmittance = 0.95", "transmits 0 to 0.918"),
        ("transmittance = \"bright\"", "spectrum `bright` at 380 nm: 0.95 is out of range"),
        ("transmittance = \"nowhere\"", "nowhere"),
        ("transmittance = true", "a number 0–1 (clear glass) or the name of a spectrum"),
        ("thickness_mm = 0.0", "thickness_mm"),
        ("ior = 0.9", "index of refraction above 1"),
    ] {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        std::fs::write(dir.path().join("mesh.obj"), obj).unwrap();
        let toml = format!(
            "format = 1\n{CAMERA}\n[spectra]\nday = {{ illuminant = \"D65\" }}\n\
             black = {{ constant = 0.0 }}\nbright = {{ constant = 0.95 }}\n[materials.pane]\nmodel = \"glass\"\n{glass}\n\
             [[objects]]\nname = \"p\"\nmesh = \"mesh.obj\"\nmaterial = \"pane\"\n{sun}\n"
        );
        std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
        let e = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err();
        assert!(e.to_string().contains(expected), "{glass}: {e}");
    }
}
