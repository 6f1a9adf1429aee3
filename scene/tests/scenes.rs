//! Scene files as a restorer writes them: every mesh format through a scene, every class of bad
//! input refused with its place and fix, bundles that are stable and self-sufficient.

use restauro_scene::bundle::bundle_folder;
use restauro_scene::load::{Limits, LoadedScene, ResolvedLight, load_folder};
use std::path::PathBuf;

/// A scene folder in a temporary directory.
struct Folder {
    dir: tempfile::TempDir,
}

impl Folder {
    fn new() -> Self {
        Self { dir: tempfile::tempdir().unwrap() }
    }

    fn write(&self, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
        let path = self.dir.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, text).unwrap();
        path
    }
}

const QUAD_OBJ: &str =
    "v -1 0 0\nv 1 0 0\nv 1 0 2\nv -1 0 2\nusemtl stone\nf 1 2 3 4\nusemtl joint\nf 1 2 3\n";

fn scene_toml(objects: &str, extra: &str) -> String {
    format!(
        r#"format = 1
[camera]
position = [0.0, -10.0, 1.0]
target = [0.0, 0.0, 1.0]
width = 64
height = 48

[spectra]
travertine = "travertine_tufa_solid__eco_ward73"
soot = "carbon_black_soot_proxy__usgs_GDS68"
dirty = {{ mix = [{{ spectrum = "travertine", weight = 0.7 }}, {{ spectrum = "soot", weight = 0.3 }}] }}
sunlight = {{ illuminant = "D65" }}

[materials.stone]
model = "lambert"
reflectance = "travertine"
degraded = {{ reflectance = "dirty" }}

[materials.glaze]
model = "cook-torrance"
reflectance = "travertine"
roughness = 0.2
ior = 1.5

{objects}

[[lights]]
kind = "sun"
illuminance_lux = 100000.0
azimuth_deg = 180.0
elevation_deg = 50.0
spectrum = "sunlight"

[variants.as-found]
state = "degraded"

{extra}
"#
    )
}

const OBJ_OBJECT: &str = r#"[[objects]]
name = "wall"
mesh = "meshes/wall.obj"
materials = { stone = "stone", joint = "glaze" }
"#;

fn load(folder: &Folder, toml: &str) -> Result<LoadedScene, String> {
    let path = folder.write("scene.toml", toml);
    load_folder(&path, &Limits::default()).map_err(|e| e.to_string())
}

fn refused(folder: &Folder, toml: &str) -> String {
    load(folder, toml).expect_err("the scene should be refused")
}

