//! Hostile and broken input (issue 15, "Trust the farm"): every file a scene reads is refused
//! with the file, the place and the fix — never a panic, a hang, an infinite or NaN value, or a
//! parser's internals. Each test builds the bad file itself and checks the words a restorer
//! reads, not an output of the code.

use base64::Engine;
use restauro_scene::formats::gltf::mesh as gltf_mesh;
use restauro_scene::formats::{obj, ply, vrml};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

struct Folder {
    dir: tempfile::TempDir,
}

impl Folder {
    fn new() -> Self {
        Self { dir: tempfile::tempdir().unwrap() }
    }

    fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let path = self.dir.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, bytes).unwrap();
        path
    }

    /// The folder as the loader names it (symbolic links such as macOS's /tmp resolved).
    fn canonical(&self) -> PathBuf {
        self.dir.path().canonicalize().unwrap()
    }
}

/// A scene of one object (`mesh`, every part of stone) under a sun, with `extra` TOML after it.
fn scene(mesh: &str, object_extra: &str, lights: &str) -> String {
    format!(
        r#"format = 1
[camera]
position = [0.0, -10.0, 1.0]
target = [0.0, 0.0, 1.0]
width = 32
height = 24

[spectra]
stone = "travertine_tufa_solid__eco_ward73"
daylight = {{ illuminant = "D65" }}

[materials.stone]
model = "lambert"
reflectance = "stone"

[[objects]]
name = "wall"
mesh = "{mesh}"
material = "stone"
{object_extra}

{lights}
"#
    )
}

const SUN: &str = r#"[[lights]]
kind = "sun"
illuminance_lux = 100000.0
azimuth_deg = 180.0
elevation_deg = 50.0
spectrum = "daylight"
"#;

const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n";

fn load(folder: &Folder, toml: &str) -> Result<LoadedScene, String> {
    let path = folder.write("scene.toml", toml);
    load_folder(&path, &Limits::default()).map_err(|e| e.to_string())
}

fn refused(folder: &Folder, toml: &str) -> String {
    match load(folder, toml) {
        Ok(_) => panic!("the scene should be refused:\n{toml}"),
        Err(e) => e,
    }
}

/// Run `f` on a thread and wait at most `seconds`: a hang fails the test instead of stalling it.
fn within<T: Send + 'static>(
    seconds: u64,
    what: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> T {
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(f());
    });
    receive
        .recv_timeout(Duration::from_secs(seconds))
        .unwrap_or_else(|_| panic!("{what} did not finish within {seconds} s"))
}

fn assert_has(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "expected «{p}» in: {message}");
    }
}

/// What `anyhow`'s `{:#}` prints: the message, then each source's, joined by ": ".
fn chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        out += &format!(": {s}");
        source = s.source();
    }
    out
}

// ---------------------------------------------------------------------------------------------
// 13. Panics inside third-party parsers

/// A glTF with one triangle: positions (`position_type`, VEC3) and indices (`index_type`,
/// SCALAR), the positions' view with `stride` and `position_view_length`.
fn gltf(
    position_type: u32,
    index_type: u32,
    stride: Option<u32>,
    position_view_length: u32,
) -> String {
    let mut bin = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u32, 1, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let data = base64::engine::general_purpose::STANDARD.encode(&bin);
    let stride = stride.map(|s| format!(r#","byteStride":{s}"#)).unwrap_or_default();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "accessors":[{{"bufferView":0,"componentType":{position_type},"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":{index_type},"count":3,"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{position_view_length}{stride}}},{{"buffer":0,"byteOffset":36,"byteLength":12}}],
        "buffers":[{{"byteLength":48,"uri":"data:application/octet-stream;base64,{data}"}}]}}"#
    )
}

#[test]
fn gltf_accessors_the_gltf_crate_would_panic_on_are_refused() {
    let path = Path::new("models/arch.gltf");
    // The well-formed file reads: the checks below refuse only what is wrong.
    assert_eq!(
        gltf_mesh::parse(gltf(5126, 5125, None, 36).as_bytes(), path).unwrap().triangles.len(),
        1
    );
    // Float indices: `unreachable!()` in the gltf crate.
    let e = gltf_mesh::parse(gltf(5126, 5126, None, 36).as_bytes(), path).unwrap_err().to_string();
    assert_has(
        &e,
        &["models/arch.gltf", "accessor 1 (indices)", "must be SCALAR of unsigned", "re-export"],
    );
    // A byte stride shorter than a VEC3 of floats: an assertion in the gltf crate.
    let e =
        gltf_mesh::parse(gltf(5126, 5125, Some(4), 36).as_bytes(), path).unwrap_err().to_string();
    assert_has(
        &e,
        &["models/arch.gltf", "accessor 0 (POSITION)", "byte stride of 4", "fix the stride"],
    );
    // Positions that are not floats.
    let e = gltf_mesh::parse(gltf(5121, 5125, None, 36).as_bytes(), path).unwrap_err().to_string();
    assert_has(&e, &["accessor 0 (POSITION)", "VEC3 of float"]);
}

