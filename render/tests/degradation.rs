//! Degradation maps: a restorer's map with two classes (black crust, biological colonisation)
//! laid over a wall; the state as found shows each class with its spectrum and the stone as
//! found elsewhere, a class's edge mixes the two by area, and a cleaning that lists only the
//! biological class leaves it and shows the clean stone where the crust was.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use std::path::Path;

/// A 4 × 2 map: column 0 black crust (black), column 1 biological (green), the rest white.
fn map_png(path: &Path) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, 4, 2);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut w = encoder.write_header().unwrap();
    let row = [[0u8, 0, 0], [0, 128, 0], [255, 255, 255], [255, 255, 255]].concat();
    w.write_image_data(&[row.clone(), row].concat()).unwrap();
}

fn scene(dir: &Path) -> LoadedScene {
    map_png(&dir.join("survey.png"));
    std::fs::write(dir.join("wall.obj"), "v 0 0 0\nv 4 0 0\nv 4 0 2\nv 0 0 2\nf 1 2 3 4\n")
        .unwrap();
    let toml = r#"format = 1
[camera]
position = [2.0, -6.0, 1.0]
target = [2.0, 0.0, 1.0]
width = 16
height = 8
[spectra]
day = { illuminant = "D65" }
stone = "travertine_tufa_solid__eco_ward73"
soot = "carbon_black_soot_proxy__usgs_GDS68"
stone_soiled = { mix = [{ spectrum = "stone", weight = 0.7 }, { spectrum = "soot", weight = 0.3 }] }
crust = { constant = 0.05 }
lichen = { constant = 0.25 }
[materials.stone]
model = "lambert"
reflectance = "stone"
degraded = { reflectance = "stone_soiled", map = "survey" }
cleaned = { map = "survey", classes = ["biological"] }
[[maps]]
name = "survey"
image = "survey.png"
corner = [0.0, 0.0, 0.0]
u = [4.0, 0.0, 0.0]
v = [0.0, 0.0, 2.0]
classes = [
  { name = "black-crust", colour = [0, 0, 0], spectrum = "crust" },
  { name = "biological", colour = [0, 128, 0], spectrum = "lichen" },
]
[[objects]]
name = "wall"
mesh = "wall.obj"
material = "stone"
[[lights]]
kind = "sun"
illuminance_lux = 10000.0
azimuth_deg = 180.0
elevation_deg = 45.0
spectrum = "day"
[variants.as-found]
state = "degraded"
[variants.cleaned]
state = "cleaned"
"#;
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

/// The reflectance the tracer uses at x along the wall, half-way up, under `variant`.
fn at(scene: &LoadedScene, variant: &str, x: f32) -> Spectrum {
    let settings = Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: 1,
        max_depth: 1,
        seed: 1,
        grids: false,
        noise_target: 0.0,
    };
    let prepared = PreparedScene::new(scene, Some(variant), settings).unwrap();
    let hit = prepared.intersect(Vec3A::new(x, -5.0, 1.0), Vec3A::Y, f32::INFINITY).unwrap();
    let mut buffer = Spectrum::ZERO;
    *prepared.reflectance(&hit, 0.0, &mut buffer)
}

fn assert_close(got: &Spectrum, want: &Spectrum, what: &str) {
    for (band, (g, w)) in got.0.iter().zip(&want.0).enumerate() {
        assert!((g - w).abs() < 1e-6, "{what}, band {band}: {g} against {w}");
    }
}

#[test]
fn each_class_shows_its_spectrum_and_a_cleaning_removes_the_classes_it_leaves_out() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path());
    let spectrum = |name: &str| s.spectra[name];
    // As found: crust, lichen, and the soiled stone where the map has no class.
    assert_close(&at(&s, "as-found", 0.5), &spectrum("crust"), "as found, the crust");
    assert_close(&at(&s, "as-found", 1.5), &spectrum("lichen"), "as found, the lichen");
    assert_close(&at(&s, "as-found", 3.5), &spectrum("stone_soiled"), "as found, no class");
    // The map ends at the wall's edge: its last column does not blend with its first.
    assert_close(&at(&s, "as-found", 3.96), &spectrum("stone_soiled"), "as found, the east edge");
    // On the edge between crust and lichen, half of each.
    let edge = Spectrum([0.5 * (0.05 + 0.25); 81]);
    assert_close(&at(&s, "as-found", 1.0), &edge, "as found, the classes' edge");
    // Cleaned of the crust only: the stone where it was, the lichen left.
    assert_close(&at(&s, "cleaned", 0.5), &spectrum("stone"), "cleaned, where the crust was");
    assert_close(&at(&s, "cleaned", 1.5), &spectrum("lichen"), "cleaned, the lichen left");
}

#[test]
fn a_map_naming_an_unknown_class_or_a_jpeg_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    scene(dir.path());
    let text = std::fs::read_to_string(dir.path().join("scene.toml")).unwrap();
    let bad = text.replace("classes = [\"biological\"]", "classes = [\"biologic\"]");
    std::fs::write(dir.path().join("scene.toml"), bad).unwrap();
    let e =
        load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("materials.stone.cleaned.classes") && e.contains("biological"), "{e}");
    let jpeg = text.replace("image = \"survey.png\"", "image = \"survey.jpg\"");
    std::fs::write(dir.path().join("survey.jpg"), b"\xff\xd8\xff").unwrap();
    std::fs::write(dir.path().join("scene.toml"), jpeg).unwrap();
    let e =
        load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("maps[0] (survey).image") && e.contains("PNG"), "{e}");
}