#[test]
fn a_scene_with_an_obj_loads_with_its_parts_and_lights() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let scene = load(&f, &scene_toml(OBJ_OBJECT, "")).unwrap();
    assert_eq!(scene.triangle_count(), 3);
    let wall = &scene.objects[0];
    let parts: Vec<(&str, &str)> = wall
        .mesh
        .groups
        .iter()
        .map(|g| g.name.as_str())
        .zip(wall.group_materials.iter().map(String::as_str))
        .collect();
    assert_eq!(parts, [("stone", "stone"), ("joint", "glaze")]);
    // The mixture: 0.7 travertine + 0.3 soot, band by band.
    let (t, s, d) = (scene.spectra["travertine"], scene.spectra["soot"], scene.spectra["dirty"]);
    assert!((d[40] - (0.7 * t[40] + 0.3 * s[40])).abs() < 1e-6);
    match &scene.lights[0] {
        ResolvedLight::Sun { direction, illuminance_lux, .. } => {
            assert_eq!(*illuminance_lux, 100_000.0);
            assert!(
                (direction[1] + 50f64.to_radians().cos()).abs() < 1e-12,
                "south: {direction:?}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(scene.state_of("as-found", "wall", "stone"), Some("degraded"));
    // The glaze has no degraded state: the scene says so.
    assert!(scene.notes.iter().any(|n| n.contains("glaze (degraded)")), "{:?}", scene.notes);
    // The travertine starts at 400 nm: its extrapolation is reported.
    assert!(scene.notes.iter().any(|n| n.contains("380–395 nm extrapolated")), "{:?}", scene.notes);
}

#[test]
fn every_mesh_format_loads_through_a_scene() {
    let f = Folder::new();
    f.write("meshes/a.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 0 1\n3 0 1 2\n");
    f.write(
        "meshes/b.wrl",
        "#VRML V2.0 utf8\nTransform { translation 5 0 0 children [ DEF B Shape { geometry IndexedFaceSet { coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] } coordIndex [0 1 2 -1] } } ] }\nPointLight { }\n",
    );
    let objects = r#"
[[objects]]
name = "scan"
mesh = "meshes/a.ply"
material = "stone"
transform = { translate = [0.0, 0.0, 2.0], scale = 2.0 }

[[objects]]
name = "survey"
mesh = "meshes/b.wrl"
material = "stone"
"#;
    let scene = load(&f, &scene_toml(objects, "")).unwrap();
    let scan = scene.objects[0].mesh.bounds().unwrap();
    assert_eq!((scan.min, scan.max), ([0.0, 0.0, 2.0], [2.0, 0.0, 4.0]));
    // VRML is Y-up: its +Y becomes +Z.
    let survey = scene.objects[1].mesh.bounds().unwrap();
    let near = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
    assert!(near(survey.min, [5.0, 0.0, 0.0]) && near(survey.max, [6.0, 0.0, 1.0]), "{survey:?}");
    // The file's own notes reach `scene check`, naming the object, the file and the line.
    let light = scene.notes.iter().find(|n| n.contains("PointLight")).expect("a note");
    assert!(
        light.starts_with("object `survey`: ") && light.contains("b.wrl:3: PointLight"),
        "{light}"
    );
}

/// A PLY file has one part, `default` (as an OBJ without groups): its name must not depend on
/// the file's name, which a bundle replaces by the file's hash — a scene that binds the part
/// loads the same from its folder and from its bundle (on the coordinator and the workers).
#[test]
fn a_ply_part_bound_by_name_loads_from_its_bundle_too() {
    let f = Folder::new();
    f.write("meshes/scan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 0 1\n3 0 1 2\n");
    let objects = "[[objects]]\nname = \"scan\"\nmesh = \"meshes/scan.ply\"\nmaterials = { default = \"stone\" }\n";
    let path = f.write("scene.toml", scene_toml(objects, ""));
    let from_folder = load_folder(&path, &Limits::default()).unwrap();
    assert_eq!(from_folder.objects[0].mesh.groups[0].name, "default");
    let bundle = bundle_folder(&path, &Limits::default()).unwrap();
    let from_bundle = bundle.load(&Limits::default()).unwrap();
    assert_eq!(from_bundle.objects[0].group_materials, ["stone"]);
}

/// A glTF buffer of one triangle: three f32 VEC3 positions (bytes 0–35), three u16 indices.
fn triangle_bin() -> Vec<u8> {
    let mut bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    bin.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    bin
}

/// A `.gltf` with its `.bin` beside it, as most exporters write it: read from the scene's folder,
/// embedded in the bundle (one file, by hash), the same triangles both ways; a buffer outside the
/// folder is refused.
#[test]
fn a_gltf_with_its_bin_beside_it_loads_and_bundles() {
    let f = Folder::new();
    f.write("meshes/wall.bin", triangle_bin());
    let gltf = |uri: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
            "buffers":[{{"byteLength":42,"uri":"{uri}"}}]}}"#
        )
    };
    f.write("meshes/wall.gltf", gltf("wall.bin"));
    let objects =
        "[[objects]]\nname = \"wall\"\nmesh = \"meshes/wall.gltf\"\nmaterial = \"stone\"\n";
    let path = f.write("scene.toml", scene_toml(objects, ""));
    let from_folder = load_folder(&path, &Limits::default()).unwrap();
    assert_eq!(from_folder.objects[0].mesh.triangles.len(), 1);
    let bundle = bundle_folder(&path, &Limits::default()).unwrap();
    assert_eq!(bundle.files.len(), 1, "the model and its buffer are one file in the bundle");
    let from_bundle = bundle.load(&Limits::default()).unwrap();
    assert_eq!(from_bundle.objects[0].mesh.positions, from_folder.objects[0].mesh.positions);
    // A buffer outside the scene's folder is refused, as any file outside it.
    f.write("meshes/wall.gltf", gltf("../../wall.bin"));
    let err = load_folder(&path, &Limits::default()).unwrap_err().to_string();
    assert!(err.contains("leaves the scene's folder") || err.contains("cannot be opened"), "{err}");
    // A missing buffer names the file looked for.
    f.write("meshes/wall.gltf", gltf("gone.bin"));
    let err = load_folder(&path, &Limits::default()).unwrap_err().to_string();
    assert!(err.contains("meshes/gone.bin"), "{err}");
}

/// A luminaire with a photometric file is rendered at the file's own absolute photometry;
/// `scene check` says its flux, peak and beam; an `intensity_cd` that departs from the file is
/// noted; without a file, `intensity_cd` is required.
#[test]
fn a_luminaire_renders_its_file_as_measured() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let cos =
        concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/photometric/lambertian_cos_1000cd.ies");
    f.write("lamps/cos.ies", std::fs::read(cos).unwrap());
    let lamp = |intensity: &str| {
        format!(
            "[[lights]]\nkind = \"point\"\nposition = [0.0, -2.0, 2.0]\n{intensity}spectrum = \"sunlight\"\nies = \"lamps/cos.ies\"\n"
        )
    };
    let measured = load(&f, &scene_toml(OBJ_OBJECT, &lamp(""))).unwrap();
    let shown = measured.lights.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n");
    // The file tabulates 1000 cd · cos γ: π · 1000 lm (to the 2.5° table's 1e-3), a 120° beam.
    let flux = |shown: &str| -> f64 {
        let after = shown.split("photometric file: ").nth(1).expect("the file's figures");
        after.split(" lm").next().unwrap().parse().unwrap()
    };
    assert!((flux(&shown) / (1000.0 * std::f64::consts::PI) - 1.0).abs() < 1e-3, "{shown}");
    assert!(shown.contains("lm, peak 1000 cd, beam 120.0°"), "{shown}");
    assert!(measured.notes.iter().all(|n| !n.contains("overrides")), "{:?}", measured.notes);
    let doubled = load(&f, &scene_toml(OBJ_OBJECT, &lamp("intensity_cd = 2000.0\n"))).unwrap();
    let shown = doubled.lights.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n");
    assert!((flux(&shown) / (2000.0 * std::f64::consts::PI) - 1.0).abs() < 1e-3, "{shown}");
    assert!(shown.contains("lm, peak 2000 cd"), "{shown}");
    assert!(
        doubled
            .notes
            .iter()
            .any(|n| n.contains("overrides the photometric file's peak of 1000.0 cd (× 2.000)")),
        "{:?}",
        doubled.notes
    );
    let bare =
        "[[lights]]\nkind = \"point\"\nposition = [0.0, -2.0, 2.0]\nspectrum = \"sunlight\"\n";
    let err = refused(&f, &scene_toml(OBJ_OBJECT, bare));
    assert!(
        err.contains("intensity_cd")
            && err.contains("needs its intensity_cd (candela) or its flux_lm"),
        "{err}"
    );
}

