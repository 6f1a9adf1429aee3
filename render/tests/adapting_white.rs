//! The adapting white each pixel carries: what a perfect white diffuser at the camera ray's
//! first surface would send back, E(λ)/π, under every light and (with `path`) the light
//! between surfaces.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, TileResult, render_tile};
use restauro_scene::load::{Limits, load_folder};
use restauro_spectral::colorimetry::{Observer, white_point};
use std::path::Path;

/// Renders the scene `toml` (written into `dir` beside a 100 m ground plane `ground.obj` and
/// a wall `wall.obj`) in one tile of `w` × `h`.
fn render(dir: &Path, toml: &str, (w, h): (u32, u32)) -> TileResult {
    std::fs::write(
        dir.join("ground.obj"),
        "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(dir.join("wall.obj"), "v -6 4 0\nv 6 4 0\nv 6 4 5\nv -6 4 5\nf 1 2 3 4\n")
        .unwrap();
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    let loaded = load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap();
    let prepared = PreparedScene::new(&loaded, None, Settings::from(&loaded.file.render)).unwrap();
    render_tile(&prepared, Rect { x: 0, y: 0, width: w, height: h }, false)
}

fn scene(integrator: &str, material: &str, lights: &str) -> String {
    format!(
        r#"format = 1
[camera]
position = [0.0, -10.0, 2.0]
target = [0.0, 4.0, 1.5]
vertical_fov_deg = 60.0
width = 24
height = 16
[render]
integrator = "{integrator}"
samples_per_pixel = 16
max_depth = 4
seed = 9
[spectra]
white = {{ constant = 1.0 }}
tinted = {{ constant = 0.3 }}
daylight = {{ illuminant = "D65" }}
sky = {{ illuminant = "daylight:12000" }}
lamp = {{ illuminant = "A" }}
[materials.white]
model = "lambert"
reflectance = "white"
[materials.tinted]
model = "lambert"
reflectance = "tinted"
[[objects]]
name = "ground"
mesh = "ground.obj"
material = "{material}"
[[objects]]
name = "wall"
mesh = "wall.obj"
material = "{material}"
{lights}"#
    )
}

const LIGHTS: &str = r#"[[lights]]
kind = "sun"
illuminance_lux = 60000.0
azimuth_deg = 200.0
elevation_deg = 35.0
spectrum = "daylight"
[[lights]]
kind = "sky"
illuminance_lux = 12000.0
model = "uniform"
spectrum = "sky"
[[lights]]
kind = "point"
position = [2.0, 0.0, 3.0]
intensity_cd = 40000.0
spectrum = "lamp"
"#;

/// A perfect white diffuser sends back exactly its white: wherever the surfaces are white
/// Lambertian (ρ = 1), each pixel's XYZ is its white's, under the sun, a sky and a lamp, direct
/// (Whitted) and with the light between surfaces (path), to float rounding.
#[test]
fn a_white_diffuser_is_its_own_white() {
    for integrator in ["whitted", "path"] {
        let dir = tempfile::tempdir().unwrap();
        let tile = render(dir.path(), &scene(integrator, "white", LIGHTS), (24, 16));
        let white = tile.white.as_ref().expect("an image carries its white");
        let sky = tile.sky.as_ref().unwrap();
        let mut checked = 0;
        for (p, (xyz, w)) in tile.xyz.iter().zip(white).enumerate() {
            if sky[p] > 0.0 {
                continue;
            }
            for c in 0..3 {
                let rel = (xyz[c] / w[c] - 1.0).abs();
                assert!(rel < 1e-4, "{integrator}, pixel {p}: {xyz:?} against {w:?}");
            }
            // The scotopic luminance of lights from 2856 to 12 000 K: between 1.3 and 3 times
            // the photopic.
            assert!((1.3..3.0).contains(&(w[3] / w[1])), "{integrator}, pixel {p}: {w:?}");
            checked += 1;
        }
        assert!(checked > 200, "{checked}");
    }
}

/// The white does not depend on the surface it is measured at: the same scene with surfaces of
/// reflectance 0.3 has, under Whitted (direct light only, the same shadow rays), the same white
/// at every pixel, and pixels 0.3 times it.
#[test]
fn the_white_is_the_lights_not_the_surfaces() {
    let dir = tempfile::tempdir().unwrap();
    let white = render(dir.path(), &scene("whitted", "white", LIGHTS), (24, 16));
    let tinted = render(dir.path(), &scene("whitted", "tinted", LIGHTS), (24, 16));
    assert_eq!(white.white, tinted.white);
    let sky = white.sky.as_ref().unwrap();
    for (p, (a, b)) in white.xyz.iter().zip(&tinted.xyz).enumerate().filter(|(p, _)| sky[*p] == 0.0)
    {
        for c in 0..3 {
            assert!((b[c] / a[c] - 0.3).abs() < 1e-4, "pixel {p}: {a:?} {b:?}");
        }
    }
}

/// Against the closed form: under a sun of E lux at normal incidence (the camera looking down
/// on a plane, the sun at the zenith), the white is E/π cd/m² with the sun's chromaticity, at
/// every pixel; with the path tracer, nothing else lights the plane.
#[test]
fn under_a_sun_the_white_is_its_illuminance_over_pi() {
    let toml = r#"format = 1
[camera]
position = [0.0, 0.0, 10.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vertical_fov_deg = 50.0
width = 8
height = 8
[render]
integrator = "path"
samples_per_pixel = 4
seed = 2
[spectra]
grey = { constant = 0.4 }
lamp = { illuminant = "A" }
[materials.grey]
model = "lambert"
reflectance = "grey"
[[objects]]
name = "ground"
mesh = "ground.obj"
material = "grey"
[[lights]]
kind = "sun"
illuminance_lux = 50000.0
elevation_deg = 90.0
spectrum = "lamp"
"#;
    let dir = tempfile::tempdir().unwrap();
    let tile = render(dir.path(), toml, (8, 8));
    let a = "A".parse::<restauro_spectral::Illuminant>().unwrap().spd().unwrap();
    let wp = white_point(&a, Observer::Cie1931TwoDegree);
    for w in tile.white.unwrap() {
        let y = 50_000.0 / std::f64::consts::PI;
        assert!((f64::from(w[1]) / y - 1.0).abs() < 1e-5, "{w:?}");
        assert!((f64::from(w[0]) / f64::from(w[1]) - wp.x / wp.y).abs() < 1e-5, "{w:?}");
        assert!((f64::from(w[2]) / f64::from(w[1]) - wp.z / wp.y).abs() < 1e-5, "{w:?}");
    }
}
