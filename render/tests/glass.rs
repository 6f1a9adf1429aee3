//! Glazing against hand-computed Fresnel values. A clear pane (no absorption) of n = 1.52 at
//! 60° incidence: sin θt = sin 60°/1.52 = 0.56975, cos θt = 0.82181; per face
//! r_s = ((cos θi − n cos θt)/(cos θi + n cos θt))² = 0.18341 and
//! r_p = ((n cos θi − cos θt)/(n cos θi + cos θt))² = 0.0015266; through both faces and their
//! inter-reflections, T = ½ Σ (1 − r)/(1 + r) = 0.84349 and R = 1 − T. At normal incidence
//! the default pane (6 mm clear float) transmits 0.88.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, film_xyz, pixel, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_scene};
use restauro_scene::scene_file::Integrator;

const T_60: f64 = 0.84349;

/// A black floor at z = 0 and a 10 × 10 m pane at z = 1 over it, of `glass` keys.
fn load(dir: &std::path::Path, glass: &str, camera: &str, lights: &str) -> LoadedScene {
    let obj = "o floor\nv -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nusemtl floor\nf 1 2 3 4\n\
               o pane\nv -5 -5 1\nv 5 -5 1\nv 5 5 1\nv -5 5 1\nusemtl pane\nf 5 6 7 8\n";
    std::fs::write(dir.join("mesh.obj"), obj).unwrap();
    let toml = format!(
        "format = 1\n{camera}\n[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 16384\n\
         max_depth = 4\n[spectra]\nday = {{ illuminant = \"D65\" }}\nblack = {{ constant = 0.0 }}\n\
         [materials.black]\nmodel = \"lambert\"\nreflectance = \"black\"\n\
         [materials.pane]\nmodel = \"glass\"\n{glass}\n\
         [[objects]]\nname = \"box\"\nmesh = \"mesh.obj\"\n\
         materials = {{ floor = \"black\", pane = \"pane\" }}\n{lights}\n\
         [[grids]]\nname = \"under\"\npoints = [[0.3, 0.1, 0.5]]\nnormal = [0.0, 0.0, 1.0]\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_scene(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

fn settings(scene: &LoadedScene, grids: bool) -> Settings {
    let r = &scene.file.render;
    Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: if grids { 1 } else { r.samples_per_pixel },
        max_depth: r.max_depth,
        seed: 2,
        grids,
    }
}

/// The direct illuminance at the grid point under the pane.
fn under(scene: &LoadedScene) -> f64 {
    let prepared = PreparedScene::new(scene, None, settings(scene, true)).unwrap();
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 1, height: 2 }, false);
    f64::from(tile.xyz[0][1])
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

/// Glass keys are checked: a reflectance on glass, glazing keys on stone, a transmittance more
/// than the faces let through.
#[test]
fn glass_keys_are_refused_where_they_do_not_belong() {
    let dir = tempfile::tempdir().unwrap();
    let sun = "[[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nelevation_deg = 50.0\nspectrum = \"day\"";
    for (glass, expected) in [
        ("reflectance = \"black\"", "glass has no reflectance"),
        ("transmittance = 0.95", "transmits 0 to 0.918"),
        ("thickness_mm = 0.0", "thickness_mm"),
        ("ior = 0.9", "index of refraction above 1"),
    ] {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        std::fs::write(dir.path().join("mesh.obj"), obj).unwrap();
        let toml = format!(
            "format = 1\n{CAMERA}\n[spectra]\nday = {{ illuminant = \"D65\" }}\n\
             black = {{ constant = 0.0 }}\n[materials.pane]\nmodel = \"glass\"\n{glass}\n\
             [[objects]]\nname = \"p\"\nmesh = \"mesh.obj\"\nmaterial = \"pane\"\n{sun}\n"
        );
        std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
        let e = load_scene(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err();
        assert!(e.to_string().contains(expected), "{glass}: {e}");
    }
}