/// A glTF's perspective camera is a viewpoint the scene's camera can use by name: glTF looks
/// along −Z with +Y up; turned Z-up, a camera 10 m along +Z at 1.7 m looks north from the south.
#[test]
fn a_gltf_camera_is_a_viewpoint_by_name() {
    let f = Folder::new();
    f.write("meshes/model.bin", triangle_bin());
    f.write(
        "meshes/model.gltf",
        r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1]}],
        "nodes":[{"mesh":0},{"camera":0,"name":"Entrance","translation":[0,1.7,10]}],
        "cameras":[{"type":"perspective","perspective":{"yfov":0.7,"znear":0.1}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
                     {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],
        "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
        "buffers":[{"byteLength":42,"uri":"model.bin"}]}"#,
    );
    let objects =
        "[[objects]]\nname = \"model\"\nmesh = \"meshes/model.gltf\"\nmaterial = \"stone\"\n";
    let toml = scene_toml(objects, "").replacen(
        "[camera]\n",
        "[camera]\nviewpoint = { object = \"model\", name = \"Entrance\" }\n",
        1,
    );
    let loaded = load(&f, &toml).unwrap();
    let c = &loaded.camera.pose;
    let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
    assert!(close(c.position, [0.0, -10.0, 1.7]), "{:?}", c.position);
    assert!(close(c.target, [0.0, -9.0, 1.7]), "looks north: {:?}", c.target);
    assert!((c.vertical_fov_deg - 0.7f64.to_degrees()).abs() < 1e-4, "{}", c.vertical_fov_deg);
    let wrong = toml.replace("name = \"Entrance\"", "name = \"Entrence\"");
    let err = refused(&f, &wrong);
    assert!(
        err.contains("camera.viewpoint.name") && err.contains("did you mean `Entrance`"),
        "{err}"
    );
}

/// The facade at dusk: a sun placed by site and time after sunset lights nothing and is noted
/// with its position, the sky still lights; alone, it leaves nothing to light the scene.
#[test]
fn a_sun_after_sunset_is_noted_and_lights_nothing() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    // Aosta, 21 December 2026, 17:00 CET: the sun set at about 16:45.
    let dusk = scene_toml(OBJ_OBJECT, "").replace(
        "illuminance_lux = 100000.0\nazimuth_deg = 180.0\nelevation_deg = 50.0",
        "illuminance_lux = 100000.0\nsite = { latitude_deg = 45.7371, longitude_deg = 7.3228, datetime = \"2026-12-21T17:00:00+01:00\" }",
    );
    assert!(dusk.contains("site = "));
    let message = refused(&f, &dusk);
    assert!(message.contains("no other light"), "{message}");
    let with_sky = format!(
        "{dusk}\n[[lights]]\nkind = \"sky\"\npreset = \"overcast\"\nspectrum = \"sunlight\"\n"
    );
    let scene = load(&f, &with_sky).unwrap();
    assert!(!scene.lights.iter().any(|l| matches!(l, ResolvedLight::Sun { .. })));
    assert!(scene.lights.iter().any(|l| matches!(l, ResolvedLight::Sky { .. })));
    let note = scene.notes.iter().find(|n| n.contains("below the horizon")).expect("a note");
    assert!(
        note.starts_with("lights[0]: at 2026-12-21T17:00:00+01:00")
            && note.contains("lights nothing"),
        "{note}"
    );
}

#[test]
fn files_outside_the_folder_and_the_scene_itself_are_refused() {
    let f = Folder::new();
    let outside = tempfile::tempdir().unwrap();
    std::fs::write(outside.path().join("wall.obj"), QUAD_OBJ).unwrap();
    let escape =
        OBJ_OBJECT.replace("meshes/wall.obj", &format!("{}/wall.obj", outside.path().display()));
    let err = refused(&f, &scene_toml(&escape, ""));
    assert!(
        err.contains("objects[0] (wall).mesh") && err.contains("leaves the scene's folder"),
        "{err}"
    );
    let dotdot = OBJ_OBJECT.replace("meshes/wall.obj", "../wall.obj");
    std::fs::write(f.dir.path().parent().unwrap().join("wall.obj"), QUAD_OBJ).ok();
    let err = refused(&f, &scene_toml(&dotdot, ""));
    assert!(err.contains("leaves the scene's folder") || err.contains("cannot be opened"), "{err}");
    let itself = OBJ_OBJECT.replace("meshes/wall.obj", "scene.toml");
    let err = refused(&f, &scene_toml(&itself, ""));
    assert!(err.contains("is the scene file itself"), "{err}");
    let missing = refused(&f, &scene_toml(OBJ_OBJECT, ""));
    assert!(missing.contains("`meshes/wall.obj` cannot be opened"), "{missing}");
}