#[test]
fn a_gltf_buffer_view_out_of_range_is_reported_as_such() {
    // The positions' view claims 24 bytes, the accessor needs 36: not "no POSITION attribute".
    let e = gltf_mesh::parse(gltf(5126, 5125, None, 24).as_bytes(), Path::new("arch.gltf"))
        .unwrap_err()
        .to_string();
    assert_has(
        &e,
        &["arch.gltf", "accessor 0 (POSITION)", "do not fit in buffer view 0 of 24 bytes"],
    );
    assert!(!e.contains("no POSITION attribute"), "{e}");
}

#[test]
fn a_ply_count_beyond_64_bits_is_refused_in_words() {
    let text = "ply\nformat ascii 1.0\nelement vertex 18446744073709551616\nproperty float x\nend_header\n0\n";
    let e = ply::parse(text.as_bytes(), Path::new("scan.ply")).unwrap_err().to_string();
    assert_has(&e, &["scan.ply:3:", "count `18446744073709551616`", "whole number below 2^64"]);
    // A count that fits 64 bits but not the file: refused before a single element is read.
    let binary = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    let e = ply::parse(binary.as_bytes(), Path::new("scan.ply")).unwrap_err().to_string();
    assert_has(
        &e,
        &["scan.ply", "element `vertex`", "4000000000000 elements but only 0 bytes follow"],
    );
}

#[test]
fn an_object_scaled_past_the_tracer_is_refused_by_scene_check() {
    let f = Folder::new();
    f.write("wall.obj", TRIANGLE_OBJ);
    let e = refused(&f, &scene("wall.obj", "transform = { scale = 1e308 }", SUN));
    assert_has(
        &e,
        &[
            "scene.toml",
            "objects[0] (wall).transform",
            "vertex 1 of `wall.obj`",
            "±1e9 m",
            "check the transform's scale",
        ],
    );
    // Survey coordinates of millions of metres are fine.
    assert!(
        load(&f, &scene("wall.obj", "transform = { translate = [3.5e5, 5.07e6, 580.0] }", SUN))
            .is_ok()
    );
}

// ---------------------------------------------------------------------------------------------
// 14. Hangs

#[cfg(unix)]
#[test]
fn a_scene_file_that_is_a_fifo_or_dev_zero_is_refused_not_waited_on() {
    let f = Folder::new();
    let fifo = f.dir.path().join("fifo.toml");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let zero = f.dir.path().join("zero.toml");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    for path in [fifo, zero] {
        let shown = path.clone();
        let e = within(20, &format!("loading {}", shown.display()), move || {
            load_folder(&path, &Limits::default()).map(|_| ()).unwrap_err().to_string()
        });
        assert_has(&e, &[&shown.display().to_string(), "not a regular file", "ordinary file"]);
    }
}

#[test]
fn vrml_def_use_chains_are_counted_before_they_are_walked() {
    // 40 levels of two USEs each: 2^40 − 1 instances, 2^39 of them a triangle.
    let mut text = "#VRML V2.0 utf8\nDEF g0 Shape { geometry IndexedFaceSet { coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] } coordIndex [0 1 2 -1] } }\n".to_string();
    for k in 1..=40 {
        text += &format!("DEF g{k} Group {{ children [ USE g{} USE g{} ] }}\n", k - 1, k - 1);
    }
    let e = within(5, "the DEF/USE chain", move || {
        vrml::parse(&text, Path::new("chain.wrl")).map(|_| ()).unwrap_err().to_string()
    });
    assert_has(
        &e,
        &[
            "chain.wrl",
            "node instances (counting USE copies)",
            "over the limit of 20000000",
            "--max-instances",
        ],
    );
}

#[test]
fn a_polygon_of_fifty_thousand_vertices_is_refused_by_its_limit() {
    let n = 50_000;
    let mut text: String = (0..n).map(|i| format!("v {} {} 0\n", i % 100, i / 100)).collect();
    text += &format!("f {}\n", (1..=n).map(|i| i.to_string()).collect::<Vec<_>>().join(" "));
    let e = obj::parse(&text, Path::new("big.obj")).unwrap_err().to_string();
    assert_has(
        &e,
        &[
            "big.obj",
            &format!("line {}", n + 1),
            "is 50000, over the limit of 10000",
            "--max-polygon-vertices",
        ],
    );
}

