//! `restauro scene aosta | check | bundle` as a user runs them.

mod common;
use common::*;

#[test]
fn aosta_writes_a_scene_that_checks_and_bundles() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("aosta");
    let o = out.to_str().unwrap();
    let run = restauro(&["scene", "aosta", "--out", o, "--width", "320", "--height", "180"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let text = String::from_utf8(run.stdout).unwrap();
    assert!(text.contains("aosta.toml: valid"), "{text}");
    assert!(text.contains("sun: 100000 lux, azimuth"), "{text}");
    // The sky by its name, not its enum's (`Uniform distribution`).
    assert!(text.contains("uniform sky: 15000 lux on the horizontal"), "{text}");
    assert!(!text.contains("Uniform") && !text.contains("distribution"), "{text}");
    assert!(text.contains("variants: as-found, cleaned"), "{text}");
    let scene = out.join("aosta.toml");
    let s = scene.to_str().unwrap();
    let check = restauro(&["scene", "check", s]);
    assert!(check.status.success());
    assert!(String::from_utf8_lossy(&check.stdout).contains("triangles in 1 objects"));
    // The bundle's identity is the same from the same files, and names the mesh by its hash.
    let id = |args: &[&str]| {
        let b = restauro(args);
        assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
        String::from_utf8(b.stdout).unwrap()
    };
    let first = id(&["scene", "bundle", s]);
    assert_eq!(first, id(&["scene", "bundle", s]));
    let mesh = std::fs::read(out.join("meshes/facade.obj")).unwrap();
    assert!(first.contains(&blake3::hash(&mesh).to_hex().to_string()), "{first}");
    // A limit set on the command line is enforced and named.
    let limited = restauro(&["scene", "check", s, "--max-triangles", "1000"]);
    assert_eq!(limited.status.code(), Some(1));
    let err = String::from_utf8(limited.stderr).unwrap();
    assert!(
        err.contains(
            "over the limit of 1000; simplify the meshes, or raise the limit with --max-triangles"
        ),
        "{err}"
    );
}

#[test]
fn a_bad_scene_is_refused_with_its_place() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, "format = 1\n[camera]\nwidth = 10\nheight = 10\nfocal = 3\n").unwrap();
    let run = restauro(&["scene", "check", scene.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(err.contains("s.toml:5:1: unknown field `focal`"), "{err}");
}

#[test]
fn render_writes_exr_with_spectral_layers_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("aosta");
    ok(&["scene", "aosta", "--out", out.to_str().unwrap(), "--width", "48", "--height", "27"]);
    let scene = out.join("aosta.toml");
    let s = scene.to_str().unwrap();
    let results = dir.path().join("results");
    let r = results.to_str().unwrap();
    let text = ok(&[
        "render",
        s,
        "--out",
        r,
        "--variant",
        "cleaned",
        "--spp",
        "1",
        "--spectral",
        "--tile",
        "16",
    ]);
    assert!(text.contains("wrote") && text.contains("aosta-cleaned.exr"), "{text}");
    // The scene's integrator (`path`) by its name, not its enum's (`Path`).
    assert!(text.contains("(48×27, path tracing, 1 spp,"), "{text}");
    let image =
        restauro_image::image_files::read_exr(&results.join("aosta-cleaned.exr"), 1 << 20).unwrap();
    assert_eq!((image.width, image.height), (48, 27));
    assert!(image.pixels.iter().any(|p| p[1] > 100.0), "the sunlit facade is bright");
    let png = std::fs::read(results.join("aosta-cleaned.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // Refusals name what is wrong.
    let err = refused(&["render", s, "--out", r, "--variant", "polished"]);
    assert!(
        err.contains("unknown variant `polished`; the scene defines as-found, cleaned"),
        "{err}"
    );
    let err = refused_usage(&["render", s, "--out", r, "--spp", "0"]);
    assert!(err.contains("'--spp <SPP>': 0; use at least 1"), "{err}");
}

/// `scene bundle --out FILE.tar` writes one file to share; `scene check` and `render` take it as
/// they take the scene, and render the same image bit for bit. A changed or foreign archive is
/// refused with what is wrong.
#[test]
fn a_bundle_archive_is_a_scene_to_share() {
    use restauro_image::image_files::{MAX_PIXELS, read_exr};
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("aosta");
    ok(&["scene", "aosta", "--out", folder.to_str().unwrap(), "--width", "96", "--height", "54"]);
    let scene = folder.join("aosta.toml");
    let archive = dir.path().join("share").join("aosta.tar");
    std::fs::create_dir_all(archive.parent().unwrap()).unwrap();
    let text =
        ok(&["scene", "bundle", scene.to_str().unwrap(), "--out", archive.to_str().unwrap()]);
    assert!(text.contains(&format!("wrote {}", archive.display())), "{text}");
    // Shared: the scene's own folder is gone.
    std::fs::remove_dir_all(&folder).unwrap();
    let a = archive.to_str().unwrap();
    assert!(ok(&["scene", "check", a]).contains("triangles in 1 objects"));
    let render = |scene: &str, out: &std::path::Path| {
        let o = out.to_str().unwrap();
        ok(&["render", scene, "--in-process", "--spp", "1", "--variant", "cleaned", "--out", o]);
        read_exr(&out.join("aosta-cleaned.exr"), MAX_PIXELS).unwrap().pixels
    };
    let from_archive = render(a, &dir.path().join("from-archive"));
    // The same scene, written again, from its folder.
    ok(&["scene", "aosta", "--out", folder.to_str().unwrap(), "--width", "96", "--height", "54"]);
    let from_folder = render(scene.to_str().unwrap(), &dir.path().join("from-folder"));
    assert!(from_archive == from_folder, "the archive renders another image");

    // One byte changed in a file it holds (the mesh is the last entry): refused.
    let mut bytes = std::fs::read(&archive).unwrap();
    let at = bytes.len() - 2048;
    let changed = dir.path().join("changed.tar");
    bytes[at - 100] ^= 0x20;
    std::fs::write(&changed, &bytes).unwrap();
    let e = refused(&["scene", "check", changed.to_str().unwrap()]);
    assert!(e.contains("changed.tar") && (e.contains("corrupt") || e.contains("changed")), "{e}");
    // Not an archive at all.
    let foreign = dir.path().join("notes.tar");
    std::fs::write(&foreign, "these are my notes, not a tar file\n".repeat(40)).unwrap();
    let e = refused(&["scene", "check", foreign.to_str().unwrap()]);
    assert!(e.contains("notes.tar") && e.contains("tar"), "{e}");
    let e = refused(&["scene", "bundle", scene.to_str().unwrap(), "--out", "x.zip"]);
    assert!(e.contains(".tar"), "{e}");
}

/// `scene new --mesh` writes a starter scene for a user's own model that checks and renders at
/// once, with every part listed.
#[test]
fn scene_new_writes_a_starter_scene_that_renders() {
    let dir = tempfile::tempdir().unwrap();
    let survey = dir.path().join("survey");
    std::fs::create_dir_all(&survey).unwrap();
    // A wall 8 m wide, 4 m high, with its plinth as a second part.
    let obj = "v -4 0 0\nv 4 0 0\nv 4 0 4\nv -4 0 4\nv -4 0 0.5\nv 4 0 0.5\n\
               g wall\nf 5 6 3 4\ng plinth\nf 1 2 6 5\n";
    let mesh = survey.join("chapel wall.obj");
    std::fs::write(&mesh, obj).unwrap();
    let m = mesh.to_str().unwrap();
    let text = ok(&["scene", "new", "--mesh", m, "--site", "45.737,7.323"]);
    assert!(text.contains("2 parts: wall, plinth"), "{text}");
    let scene = survey.join("chapel wall.toml");
    let toml = std::fs::read_to_string(&scene).unwrap();
    assert!(toml.contains("materials = { wall = \"stone\", plinth = \"stone\" }"), "{toml}");
    assert!(toml.contains("latitude_deg = 45.737"), "{toml}");
    let s = scene.to_str().unwrap();
    assert!(ok(&["scene", "check", s]).contains("valid"));
    let out = dir.path().join("render");
    let o = out.to_str().unwrap();
    ok(&["render", s, "--in-process", "--spp", "1", "--width", "64", "--height", "36", "--out", o]);
    // The wall is in view: the render is not black.
    let image = restauro_image::image_files::read_exr(
        &out.join("chapel_wall.exr"),
        restauro_image::image_files::MAX_PIXELS,
    )
    .unwrap();
    let lit = image.pixels.iter().filter(|p| p[1] > 0.0).count();
    assert!(lit > image.pixels.len() / 4, "only {lit} pixels see the model");
    // Written again: refused unless --force; elsewhere, the model is copied beside the scene.
    let e = refused(&["scene", "new", "--mesh", m]);
    assert!(e.contains("--force"), "{e}");
    let elsewhere = dir.path().join("project");
    ok(&["scene", "new", "--mesh", m, "--out", elsewhere.to_str().unwrap()]);
    assert!(elsewhere.join("meshes/chapel wall.obj").is_file());
    assert!(
        ok(&["scene", "check", elsewhere.join("chapel wall.toml").to_str().unwrap()])
            .contains("valid")
    );
    let e = refused(&["scene", "new", "--mesh", m, "--site", "north", "--force"]);
    assert!(e.contains("--site"), "{e}");
}

/// A model exported Y-up (an open-bottomed house, 4 m wide, 3 m deep, 2 m high, with its +Z
/// written as +Y): `scene check` says it lies on its back, `scene new` reads it Y-up.
#[test]
fn a_y_up_model_is_stood_up() {
    let dir = tempfile::tempdir().unwrap();
    let (x, y, z) = (4.0, 3.0, 2.0);
    let quads: [[[f64; 3]; 4]; 5] = [
        [[0., 0., 0.], [x, 0., 0.], [x, 0., z], [0., 0., z]],
        [[x, y, 0.], [0., y, 0.], [0., y, z], [x, y, z]],
        [[0., y, 0.], [0., 0., 0.], [0., 0., z], [0., y, z]],
        [[x, 0., 0.], [x, y, 0.], [x, y, z], [x, 0., z]],
        [[0., 0., z], [x, 0., z], [x, y, z], [0., y, z]],
    ];
    let mut obj = String::from("g walls\n");
    for (q, quad) in quads.iter().enumerate() {
        for [a, b, c] in quad {
            obj += &format!("v {a} {c} {}\n", -b);
        }
        obj += &format!("f {} {} {} {}\n", 4 * q + 1, 4 * q + 2, 4 * q + 3, 4 * q + 4);
    }
    let mesh = dir.path().join("house.obj");
    std::fs::write(&mesh, obj).unwrap();
    let text = ok(&["scene", "new", "--mesh", mesh.to_str().unwrap()]);
    assert!(text.contains("looked Y-up"), "{text}");
    let scene = dir.path().join("house.toml");
    let toml = std::fs::read_to_string(&scene).unwrap();
    assert!(toml.contains("\nup_axis = \"y\"\n"), "{toml}");
    // Framed standing: 4 m wide, 3 m deep, 2 m high.
    assert!(toml.contains("(4.0 × 3.0 × 2.0 m)"), "{toml}");
    let check = ok(&["scene", "check", scene.to_str().unwrap()]);
    assert!(!check.contains("lies on its back"), "{check}");
    // Without the line, `scene check` says what is wrong and what to write.
    std::fs::write(&scene, toml.replace("\nup_axis = \"y\"\n", "\n")).unwrap();
    let check = ok(&["scene", "check", scene.to_str().unwrap()]);
    assert!(check.contains("`house.obj` probably lies on its back"), "{check}");
    assert!(check.contains("add `up_axis = \"y\"`"), "{check}");
}

/// A photogrammetry export (OBJ, its material library, the photo in a subfolder) written to a
/// scene elsewhere: the library and the photo are copied with the model, and the part shows
/// its photo (so `scene check` notes nothing unread).
#[test]
fn scene_new_copies_an_objs_library_and_photos_with_it() {
    let dir = tempfile::tempdir().unwrap();
    let survey = dir.path().join("survey");
    std::fs::create_dir_all(survey.join("tex")).unwrap();
    let obj = "mtllib scan.mtl\nv -4 0 0\nv 4 0 0\nv 4 0 4\nv -4 0 4\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl scan\nf 1/1 2/2 3/3 4/4\n";
    std::fs::write(survey.join("scan.obj"), obj).unwrap();
    std::fs::write(survey.join("scan.mtl"), "newmtl scan\nmap_Kd tex/scan_0.png\n").unwrap();
    let mut png_bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png_bytes, 1, 1);
        encoder.set_color(png::ColorType::Rgb);
        encoder.write_header().unwrap().write_image_data(&[120, 110, 100]).unwrap();
    }
    std::fs::write(survey.join("tex/scan_0.png"), &png_bytes).unwrap();
    let project = dir.path().join("project");
    let mesh = survey.join("scan.obj");
    ok(&["scene", "new", "--mesh", mesh.to_str().unwrap(), "--out", project.to_str().unwrap()]);
    for copied in ["meshes/scan.obj", "meshes/scan.mtl", "meshes/tex/scan_0.png"] {
        assert!(project.join(copied).is_file(), "{copied} was not copied");
    }
    let check = ok(&["scene", "check", project.join("scan.toml").to_str().unwrap()]);
    assert!(check.contains("valid") && !check.contains("not read"), "{check}");
}