#[test]
fn each_class_of_bad_scene_is_refused_with_place_and_fix() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let good = scene_toml(OBJ_OBJECT, "");
    let cases: Vec<(String, &str)> = vec![
        (good.replace("width = 64", "width = 64\nlens = 35"), "unknown field `lens`"),
        (good.replace("format = 1", "format = 9"), "format = 9, but this restauro reads format 1"),
        // A misspelt key in a spectrum's inline table, and two forms in one.
        (
            good.replace("{ illuminant = \"D65\" }", "{ illuminant = \"D65\", extrapolat = true }"),
            "with no other keys",
        ),
        (
            good.replace("{ illuminant = \"D65\" }", "{ illuminant = \"D65\", file = \"d.csv\" }"),
            "a spectrum is a shipped name",
        ),
        (good.replace("width = 64", "width = \"wide\""), "invalid type"),
        (
            good.replace("stone = \"stone\", joint", "stone = \"ston\", joint"),
            "unknown material `ston` (did you mean `stone`?)",
        ),
        (
            good.replace("joint = \"glaze\"", "joints = \"glaze\""),
            "unknown mesh part `joints` (did you mean `joint`?)",
        ),
        (
            good.replace("roughness = 0.2", "roughness = -0.2"),
            "materials.glaze.roughness: -0.2 is out of range",
        ),
        (
            good.replace("illuminance_lux = 100000.0", "illuminance_lux = -5.0"),
            "is not a finite illuminance ≥ 0 lux",
        ),
        (
            good.replace("elevation_deg = 50.0", "elevation_deg = -10.0"),
            "the sun is below the horizon",
        ),
        (good.replace("azimuth_deg = 180.0", "azimuth_deg = nan"), "lights[0].azimuth_deg"),
        (
            good.replace("reflectance = \"dirty\"", "reflectance = \"sunlight\""),
            "is used as a reflectance, which cannot exceed 1",
        ),
        (good.replace("weight = 0.3", "weight = 0.5"), "mixture weights must be ≥ 0 and sum to 1"),
        (
            good.replace("spectrum = \"soot\", weight = 0.3", "spectrum = \"dirty\", weight = 0.3"),
            "the mixture refers to itself",
        ),
        (
            good.replace("target = [0.0, 0.0, 1.0]", "target = [0.0, -10.0, 1.0]"),
            "the target is where the camera is",
        ),
        (good.replace("state = \"degraded\"", "state = \"restored\""), "unknown state `restored`"),
        (
            scene_toml(OBJ_OBJECT, "[[lights]]\nkind = \"sky\"\nspectrum = \"sunlight\"\n"),
            "lights[1]: give illuminance_lux, or preset = \"overcast\" or \"clear\"",
        ),
        (
            scene_toml(
                OBJ_OBJECT,
                "[[lights]]\nkind = \"sky\"\nilluminance_lux = -1.0\nspectrum = \"sunlight\"\n",
            ),
            "lights[1].illuminance_lux: -1 is not a finite illuminance ≥ 0 lux",
        ),
        (
            scene_toml(
                OBJ_OBJECT,
                "[[lights]]\nkind = \"sky\"\npreset = \"overcast\"\nspectrum = \"sunlight\"\n[[lights]]\nkind = \"sky\"\npreset = \"clear\"\nspectrum = \"sunlight\"\n",
            ),
            "more than one sky",
        ),
        (
            scene_toml(
                OBJ_OBJECT,
                "[[lights]]\nkind = \"sky\"\npreset = \"overcast\"\nmodel = \"perez\"\nspectrum = \"sunlight\"\n",
            ),
            "unknown variant `perez`",
        ),
        (
            scene_toml(OBJ_OBJECT, "[render]\nsamples_per_pixel = 0"),
            "render.samples_per_pixel is 0",
        ),
    ];
    for (toml, expect) in cases {
        let err = refused(&f, &toml);
        assert!(err.contains(expect), "expected «{expect}» in: {err}");
        assert!(err.contains("scene.toml"), "the message names the file: {err}");
    }
    // TOML syntax errors carry their line and column.
    let err = refused(&f, &good.replace("height = 48", "height = = 48"));
    assert!(err.contains("scene.toml:6:10:"), "{err}");
}

#[test]
fn bad_meshes_are_refused_through_the_scene() {
    let f = Folder::new();
    let toml = scene_toml(OBJ_OBJECT, "");
    for (obj, expect) in [
        (
            "v 0 0 0\nv 1 0 0\nv 0 0 1\nusemtl stone\nf 1 2 5\n",
            "line 5: vertex index 5 is out of range",
        ),
        ("v 0 0 0\nv 1 0 0\nusemtl stone\nf 1 2\n", "a face with 2 vertices"),
        ("v 0 0 0\nv 1 0 0\nv 2 0 0\nusemtl stone\nf 1 2 3\n", "has no triangles with an area"),
        ("v 0 0 nan\nv 1 0 0\nv 0 0 1\nusemtl stone\nf 1 2 3\n", "vertex 0 is"),
        ("# nothing\n", "has no triangles"),
    ] {
        f.write("meshes/wall.obj", obj);
        let err = refused(
            &f,
            &toml.replace(
                "materials = { stone = \"stone\", joint = \"glaze\" }",
                "material = \"stone\"",
            ),
        );
        assert!(err.contains(expect), "expected «{expect}» in: {err}");
    }
    f.write("meshes/wall.stl", "solid x");
    let err = refused(&f, &toml.replace("wall.obj", "wall.stl"));
    assert!(err.contains("`.stl` is not a mesh format restauro reads"), "{err}");
}

