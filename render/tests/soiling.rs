//! Exposure-driven soiling on the Aosta facade as found: the band of wall sheltered by the
//! cornice from the sky and the south-westerly rain keeps its deposit, the buttresses' open
//! fronts, which the rain reaches, are washed nearly clean.

use glam::Vec3A;
use restauro_render::integrator::lift;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::sampler::PixelSampler;
use restauro_scene::load::{Limits, load_folder};
use restauro_scene::scene_file::Integrator;

/// The deposit's mean share where a ray from `origin` along +Y meets the facade, over `n`
/// estimates.
fn mean_share(prepared: &PreparedScene, origin: Vec3A, n: u32) -> f32 {
    let hit = prepared.intersect(origin, Vec3A::Y, f32::INFINITY).expect("the facade");
    let soiling = prepared.soiling(hit.material).expect("a soiled stone");
    let mut rays = 0;
    let total: f32 = (0..n)
        .map(|s| {
            let mut sampler = PixelSampler::new(7, 0, 0, s);
            let occluded = |from, towards| prepared.occluded(from, towards, f32::INFINITY);
            soiling.share(occluded, lift(&hit), hit.shading, &mut sampler, &mut rays)
        })
        .sum();
    total / n as f32
}

#[test]
fn the_band_under_the_cornice_is_darker_than_the_rain_washed_buttresses() {
    let dir = tempfile::tempdir().unwrap();
    let generated = restauro_demo::scenes::aosta::generate(64, 36, 3);
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::write(dir.path().join("meshes/facade.obj"), &generated.facade_obj).unwrap();
    std::fs::write(dir.path().join("aosta.toml"), &generated.scene_toml).unwrap();
    let loaded = load_folder(&dir.path().join("aosta.toml"), &Limits::default()).unwrap();
    let settings = Settings {
        integrator: Integrator::Path,
        samples_per_pixel: 1,
        max_depth: 2,
        seed: 1,
        grids: false,
        noise_target: 0.0,
    };
    let prepared = PreparedScene::new(&loaded, Some("as-found"), settings).unwrap();
    // The wall 30 cm under the cornice (at 21.2 m), mid-bay; the front of the buttress at
    // x = 0 half-way up.
    let sheltered = mean_share(&prepared, Vec3A::new(3.5, -0.5, 20.9), 4000);
    let washed = mean_share(&prepared, Vec3A::new(0.0, -3.0, 10.0), 4000);
    assert!(sheltered > 0.4, "under the cornice the deposit covers {sheltered}");
    assert!(washed < 0.2, "the buttress's front keeps {washed}");
    assert!(sheltered > 3.0 * washed, "{sheltered} against {washed}");
    // The cleaned facade has no deposit at all.
    let cleaned = PreparedScene::new(&loaded, Some("cleaned"), settings).unwrap();
    let hit = cleaned.intersect(Vec3A::new(3.5, -0.5, 20.9), Vec3A::Y, f32::INFINITY).unwrap();
    assert!(cleaned.soiling(hit.material).is_none());
}
