//! A scene in survey coordinates (UTM-like, 5 000 000 m east): with its `origin`, a shadow
//! edge falls where it should to the millimetre. In 32 bits at 5 000 000 m the nearest
//! representable coordinates are 0.5 m apart, so without the recentring the occluder's edge
//! would move by 0.2 m and both sensors below would be in its shadow.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, load_folder};
use restauro_scene::scene_file::Integrator;

const EAST_M: f64 = 5_000_000.3;
const NORTH_M: f64 = 4_000_000.7;

/// A light 1 m above the edge of an opaque sheet at half its height: the sheet's shadow on the
/// ground ends right below the edge. Sensors 1 mm either side of that line.
#[test]
fn a_shadow_edge_in_survey_coordinates_is_placed_to_the_millimetre() {
    let dir = tempfile::tempdir().unwrap();
    // The sheet covers x < EAST_M (and 1 m either side of the northing), at 0.5 m.
    let (e, n) = (EAST_M, NORTH_M);
    let sheet = format!(
        "v {} {} 0.5\nv {e} {} 0.5\nv {e} {} 0.5\nv {} {} 0.5\nf 1 2 3 4\n",
        e - 2.0,
        n - 1.0,
        n - 1.0,
        n + 1.0,
        e - 2.0,
        n + 1.0
    );
    std::fs::write(dir.path().join("sheet.obj"), sheet).unwrap();
    let points: Vec<String> =
        [-0.001, 0.001].iter().map(|dx| format!("[{}, {n}, 0.0]", e + dx)).collect();
    let toml = format!(
        "format = 1\norigin = [5000000.0, 4000000.0, 0.0]\n\
         [camera]\nposition = [{}, {n}, 3.0]\ntarget = [{e}, {n}, 0.0]\nup = [0, 1, 0]\nwidth = 8\nheight = 6\n\
         [spectra]\nlamp = {{ illuminant = \"A\" }}\ngrey = {{ constant = 0.5 }}\n\
         [materials.grey]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
         [[objects]]\nname = \"sheet\"\nmesh = \"sheet.obj\"\nmaterial = \"grey\"\n\
         [[lights]]\nkind = \"point\"\nposition = [{e}, {n}, 1.0]\nintensity_cd = 1000.0\nspectrum = \"lamp\"\n\
         [[grids]]\nname = \"edge\"\npoints = [{}]\nnormal = [0, 0, 1]\n",
        e - 1.0,
        points.join(", ")
    );
    std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
    let scene = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    assert_eq!(scene.origin_m, [5_000_000.0, 4_000_000.0, 0.0]);
    let settings = Settings {
        integrator: Integrator::Path,
        samples_per_pixel: 4,
        max_depth: 0,
        seed: 3,
        grids: true,
        noise_target: 0.0,
    };
    let prepared = PreparedScene::new(&scene, None, settings).unwrap();
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: 2, height: 2 }, false);
    let lux = |k: usize| f64::from(tile.xyz[k][1]);
    // E = I cos θ / d² with d = √(1 + 0.001²): 1000 lx to 1e-6.
    assert_eq!(lux(0), 0.0, "1 mm inside the shadow");
    assert!((lux(1) / 1000.0 - 1.0).abs() < 1e-4, "1 mm outside the shadow: {} lx", lux(1));
}