#[test]
fn limits_say_which_limit_and_how_to_raise_it() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let path = f.write("scene.toml", scene_toml(OBJ_OBJECT, ""));
    let limits = Limits { max_triangles: 2, ..Limits::default() };
    let err = load_folder(&path, &limits).unwrap_err().to_string();
    assert!(err.contains("the number of triangles is 3, over the limit of 2; simplify the meshes, or raise the limit with --max-triangles"), "{err}");
    let limits = Limits { max_pixels: 1000, ..Limits::default() };
    let err = load_folder(&path, &limits).unwrap_err().to_string();
    assert!(err.contains("the image size (pixels) is 3072, over the limit of 1000"), "{err}");
    let limits = Limits { max_file_bytes: 10, ..Limits::default() };
    let err = load_folder(&path, &limits).unwrap_err().to_string();
    assert!(err.contains("the file size (bytes)") && err.contains("--max-file-mb"), "{err}");
}

#[test]
fn bundles_are_stable_self_sufficient_and_name_files_by_content() {
    let a = Folder::new();
    a.write("meshes/wall.obj", QUAD_OBJ);
    let path_a = a.write("scene.toml", scene_toml(OBJ_OBJECT, ""));
    let bundle = bundle_folder(&path_a, &Limits::default()).unwrap();
    assert_eq!(bundle.files.len(), 1);
    let hash = blake3::hash(QUAD_OBJ.as_bytes()).to_hex().to_string();
    assert_eq!(bundle.scene.objects[0].mesh, format!("blake3:{hash}.obj"));
    // Bundling again gives the same identity.
    assert_eq!(bundle_folder(&path_a, &Limits::default()).unwrap().id(), bundle.id());
    // The same scene elsewhere, with other file names, comments and layout: the same identity.
    let b = Folder::new();
    b.write("geometry/muro.obj", QUAD_OBJ);
    let moved = scene_toml(&OBJ_OBJECT.replace("meshes/wall.obj", "geometry/muro.obj"), "")
        .replace("format = 1", "# copied\nformat   =   1");
    let path_b = b.write("other-name.toml", moved);
    assert_eq!(bundle_folder(&path_b, &Limits::default()).unwrap().id(), bundle.id());
    // A different mesh is a different scene.
    b.write("geometry/muro.obj", QUAD_OBJ.replace("v 1 0 2", "v 1 0 3"));
    assert_ne!(bundle_folder(&path_b, &Limits::default()).unwrap().id(), bundle.id());
    // The bundle alone is enough to load the scene, as a worker does.
    let from_bundle = bundle.load(&Limits::default()).unwrap();
    let from_folder = load_folder(&path_a, &Limits::default()).unwrap();
    assert_eq!(from_bundle.objects[0].mesh, from_folder.objects[0].mesh);
    // Rebuilt from its canonical form and files, checked; a corrupted file is caught.
    let rebuilt =
        restauro_scene::bundle::Bundle::from_parts(&bundle.canonical_json(), bundle.files.clone())
            .unwrap();
    assert_eq!(rebuilt.id(), bundle.id());
    let mut corrupt = bundle.files.clone();
    corrupt.get_mut(&hash).unwrap().push(b'\n');
    let err = restauro_scene::bundle::Bundle::from_parts(&bundle.canonical_json(), corrupt)
        .unwrap_err()
        .to_string();
    assert!(err.contains("the bundle is corrupt"), "{err}");
}

/// A house without a floor (walls and a flat roof, wound outwards), as OBJ text in Z-up world
/// coordinates mapped to the file's by `to_file`.
fn open_house_obj(to_file: impl Fn([f32; 3]) -> [f32; 3]) -> String {
    let (x, y, z) = (4.0f32, 3.0f32, 2.0f32);
    let quads = [
        [[0., 0., 0.], [x, 0., 0.], [x, 0., z], [0., 0., z]],
        [[x, y, 0.], [0., y, 0.], [0., y, z], [x, y, z]],
        [[0., y, 0.], [0., 0., 0.], [0., 0., z], [0., y, z]],
        [[x, 0., 0.], [x, y, 0.], [x, y, z], [x, 0., z]],
        [[0., 0., z], [x, 0., z], [x, y, z], [0., y, z]],
    ];
    let mut text = String::from("usemtl stone\n");
    for (q, quad) in quads.iter().enumerate() {
        for p in quad {
            let [a, b, c] = to_file(*p);
            text += &format!("v {a} {b} {c}\n");
        }
        let i = 4 * q + 1;
        text += &format!("f {} {} {} {}\n", i, i + 1, i + 2, i + 3);
    }
    text
}

const HOUSE_OBJECT: &str = r#"[[objects]]
name = "house"
mesh = "meshes/house.obj"
material = "stone"
"#;

