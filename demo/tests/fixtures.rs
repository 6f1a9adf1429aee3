//! Scenes of the demo that other crates' tests read as fixtures are what the generators write:
//! the scene model's tests of the studio's edits read the Aosta facade's scene file without
//! depending on this crate (which depends on the scene model).

use restauro_demo::scenes::aosta;

/// `scene/tests/data/edit/aosta.toml` is the facade's scene file at 64 × 32 pixels, 1 sample per
/// pixel. When the generator changes, write the file again:
/// `RESTAURO_WRITE_FIXTURES=1 cargo test -p restauro-demo --test fixtures`.
#[test]
fn the_edit_tests_read_the_facade_as_generated() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scene/tests/data/edit/aosta.toml");
    let generated = aosta::generate(64, 32, 1).scene_toml;
    if std::env::var_os("RESTAURO_WRITE_FIXTURES").is_some() {
        std::fs::write(path, &generated).unwrap();
    }
    let fixture = std::fs::read_to_string(path).unwrap();
    assert!(
        fixture == generated,
        "{path} is not the facade's scene as generated; write it again with \
         RESTAURO_WRITE_FIXTURES=1 cargo test -p restauro-demo --test fixtures"
    );
}
