//! Levels of detail: a VRML97 `LOD` keeps every level, and each render shows the level its
//! camera calls for by the object's projected size (`restauro_scene::lod`): the VRML ranges
//! hold for a 480-pixel-high view at 45°, and a render with four times the pixels shows, at the
//! same distance, the level of a quarter of it.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_scene::load::{Limits, load_folder};
use restauro_scene::scene_file::Integrator;

/// The LOD (scaled by 2 by its Transform, so its ranges are in half-metres) holds a light box
/// near the camera and a dark one farther off.
const WORLD: &str = "#VRML V2.0 utf8\n\
    Transform { scale 2 2 2 children [\n\
      LOD { center 0 0 0 range [ 10 ] level [\n\
        DEF near Shape { geometry Box { size 1 1 1 } }\n\
        DEF far Shape { geometry Box { size 1 1 1 } }\n\
      ] }\n\
    ] }\n";

/// The reflectance the camera sees at the middle of the image, at `distance_m` with an image
/// `height_px` high (45° field of view).
fn seen(distance_m: f64, height_px: u32) -> f32 {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("box.wrl"), WORLD).unwrap();
    let toml = format!(
        "format = 1\n[camera]\nposition = [0.0, -{distance_m}, 0.0]\ntarget = [0.0, 0.0, 0.0]\n\
         vertical_fov_deg = 45.0\nwidth = {height_px}\nheight = {height_px}\n\
         [spectra]\nday = {{ illuminant = \"D65\" }}\nlight = {{ constant = 0.8 }}\ndark = {{ constant = 0.1 }}\n\
         [materials.light]\nmodel = \"lambert\"\nreflectance = \"light\"\n\
         [materials.dark]\nmodel = \"lambert\"\nreflectance = \"dark\"\n\
         [[objects]]\nname = \"box\"\nmesh = \"box.wrl\"\nmaterials = {{ near = \"light\", far = \"dark\" }}\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 0.0\nelevation_deg = 45.0\nspectrum = \"day\"\n"
    );
    std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
    let scene = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    assert_eq!(scene.objects[0].mesh.triangles.len(), 24, "both levels are kept");
    let settings = Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: 1,
        max_depth: 1,
        seed: 1,
        grids: false,
        noise_target: 0.0,
    };
    let prepared = PreparedScene::new(&scene, None, settings).unwrap();
    assert_eq!(prepared.triangle_count(), 12, "one level is traced");
    let origin = Vec3A::new(0.0, -distance_m as f32, 0.0);
    let hit = prepared.intersect(origin, Vec3A::Y, f32::INFINITY).expect("the box");
    prepared.materials[hit.material as usize].rho().0[40]
}

#[test]
fn the_level_follows_the_distance_and_the_pixels() {
    // The LOD's units are half-metres (scale 2): its range of 10 is 20 m.
    assert_eq!(seen(15.0, 480), 0.8, "15 m: the near level");
    assert_eq!(seen(30.0, 480), 0.1, "30 m: the far level");
    // Four times the pixels: at 30 m it looks as large as at 7.5 m in 480 pixels.
    assert_eq!(seen(30.0, 1920), 0.8, "30 m in 1920 pixels: the near level");
}