#[test]
fn a_y_up_obj_is_noticed_and_up_axis_stands_it_up() {
    let folder = Folder::new();
    // As a Y-up exporter writes it: world +Z is the file's +Y, world +Y the file's −Z.
    folder.write("meshes/house.obj", open_house_obj(|[x, y, z]| [x, z, -y]));
    let scene = load(&folder, &scene_toml(HOUSE_OBJECT, "")).unwrap();
    let hint: Vec<_> = scene.notes.iter().filter(|n| n.contains("lies on its back")).collect();
    assert_eq!(hint.len(), 1, "{:?}", scene.notes);
    assert!(hint[0].contains("objects[0]") && hint[0].contains("up_axis = \"y\""), "{hint:?}");
    // Read as Z-up it lies 3 m "tall" (its depth); with the suggested fix it stands 2 m tall.
    let height = |s: &LoadedScene| {
        let b = s.objects[0].mesh.bounds().unwrap();
        b.max[2] - b.min[2]
    };
    assert!((height(&scene) - 3.0).abs() < 1e-5);
    let fixed = HOUSE_OBJECT.replace("material =", "up_axis = \"y\"\nmaterial =");
    let scene = load(&folder, &scene_toml(&fixed, "")).unwrap();
    assert!(scene.notes.iter().all(|n| !n.contains("lies on its back")), "{:?}", scene.notes);
    assert!((height(&scene) - 2.0).abs() < 1e-5);
    // The same house written Z-up gives no note.
    folder.write("meshes/house.obj", open_house_obj(|p| p));
    let scene = load(&folder, &scene_toml(HOUSE_OBJECT, "")).unwrap();
    assert!(scene.notes.iter().all(|n| !n.contains("lies on its back")), "{:?}", scene.notes);
}

#[test]
fn a_y_up_ply_is_noticed_too() {
    let folder = Folder::new();
    let obj = open_house_obj(|[x, y, z]| [x, z, -y]);
    let vertices: Vec<&str> = obj.lines().filter_map(|l| l.strip_prefix("v ")).collect();
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face 5\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len()
    );
    for v in &vertices {
        ply += &format!("{v}\n");
    }
    for q in 0..5 {
        ply += &format!("4 {} {} {} {}\n", 4 * q, 4 * q + 1, 4 * q + 2, 4 * q + 3);
    }
    folder.write("meshes/house.ply", ply);
    let object = HOUSE_OBJECT.replace("house.obj", "house.ply");
    let scene = load(&folder, &scene_toml(&object, "")).unwrap();
    assert!(
        scene.notes.iter().any(|n| n.contains("`meshes/house.ply` probably lies on its back")),
        "{:?}",
        scene.notes
    );
}

/// Notes pinned to the model are checked as the rest of the file: a part that exists, links
/// that are web addresses, one note per title, a pose the camera can take.
#[test]
fn annotations_are_checked_as_the_rest_of_the_scene() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let note = |fields: &str| {
        scene_toml(
            OBJ_OBJECT,
            &format!("[[annotations]]\ntitle = \"crack\"\nposition = [0.0, 0.0, 1.0]\n{fields}\n"),
        )
    };
    let good = note(
        "part = \"wall/stone\"\nlinks = [\"https://example.org/a.pdf\"]\npose = { position = [0.0, -5.0, 1.6], target = [0.0, 0.0, 1.0] }",
    );
    let scene = load(&f, &good).unwrap();
    assert_eq!(scene.file.annotations[0].links, ["https://example.org/a.pdf"]);
    for (fields, words) in [
        ("part = \"wal\"", "annotations[0].part: unknown object `wal`"),
        ("part = \"wall/stones\"", "unknown mesh part `stones`"),
        (
            "links = [\"javascript:alert(1)\"]",
            "annotations[0].links[0]: `javascript:alert(1)` is not a web address",
        ),
        ("links = [\"file:///etc/passwd\"]", "is not a web address"),
        (
            "pose = { position = [0.0, 0.0, 1.0], target = [0.0, 0.0, 1.0] }",
            "annotations[0].pose: the target is where the camera is",
        ),
    ] {
        let message = refused(&f, &note(fields));
        assert!(message.contains(words), "{fields}: {message}");
    }
    let twice = format!("{good}\n[[annotations]]\ntitle = \"crack\"\nposition = [1.0, 0.0, 1.0]\n");
    assert!(refused(&f, &twice).contains("a second note titled `crack`"));
}