/// A VRML97 world that inlines other files is not copied away from them by `scene new --out`:
/// the refusal says to write the scene beside the model.
#[test]
fn scene_new_keeps_a_world_with_inlines_beside_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let world = dir.path().join("world.wrl");
    std::fs::write(&world, "#VRML V2.0 utf8\nInline { url \"parts/column.wrl\" }\n").unwrap();
    let elsewhere = dir.path().join("project");
    let e = refused(&[
        "scene",
        "new",
        "--mesh",
        world.to_str().unwrap(),
        "--out",
        elsewhere.to_str().unwrap(),
    ]);
    assert!(e.contains("world.wrl") && e.contains("inlines other files"), "{e}");
    assert!(e.contains("leave out --out"), "{e}");
}

/// A laser scan with vertex colours and a photogrammetry export with its photo, each made a
/// scene: `scene check` says what each part shows over its spectrum, and nothing once the
/// material says `detail = "none"`.
#[test]
fn scene_check_says_which_parts_show_their_files_colours() {
    let dir = tempfile::tempdir().unwrap();
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scans");
    for (file, shown) in [
        ("weathered-patch.ply", "→stone (vertex colours)"),
        ("weathered-patch.glb", "→stone (its photo)"),
    ] {
        let mesh = dir.path().join(file);
        std::fs::copy(data.join(file), &mesh).unwrap();
        ok(&["scene", "new", "--mesh", mesh.to_str().unwrap()]);
        let scene = mesh.with_extension("toml");
        let check = ok(&["scene", "check", scene.to_str().unwrap()]);
        assert!(check.contains(shown), "{check}");
        let toml = std::fs::read_to_string(&scene).unwrap();
        let plain = toml
            .replace("reflectance = \"stone\"\n", "reflectance = \"stone\"\ndetail = \"none\"\n");
        assert_ne!(plain, toml);
        std::fs::write(&scene, plain).unwrap();
        let check = ok(&["scene", "check", scene.to_str().unwrap()]);
        assert!(!check.contains(shown), "{check}");
        std::fs::remove_file(&scene).unwrap();
    }
}