// ---------------------------------------------------------------------------------------------
// 15. Values that would render as inf or NaN

#[test]
fn light_levels_that_overflow_are_refused_with_the_bound() {
    let f = Folder::new();
    f.write("wall.obj", TRIANGLE_OBJ);
    let sun = SUN.replace("100000.0", "1e308");
    let e = refused(&f, &scene("wall.obj", "", &sun));
    assert_has(
        &e,
        &["scene.toml", "lights[0].illuminance_lux", "1e6 lux", "give the illuminance in lux"],
    );
    let sky = "[[lights]]\nkind = \"sky\"\nilluminance_lux = 1e308\nspectrum = \"daylight\"\n";
    let e = refused(&f, &scene("wall.obj", "", &format!("{SUN}\n{sky}")));
    assert_has(&e, &["lights[1].illuminance_lux", "1e6 lux"]);
    for kind in ["point", "spot"] {
        let extra = if kind == "spot" { "aim = [0.0, 0.0, 0.0]\ncone_deg = 30.0\n" } else { "" };
        let lamp = format!(
            "[[lights]]\nkind = \"{kind}\"\nposition = [0.0, -2.0, 2.0]\nintensity_cd = 1e308\nspectrum = \"daylight\"\n{extra}"
        );
        let e = refused(&f, &scene("wall.obj", "", &lamp));
        assert_has(&e, &["lights[0].intensity_cd", "1e9 cd", "candela"]);
    }
}

#[test]
fn vectors_of_the_wrong_length_are_refused_naming_the_field() {
    let f = Folder::new();
    f.write("wall.obj", TRIANGLE_OBJ);
    let good = scene("wall.obj", "", SUN);
    for (from, to, field) in [
        (
            "position = [0.0, -10.0, 1.0]",
            "position = [0.0, -10.0, 1.0, 5.0]",
            "`position` has 4 numbers",
        ),
        ("target = [0.0, 0.0, 1.0]", "target = [0.0, 0.0]", "`target` has 2 numbers"),
        (
            "material = \"stone\"",
            "material = \"stone\"\ntransform = { translate = [1.0, 2.0, 3.0, 4.0] }",
            "`translate` has 4 numbers",
        ),
        (
            "material = \"stone\"",
            "material = \"stone\"\ntransform = { scale = [1.0, 2.0] }",
            "`scale` has 2 numbers",
        ),
    ] {
        let e = refused(&f, &good.replace(from, to));
        assert_has(&e, &["scene.toml:", field, "3"]);
    }
    let lamp = "[[lights]]\nkind = \"point\"\nposition = [0.0, -2.0, 2.0, 1.0]\nintensity_cd = 100.0\nspectrum = \"daylight\"\n";
    let e = refused(&f, &scene("wall.obj", "", lamp));
    assert_has(&e, &["scene.toml", "`position` has 4 numbers; give exactly 3"]);
}

// ---------------------------------------------------------------------------------------------
// 16. Messages: the file, the place, the fix, once, in plain words

#[test]
fn ply_errors_say_where_in_plain_words() {
    let ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n";
    let e = ply::parse(ascii.as_bytes(), Path::new("scan.ply")).unwrap_err().to_string();
    assert_has(&e, &["scan.ply", "line 11 (element `vertex` 1)", "`zero` is not a number"]);
    assert!(!e.contains("ParseError") && !e.contains("LineCol"), "{e}");
    let mut binary = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    binary.extend_from_slice(&[0u8; 30]); // 2.5 vertices of 12 bytes
    let e = ply::parse(&binary, Path::new("scan.ply")).unwrap_err().to_string();
    assert_has(
        &e,
        &["scan.ply", "element `vertex` 2", "the file ends inside element", "truncated"],
    );
    assert!(!e.contains("fill whole buffer"), "{e}");
}

#[test]
fn text_that_is_not_utf8_is_refused_with_its_line_and_byte() {
    let f = Folder::new();
    let mut bytes = b"v 0 0 0\nv 1 0 0\n# caf".to_vec();
    bytes.push(0xe9); // Latin-1 é
    bytes.extend_from_slice(b"\nv 0 0 1\nf 1 2 3\n");
    f.write("meshes/wall.obj", &bytes);
    let e = refused(&f, &scene("meshes/wall.obj", "", SUN));
    assert_has(&e, &["wall.obj:3:6:", "byte 21 (0xe9) is not UTF-8", "save the file as UTF-8"]);
}