/// A note's images are files beside the scene, bundled with it, each the PNG or JPEG its name
/// says: a script or a mesh renamed `.png` is refused, naming the file.
#[test]
fn a_notes_images_are_bundled_and_must_be_what_their_names_say() {
    const PNG_START: &[u8] = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01\0\0\0\x01\x08\x02\0\0\0";
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    f.write("photos/crack.png", PNG_START);
    f.write("photos/crack.jpg", b"\xff\xd8\xff\xe0\0\x10JFIF\0");
    f.write("photos/fake.png", b"<svg onload=alert(1)>");
    f.write("photos/chart.gif", b"GIF89a");
    let note = |images: &str| {
        scene_toml(
            OBJ_OBJECT,
            &format!(
                "[[annotations]]\ntitle = \"crack\"\nposition = [0.0, 0.0, 1.0]\nimages = {images}\n"
            ),
        )
    };
    let good = note("[\"photos/crack.png\", \"photos/crack.jpg\"]");
    let path = f.write("scene.toml", &good);
    let bundle = bundle_folder(&path, &Limits::default()).unwrap();
    let hash = blake3::hash(PNG_START).to_hex().to_string();
    assert_eq!(bundle.scene.annotations[0].images[0], format!("blake3:{hash}.png"));
    assert_eq!(bundle.files[&hash], PNG_START);
    assert_eq!(bundle.files.len(), 3, "the mesh and two images");
    bundle.load(&Limits::default()).unwrap();
    for (images, words) in [
        ("[\"photos/fake.png\"]", "photos/fake.png: annotations[0].images[0]: not a PNG file"),
        (
            "[\"photos/crack.png\", \"photos/chart.gif\"]",
            "annotations[0].images[1]: `photos/chart.gif`: a note's image is a .png, .jpg or .jpeg file",
        ),
        ("[\"meshes/wall.obj\"]", "a note's image is a .png"),
        ("[\"photos/missing.png\"]", "photos/missing.png"),
    ] {
        let message = refused(&f, &note(images));
        assert!(message.contains(words), "{images}: {message}");
    }
    let many: Vec<String> = (0..33).map(|_| "\"photos/crack.png\"".to_owned()).collect();
    let message = refused(&f, &note(&format!("[{}]", many.join(", "))));
    assert!(message.contains("33 images; a note holds at most 32"), "{message}");
}

/// A reflectance given as a number is flat at every wavelength; 0 (a black surface) is allowed,
/// a negative value or one above 1 for a reflectance is refused; `max_depth = 0` (no cap) is
/// taken, a depth over the limit is not.
#[test]
fn constant_spectra_and_an_uncapped_depth() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let with = |spectrum: &str, render: &str| {
        scene_toml(OBJ_OBJECT, render).replace(
            "travertine = \"travertine_tufa_solid__eco_ward73\"",
            &format!("travertine = {spectrum}"),
        )
    };
    let scene = load(&f, &with("{ constant = 0.0 }", "[render]\nmax_depth = 0")).unwrap();
    assert!(scene.spectra["travertine"].0.iter().all(|&v| v == 0.0));
    assert_eq!(scene.file.render.max_depth, 0);
    let scene = load(&f, &with("{ constant = 0.95 }", "")).unwrap();
    assert!(scene.spectra["travertine"].0.iter().all(|&v| v == 0.95));
    for (spectrum, render, words) in [
        ("{ constant = -0.1 }", "", "spectra.travertine: constant = -0.1: give a value from 0"),
        ("{ constant = 1.5 }", "", "reaches 1.5 but is used as a reflectance"),
        ("{ constant = nan }", "", "constant = NaN"),
        ("{ constant = 0.5 }", "[render]\nmax_depth = 65", "render.max_depth"),
    ] {
        let message = refused(&f, &with(spectrum, render));
        assert!(message.contains(words), "{spectrum} {render}: {message}");
    }
}

/// A luminaire given by its flux: an isotropic point of Φ lm has Φ/4π cd; a spot of one
/// candela inside a 30° cone with no falloff emits 2π(1 − cos 30°) lm, and with a falloff its
/// smoothstep band adds half its solid angle; a photometric file is scaled so that its flux is
/// the one given. Both intensity and flux at once are refused.
#[test]
fn luminaires_given_by_their_flux() {
    use restauro_scene::load::ResolvedLight;
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let ies =
        concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/photometric/lambertian_cos_1000cd.ies");
    f.write("lamps/cos.ies", std::fs::read(ies).unwrap());
    let intensity = |light: &str| -> f64 {
        let scene = load(
            &f,
            &scene_toml(OBJ_OBJECT, &format!("[[lights]]\n{light}spectrum = \"sunlight\"\n")),
        )
        .unwrap();
        match scene.lights.last().unwrap() {
            ResolvedLight::Point { intensity_cd, .. }
            | ResolvedLight::Spot { intensity_cd, .. } => *intensity_cd,
            other => panic!("{other}"),
        }
    };
    let pi = std::f64::consts::PI;
    let point = intensity("kind = \"point\"\nposition = [0.0, -2.0, 2.0]\nflux_lm = 1000.0\n");
    assert!((point - 1000.0 / (4.0 * pi)).abs() < 1e-9, "{point}");
    let spot = "kind = \"spot\"\nposition = [0.0, -2.0, 2.0]\naim = [0.0, 0.0, 0.0]\nflux_lm = 1000.0\ncone_deg = 30.0\n";
    let sharp = intensity(spot);
    let cos30 = 30f64.to_radians().cos();
    assert!((sharp - 1000.0 / (2.0 * pi * (1.0 - cos30))).abs() < 0.05, "{sharp}");
    let soft = intensity(&format!("{spot}falloff_deg = 10.0\n"));
    let cos40 = 40f64.to_radians().cos();
    let want = 1000.0 / (2.0 * pi * ((1.0 - cos30) + 0.5 * (cos30 - cos40)));
    assert!((soft - want).abs() < 1e-9, "{soft} vs {want}");
    // A cosine luminaire of 1000 cd at its peak emits π · 1000 lm: given 500 lm, its peak is
    // 500/π cd.
    let filed = intensity(
        "kind = \"point\"\nposition = [0.0, -2.0, 2.0]\nies = \"lamps/cos.ies\"\nflux_lm = 500.0\n",
    );
    assert!((filed - 500.0 / pi).abs() < 0.01 * 500.0 / pi, "{filed}");
    let both = refused(
        &f,
        &scene_toml(
            OBJ_OBJECT,
            "[[lights]]\nkind = \"point\"\nposition = [0.0, -2.0, 2.0]\nflux_lm = 10.0\nintensity_cd = 1.0\nspectrum = \"sunlight\"\n",
        ),
    );
    assert!(both.contains("give intensity_cd or flux_lm, not both"), "{both}");
    let negative = refused(
        &f,
        &scene_toml(
            OBJ_OBJECT,
            "[[lights]]\nkind = \"point\"\nposition = [0.0, -2.0, 2.0]\nflux_lm = -10.0\nspectrum = \"sunlight\"\n",
        ),
    );
    assert!(negative.contains("lights[1].flux_lm: -10 is not a luminous flux"), "{negative}");
}

