//! The demo's scenes load as the scene model checks any scene a restorer writes.

use restauro_demo::scenes::aosta;
use restauro_scene::load::{Limits, ResolvedLight, load_folder};

#[test]
fn the_aosta_scene_validates() {
    let dir = tempfile::tempdir().unwrap();
    let generated = aosta::generate(320, 180, 1);
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::write(dir.path().join("meshes/facade.obj"), &generated.facade_obj).unwrap();
    let path = dir.path().join("aosta.toml");
    std::fs::write(&path, &generated.scene_toml).unwrap();
    let scene = load_folder(&path, &Limits::default()).unwrap();
    assert_eq!(scene.triangle_count(), generated.triangles);
    // The summer-afternoon sun over the theatre is up and in the south-west.
    match &scene.lights[0] {
        ResolvedLight::Sun { azimuth_deg, elevation_deg, .. } => {
            assert!(
                (180.0..270.0).contains(azimuth_deg) && *elevation_deg > 30.0,
                "{azimuth_deg} {elevation_deg}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(scene.state_of("as-found", "facade", "travertine"), Some("degraded"));
    assert_eq!(scene.state_of("cleaned", "facade", "puddinga"), Some("cleaned"));
}