#[test]
fn a_missing_file_is_reported_once() {
    let e =
        load_folder(Path::new("/nonexistent/restauro/scene.toml"), &Limits::default()).unwrap_err();
    let text = chain(&e);
    assert_has(&text, &["/nonexistent/restauro/scene.toml", "does not exist", "check the path"]);
    assert!(text.matches("does not exist").count() == 1, "said twice: {text}");
    assert!(!text.contains("(os error 2)"), "{text}");
    // A file the scene refers to: where it was looked for, in the same words.
    let f = Folder::new();
    let e = refused(&f, &scene("meshes/gone.obj", "", SUN));
    let looked = f.canonical().join("meshes/gone.obj");
    assert_has(
        &e,
        &["objects[0] (wall).mesh", &format!("looked for {}", looked.display()), "does not exist"],
    );
    assert!(!e.contains("os error"), "{e}");
}

#[test]
fn mesh_errors_name_the_mesh_by_its_path() {
    let f = Folder::new();
    f.write("meshes/north/wall.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 9\n");
    let e = refused(&f, &scene("meshes/north/wall.obj", "", SUN));
    let full = f.canonical().join("meshes/north/wall.obj");
    assert_has(&e, &[&format!("{}: line 4: vertex index 9 is out of range", full.display())]);
}

// ---------------------------------------------------------------------------------------------
// Found by the fuzz harness (tests/tests/fuzz_readers.rs)

/// The fuzz harness repeated blocks of the demo's scenes a few thousand times, each copy opening
/// an inline table it never closes, with a table header and a stray `]` between them: the TOML
/// parser (toml 0.9) overflowed a 2 MiB thread stack (a worker's threads have that) and
/// aborted the process. Reduced to its core, 3000 times.
#[test]
fn deeply_nested_toml_is_refused_before_it_overflows_the_stack() {
    let f = Folder::new();
    f.write("wall.obj", TRIANGLE_OBJ);
    let block = "ials.board]\n[[objects]]\nmaterials = { travertine_found\0=";
    let deep = format!("{}\n{}", scene("wall.obj", "", SUN), block.repeat(3000));
    let path = f.write("scene.toml", &deep);
    let e = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || load_folder(&path, &Limits::default()).map(|_| ()).unwrap_err().to_string())
        .unwrap()
        .join()
        .unwrap();
    assert_has(&e, &["scene.toml:", "nested more than 32 deep", "damaged"]);
    // Brackets inside strings and comments are text, not nesting.
    let text =
        scene("wall.obj", "", SUN).replace("[camera]", &format!("# {}\n[camera]", "[".repeat(40)));
    let text = text.replace("name = \"wall\"", &format!("name = \"{}\"", "{".repeat(40)));
    assert!(load(&f, &text).is_ok());
}

/// The gltf crate's validation indexes a primitive's POSITION accessor before it checks the
/// index (a panic); and it subtracts the GLB header from the stated length without checking
/// (an overflow). Both found by the harness, from one changed number or byte.
#[test]
fn gltf_references_and_glb_framing_the_gltf_crate_trusts_are_checked() {
    let json = gltf(5126, 5125, None, 36).replace(r#""POSITION":0"#, r#""POSITION":7"#);
    let e = gltf_mesh::parse(json.as_bytes(), Path::new("arch.gltf")).unwrap_err().to_string();
    assert_has(
        &e,
        &[
            "arch.gltf",
            "meshes[0].primitives[0].attributes.POSITION",
            "refers to accessor 7",
            "2 accessors",
        ],
    );
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&5u32.to_le_bytes()); // shorter than the header itself
    glb.extend_from_slice(&[0; 20]);
    let e = gltf_mesh::parse(&glb, Path::new("arch.glb")).unwrap_err().to_string();
    assert_has(&e, &["arch.glb", "GLB header", "length of 5 bytes", "truncated or damaged"]);
}

/// The scene model reads a folder and fetches nothing: a file named by URL is refused, naming
/// the place and the loader that fetches it (restauro-assets), and never reaches the network.
#[test]
fn a_url_read_without_a_fetcher_names_the_loader_that_fetches() {
    let folder = Folder::new();
    let url = "https://survey.example.org/aosta/facade.obj";
    let message = refused(&folder, &scene(url, "", SUN));
    assert!(message.contains("objects[0] (wall).mesh"), "{message}");
    assert!(message.contains(&format!("`{url}` is a URL")), "{message}");
    assert!(message.contains("restauro_assets::load_scene"), "{message}");
}