/// A CIE general sky takes the scene's sun, or its own, never both; its type and ground are
/// checked; the ground's luminance is ρ E_h / π with the sun's horizontal share in E_h.
#[test]
fn a_general_sky_finds_its_sun_and_its_ground() {
    let f = Folder::new();
    f.write("meshes/wall.obj", QUAD_OBJ);
    let sky = |keys: &str| {
        format!(
            "[[lights]]\nkind = \"sky\"\nilluminance_lux = 20000.0\nspectrum = \"sunlight\"\n{keys}\n"
        )
    };
    let with_sun = |keys: &str| scene_toml(OBJ_OBJECT, &sky(keys));
    let scene =
        load(&f, &with_sun("model = \"cie-general\"\ncie_type = 12\nground_reflectance = 0.2"))
            .unwrap();
    let Some(ResolvedLight::Sky { general: Some(g), ground_cd_m2, .. }) =
        scene.lights.iter().find(|l| matches!(l, ResolvedLight::Sky { .. }))
    else {
        panic!("no general sky")
    };
    assert_eq!(g.sky_type, 12);
    assert!((g.sun[2] - 50f64.to_radians().sin()).abs() < 1e-12, "the scene's sun, 50° high");
    let e_h = 20_000.0 + 100_000.0 * 50f64.to_radians().sin();
    assert!((ground_cd_m2 - 0.2 * e_h / std::f64::consts::PI).abs() < 1e-9);
    let cases = [
        (with_sun("model = \"cie-general\""), "lights[1].cie_type"),
        (with_sun("model = \"cie-general\"\ncie_type = 16"), "16 is not a sky type"),
        (with_sun("cie_type = 3"), "cie_type is for model = \"cie-general\""),
        (
            with_sun(
                "model = \"cie-general\"\ncie_type = 3\nsun_elevation_deg = 30.0\nsun_azimuth_deg = 90.0",
            ),
            "the scene has a sun light",
        ),
        (with_sun("ground_reflectance = 1.5"), "not a reflectance"),
        (with_sun("sun_elevation_deg = 30.0"), "only a CIE general sky"),
    ];
    for (toml, expected) in cases {
        let e = refused(&f, &toml);
        assert!(e.contains(expected), "{expected}: {e}");
    }
    // Without a sun light, the sky's own sun: by angles, or missing.
    let no_sun = |keys: &str| {
        let toml = with_sun(keys);
        let start = toml.find("[[lights]]\nkind = \"sun\"").unwrap();
        let end = start + toml[start..].find("spectrum = \"sunlight\"\n").unwrap() + 22;
        format!("{}{}", &toml[..start], &toml[end..])
    };
    let own = load(&f, &no_sun("model = \"cie-general\"\ncie_type = 7\nsun_elevation_deg = 30.0\nsun_azimuth_deg = 90.0"))
        .unwrap();
    let Some(ResolvedLight::Sky { general: Some(g), .. }) = own.lights.first() else { panic!() };
    assert!((g.sun[0] - 30f64.to_radians().cos()).abs() < 1e-12, "east, 30° high");
    let e = refused(&f, &no_sun("model = \"cie-general\"\ncie_type = 7"));
    assert!(e.contains("a CIE general sky is shaped by the sun"), "{e}");
    // A sky without a spectrum is CIE D65 (ISO 15469's daylight), the tabulated illuminant.
    let toml = with_sun("").replace(
        "[[lights]]\nkind = \"sky\"\nilluminance_lux = 20000.0\nspectrum = \"sunlight\"\n",
        "[[lights]]\nkind = \"sky\"\nilluminance_lux = 20000.0\n",
    );
    let scene = load(&f, &toml).unwrap();
    let Some(ResolvedLight::Sky { spectrum, .. }) =
        scene.lights.iter().find(|l| matches!(l, ResolvedLight::Sky { .. }))
    else {
        panic!("no sky")
    };
    assert_eq!(spectrum, restauro_scene::load::DEFAULT_SKY_SPECTRUM);
    let d65 = restauro_spectral::Illuminant::D65.spd().unwrap();
    assert_eq!(scene.spectra[spectrum], d65, "{spectrum}");
}
