//! An OBJ with its material library as photogrammetry exports it: `mtllib` beside the OBJ,
//! `map_Kd` photos beside the library (with options before the file name, and Windows
//! separators); each `usemtl` part gets its photo, a library or photo that cannot be read is a
//! note, and a bundle carries the library and its photos by hash.

use restauro_scene::bundle::bundle_folder;
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use std::path::Path;

/// Two parts on two quads, both with texture coordinates.
const OBJ: &str = "mtllib model.mtl\n\
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 3 1 0\nv 2 1 0\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
usemtl stone\nf 1/1 2/2 3/3 4/4\nusemtl mortar\nf 5/1 6/2 7/3 8/4\n";

const MTL: &str = "newmtl stone\nKd 0.8 0.8 0.8\nmap_Kd -s 1 1 1 textures\\block.png\n\
newmtl mortar\nKd 0.5 0.5 0.5\n";

/// A 2 × 1 RGB PNG: `left`, then white.
fn png(left: [u8; 3]) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, 2, 1);
        encoder.set_color(png::ColorType::Rgb);
        let mut w = encoder.write_header().unwrap();
        w.write_image_data(&[left[0], left[1], left[2], 255, 255, 255]).unwrap();
    }
    out
}

fn write(dir: &Path, files: &[(&str, &[u8])]) {
    for (name, bytes) in files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
    let toml = "format = 1\n[camera]\nposition = [1.5, 0.5, 5.0]\ntarget = [1.5, 0.5, 0.0]\nup = [0, 1, 0]\nwidth = 8\nheight = 8\n\
         [spectra]\nday = { illuminant = \"D65\" }\ngrey = { constant = 0.5 }\n\
         [materials.stone]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
         [[objects]]\nname = \"scan\"\nmesh = \"scan/model.obj\"\nmaterial = \"stone\"\nup_axis = \"z\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 0.0\nelevation_deg = 60.0\nspectrum = \"day\"\n";
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
}

fn photo_of(scene: &LoadedScene, part: &str) -> Option<[u16; 3]> {
    let groups = &scene.objects[0].mesh.groups;
    let group = groups.iter().find(|g| g.name == part).expect("the part");
    group.photo.as_ref().map(|t| t.texels[0])
}

#[test]
fn each_part_gets_the_photo_its_library_names() {
    let dir = tempfile::tempdir().unwrap();
    let photo = png([200, 100, 50]);
    write(
        dir.path(),
        &[
            ("scan/model.obj", OBJ.as_bytes()),
            ("scan/model.mtl", MTL.as_bytes()),
            ("scan/textures/block.png", &photo),
        ],
    );
    let scene = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    // 8-bit 200 is 200·257 in the 16-bit texels.
    assert_eq!(photo_of(&scene, "stone"), Some([200 * 257, 100 * 257, 50 * 257]));
    assert_eq!(photo_of(&scene, "mortar"), None, "the mortar has no map_Kd");
    assert!(scene.notes.iter().all(|n| !n.contains("not read")), "{:?}", scene.notes);
}

#[test]
fn a_library_or_photo_that_cannot_be_read_is_a_note() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), &[("scan/model.obj", OBJ.as_bytes())]);
    let scene = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    assert_eq!(photo_of(&scene, "stone"), None);
    let notes = scene.notes.join("\n");
    assert!(
        notes.contains("model.obj") && notes.contains("mtllib model.mtl is not read"),
        "{notes}"
    );

    write(dir.path(), &[("scan/model.mtl", MTL.as_bytes())]);
    let scene = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    let notes = scene.notes.join("\n");
    assert!(
        notes.contains("model.mtl") && notes.contains("the photo textures/block.png of `stone`"),
        "{notes}"
    );

    write(dir.path(), &[("scan/textures/block.png", b"not a png")]);
    let e = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err();
    assert!(e.to_string().contains("block.png"), "{e}");
}

/// The bundle carries the library and the photo (the OBJ and the library naming them by hash),
/// loads alone, and keeps its identity when the files are renamed.
#[test]
fn a_bundle_carries_the_library_and_its_photos() {
    let dir = tempfile::tempdir().unwrap();
    let photo = png([10, 20, 30]);
    write(
        dir.path(),
        &[
            ("scan/model.obj", OBJ.as_bytes()),
            ("scan/model.mtl", MTL.as_bytes()),
            ("scan/textures/block.png", &photo),
        ],
    );
    let bundle = bundle_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    let kinds: Vec<&str> =
        bundle.scene.included.iter().map(|r| r.rsplit('.').next().unwrap()).collect();
    assert_eq!(kinds.len(), 2, "{:?}", bundle.scene.included);
    assert!(kinds.contains(&"mtl") && kinds.contains(&"png"), "{kinds:?}");
    let loaded = bundle.load(&Limits::default()).unwrap();
    assert_eq!(photo_of(&loaded, "stone"), Some([10 * 257, 20 * 257, 30 * 257]));

    let renamed = tempfile::tempdir().unwrap();
    let obj = OBJ.replace("model.mtl", "library.mtl");
    let mtl = MTL.replace("textures\\block.png", "photo.png");
    write(
        renamed.path(),
        &[
            ("scan/model.obj", obj.as_bytes()),
            ("scan/library.mtl", mtl.as_bytes()),
            ("scan/photo.png", &photo),
        ],
    );
    let again = bundle_folder(&renamed.path().join("scene.toml"), &Limits::default()).unwrap();
    assert_eq!(again.id(), bundle.id(), "the same scan under other file names");
}

#[test]
fn a_photo_before_any_material_is_refused_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = "# exported\nmap_Kd photo.png\nnewmtl stone\n";
    write(dir.path(), &[("scan/model.obj", OBJ.as_bytes()), ("scan/model.mtl", mtl.as_bytes())]);
    let e =
        load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(e.contains("model.mtl: line 2") && e.contains("before any `newmtl`"), "{e}");
}
