//! VRML97 `Inline` (ISO/IEC 14772-1 §6.25) through a scene: the inlined world is drawn in
//! place under the transforms around it, with DEF names of its own, its urls tried in order and
//! relative to the file that holds it; a file that inlines itself is refused; and a bundle
//! carries the inlined files by hash, so that it loads alone and its identity does not depend
//! on what the files were called.

use restauro_scene::bundle::bundle_folder;
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use std::path::Path;

/// A box 2 m on a side (§6.7: 12 triangles) at the origin of the file, DEF'd `PART` as the
/// world that inlines it also DEFs a node.
const COLUMN: &str = "#VRML V2.0 utf8\nDEF PART Transform { translation 0 1 0 children [\n\
  Shape { geometry Box { size 2 2 2 } }\n\
  Inline { url \"capital.wrl\" }\n] }\n";
/// A box 1 m on a side, 3 m up: relative to `parts/column.wrl`, it is `parts/capital.wrl`.
const CAPITAL: &str = "#VRML V2.0 utf8\nTransform { translation 0 3 0 children Shape { geometry Box { size 1 1 1 } } }\n";

fn write(dir: &Path, files: &[(&str, &str)]) {
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    let toml = "format = 1\n[camera]\nposition = [0.0, -20.0, 2.0]\ntarget = [0.0, 0.0, 2.0]\nwidth = 8\nheight = 8\n\
         [spectra]\nday = { illuminant = \"D65\" }\ngrey = { constant = 0.5 }\n\
         [materials.stone]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
         [[objects]]\nname = \"world\"\nmesh = \"world.wrl\"\nmaterial = \"stone\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 0.0\nelevation_deg = 60.0\nspectrum = \"day\"\n";
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
}

fn load(dir: &Path) -> restauro_scene::Result<LoadedScene> {
    load_folder(&dir.join("scene.toml"), &Limits::default())
}

/// The world's own box, and the column inlined twice (by DEF/USE) at x = ±10.
fn world(url: &str) -> String {
    format!(
        "#VRML V2.0 utf8\nDEF PART Shape {{ geometry Box {{ size 4 4 4 }} }}\n\
         Transform {{ translation 10 0 0 children DEF COLUMN Inline {{ url [{url}] }} }}\n\
         Transform {{ translation -10 0 0 children USE COLUMN }}\n"
    )
}

/// The extent of the triangles' vertices along the file's x (the scene turns Y-up to Z-up,
/// which leaves x alone) and the count of triangles.
fn summary(scene: &LoadedScene) -> (usize, f32, f32) {
    let mesh = &scene.objects[0].mesh;
    let xs = mesh.positions.iter().map(|p| p[0]);
    let (lo, hi) = xs.fold((f32::MAX, f32::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
    (mesh.triangles.len(), lo, hi)
}

#[test]
fn an_inlined_world_is_drawn_in_place_with_its_own_names() {
    let dir = tempfile::tempdir().unwrap();
    let files = [
        ("world.wrl", world("\"parts/column.wrl\"").as_str()),
        ("parts/column.wrl", COLUMN),
        ("parts/capital.wrl", CAPITAL),
    ]
    .map(|(n, t)| (n, t.to_owned()));
    let files: Vec<(&str, &str)> = files.iter().map(|(n, t)| (*n, t.as_str())).collect();
    write(dir.path(), &files);
    let scene = load(dir.path()).unwrap();
    // 12 triangles a box: the world's, and two columns of two boxes each.
    let (triangles, lo, hi) = summary(&scene);
    assert_eq!(triangles, 12 * 5);
    // The columns' boxes (2 m wide) stand at x = ±10: from −11 to 11.
    assert_eq!((lo, hi), (-11.0, 11.0));
}

#[test]
fn an_inlines_urls_are_tried_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let world_text = world("\"parts/missing.wrl\" \"parts/column.wrl\"");
    write(
        dir.path(),
        &[("world.wrl", &world_text), ("parts/column.wrl", COLUMN), ("parts/capital.wrl", CAPITAL)],
    );
    assert_eq!(summary(&load(dir.path()).unwrap()).0, 12 * 5);

    let only_missing = world("\"parts/missing.wrl\"");
    write(dir.path(), &[("world.wrl", &only_missing)]);
    let e = load(dir.path()).unwrap_err().to_string();
    assert!(e.contains("world.wrl") && e.contains("`url` of Inline `COLUMN`"), "{e}");
    assert!(e.contains("no url can be read") && e.contains("parts/missing.wrl"), "{e}");
}

#[test]
fn a_world_that_inlines_itself_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = "#VRML V2.0 utf8\nShape { geometry Box {} }\nInline { url \"parts/b.wrl\" }\n";
    let b = "#VRML V2.0 utf8\nInline { url \"../world.wrl\" }\n";
    write(dir.path(), &[("world.wrl", a), ("parts/b.wrl", b)]);
    let e = load(dir.path()).unwrap_err().to_string();
    assert!(e.contains("the file inlines itself: world.wrl → parts/b.wrl → world.wrl"), "{e}");
    let e = bundle_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err();
    assert!(e.to_string().contains("the file inlines itself"), "{e}");
}

/// The bundle names each inlined file by its hash, in the world and in its list of files, so
/// it loads alone; renaming the inlined files leaves its identity as it was.
#[test]
fn a_bundle_carries_the_inlined_worlds_by_hash() {
    let dir = tempfile::tempdir().unwrap();
    let world_text = world("\"parts/column.wrl\"");
    write(
        dir.path(),
        &[("world.wrl", &world_text), ("parts/column.wrl", COLUMN), ("parts/capital.wrl", CAPITAL)],
    );
    let from_folder = load(dir.path()).unwrap();
    let bundle = bundle_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    assert_eq!(bundle.scene.included.len(), 2, "{:?}", bundle.scene.included);
    assert!(bundle.scene.included.iter().all(|r| r.starts_with("blake3:") && r.ends_with(".wrl")));
    let from_bundle = bundle.load(&Limits::default()).unwrap();
    assert_eq!(from_bundle.objects[0].mesh.positions, from_folder.objects[0].mesh.positions);

    let renamed = tempfile::tempdir().unwrap();
    let world_text = world("\"other/pillar.wrl\"");
    let column = COLUMN.replace("capital.wrl", "top.wrl");
    write(
        renamed.path(),
        &[("world.wrl", &world_text), ("other/pillar.wrl", &column), ("other/top.wrl", CAPITAL)],
    );
    let again = bundle_folder(&renamed.path().join("scene.toml"), &Limits::default()).unwrap();
    assert_eq!(again.id(), bundle.id(), "the same world under other file names");
}

#[test]
fn an_inline_without_a_url_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let world = "#VRML V2.0 utf8\nShape { geometry Box {} }\nDEF EMPTY Inline { }\n";
    write(dir.path(), &[("world.wrl", world)]);
    let e = load(dir.path()).unwrap_err().to_string();
    assert!(e.contains("world.wrl") && e.contains("`url` of Inline `EMPTY`"), "{e}");
    assert!(e.contains("an Inline needs the url of a file"), "{e}");
}
