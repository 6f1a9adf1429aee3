//! A scene folder as one file: the folder the studio hands back as a tar reads back as the same
//! bundle, and a folder sent as a zip bundles as the folder on disk does; what would leave the
//! folder, exceed a limit or cannot be read is refused, naming what is wrong.

use restauro_assets::bundle_scene;
use restauro_assets::folder::{bundle_folder_archive, folder_tar};
use restauro_scene::limits::Limits;
use std::path::{Path, PathBuf};

/// The wall fixture: two parts, stone and a glazed joint, under the sun.
const SCENE: &str = include_str!("../../scene/tests/data/wall/scene.toml");
const WALL_OBJ: &str = include_str!("../../scene/tests/data/wall/meshes/wall.obj");

/// The scene and its wall written into `dir`; the scene file's path.
fn write_scene(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(dir.join("meshes/wall.obj"), WALL_OBJ).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    dir.join("scene.toml")
}

/// A bundle written out as a folder reads back as the same bundle: the same canonical scene,
/// the same identity, the same files.
#[test]
fn a_bundle_written_as_a_folder_reads_back_as_itself() {
    let dir = tempfile::tempdir().unwrap();
    let bundle = bundle_scene(&write_scene(dir.path()), &Limits::default()).unwrap();
    let tar = folder_tar(&bundle, "wall-r1", "Revision 1\nof the wall").unwrap();
    let out = tempfile::tempdir().unwrap();
    tar::Archive::new(std::io::Cursor::new(tar)).unpack(out.path()).unwrap();
    let scene = out.path().join("wall-r1/scene.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.starts_with("# Revision 1\n# of the wall\n"), "{text}");
    let again = bundle_scene(&scene, &Limits::default()).unwrap();
    assert_eq!(again.canonical_json(), bundle.canonical_json());
    assert_eq!(again.id(), bundle.id());
    assert_eq!(again.files, bundle.files);
}

/// `entries` as a zip, each deflated.
fn zip_of(entries: &[(&str, &[u8])]) -> Vec<u8> {
    use std::io::Write;
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in entries {
        w.start_file(*name, options).unwrap();
        w.write_all(bytes).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// A scene folder sent as a zip (as a file manager packs one) bundles as the folder on disk
/// does; a path out of the folder, a file over the size limit and a damaged zip are refused,
/// naming what is wrong.
#[test]
fn a_scene_folder_sent_as_a_zip_bundles_as_the_folder_does() {
    let dir = tempfile::tempdir().unwrap();
    let on_disk = bundle_scene(&write_scene(dir.path()), &Limits::default()).unwrap();
    let zipped = zip_of(&[
        ("facade/scene.toml", SCENE.as_bytes()),
        ("facade/meshes/wall.obj", WALL_OBJ.as_bytes()),
    ]);
    let sent = bundle_folder_archive(&zipped, None, &Limits::default()).unwrap();
    assert_eq!(sent.id(), on_disk.id());

    let small = Limits { max_file_bytes: 4096, ..Limits::default() };
    let zeros = vec![0u8; 10_000];
    for (entries, limits, words) in [
        (
            vec![("../scene.toml", SCENE.as_bytes())],
            Limits::default(),
            "`../scene.toml` is not a path inside the folder",
        ),
        (
            vec![("/etc/scene.toml", SCENE.as_bytes())],
            Limits::default(),
            "is not a path inside the folder",
        ),
        (
            vec![("scene.toml", SCENE.as_bytes()), ("meshes/wall.obj", &zeros[..])],
            small,
            "`meshes/wall.obj` is more than 4096 bytes",
        ),
        (vec![("meshes/wall.obj", WALL_OBJ.as_bytes())], Limits::default(), "it has no scene file"),
    ] {
        let message =
            bundle_folder_archive(&zip_of(&entries), None, &limits).unwrap_err().to_string();
        assert!(message.contains(words), "{message}");
        assert!(message.starts_with("the folder sent"), "{message}");
    }
    let mut damaged = zipped.clone();
    damaged.truncate(zipped.len() / 2);
    let message =
        bundle_folder_archive(&damaged, None, &Limits::default()).unwrap_err().to_string();
    assert!(message.contains("not a readable zip archive"), "{message}");
}
