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
    let err = refused(&["render", s, "--out", r, "--spp", "0"]);
    assert!(err.contains("--spp: 0; use at least 1"), "{err}");
}
