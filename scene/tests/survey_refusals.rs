//! Every refusal the survey-data features add (origins, photos, degradation maps, soiling,
//! levels of detail, a glTF's own photo) shows its place and its fix. Each case breaks one
//! thing of a scene that loads, and checks the words a restorer reads.

use base64::Engine as _;
use restauro_scene::load::{Limits, load_folder};

const QUAD: &str =
    "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";

const SCENE: &str = r#"format = 1
origin = [0.0, 0.0, 0.0]
[camera]
position = [0.5, -5.0, 0.5]
target = [0.5, 0.0, 0.5]
width = 8
height = 8
[spectra]
day = { illuminant = "D65" }
stone = { constant = 0.5 }
soot = { constant = 0.05 }
[materials.stone]
model = "lambert"
reflectance = "stone"
texture = "photo.png"
degraded = { map = "survey", classes = ["crust"], soiling = { spectrum = "soot", max_fraction = 0.5 } }
[materials.window]
model = "glass"
[[maps]]
name = "survey"
image = "map.png"
corner = [0.0, 0.0, 0.0]
u = [1.0, 0.0, 0.0]
v = [0.0, 0.0, 1.0]
classes = [{ name = "crust", colour = [0, 0, 0], spectrum = "soot" }, { name = "moss", colour = [0, 128, 0], spectrum = "stone" }]
[[objects]]
name = "wall"
mesh = "quad.obj"
material = "stone"
[[lights]]
kind = "sun"
illuminance_lux = 1000.0
azimuth_deg = 180.0
elevation_deg = 45.0
spectrum = "day"
"#;

fn png() -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, 1, 1);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.write_header().unwrap().write_image_data(&[0, 0, 0]).unwrap();
    }
    out
}

/// The scene with `from` replaced by `to`, loaded: its refusal.
fn refusal(dir: &std::path::Path, from: &str, to: &str) -> String {
    assert!(SCENE.contains(from), "the scene has no `{from}`");
    std::fs::write(dir.join("scene.toml"), SCENE.replace(from, to)).unwrap();
    match load_folder(&dir.join("scene.toml"), &Limits::default()) {
        Ok(_) => panic!("accepted with `{to}`"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn each_refusal_names_its_place_and_its_fix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("quad.obj"), QUAD).unwrap();
    std::fs::write(d.join("photo.png"), png()).unwrap();
    std::fs::write(d.join("map.png"), png()).unwrap();
    std::fs::write(d.join("scene.toml"), SCENE).unwrap();
    load_folder(&d.join("scene.toml"), &Limits::default()).expect("the scene itself loads");
    let classes = "classes = [{ name = \"crust\", colour = [0, 0, 0], spectrum = \"soot\" }, { name = \"moss\", colour = [0, 128, 0], spectrum = \"stone\" }]";
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        ("origin = [0.0, 0.0, 0.0]", "origin = [1e12, 0.0, 0.0]".into(), vec!["origin", "out of range", "±1e9 m"]),
        ("[materials.window]\nmodel = \"glass\"", "[materials.window]\nmodel = \"glass\"\ntexture = \"photo.png\"".into(), vec!["materials.window.texture", "glass takes no texture"]),
        ("[[objects]]", "[[maps]]\nname = \"survey\"\nimage = \"map.png\"\ncorner = [0.0, 0.0, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 0.0, 1.0]\nclasses = [{ name = \"a\", colour = [1, 2, 3], spectrum = \"soot\" }]\n[[objects]]".into(), vec!["maps[1] (survey)", "names must be unique"]),
        ("v = [0.0, 0.0, 1.0]", "v = [2.0, 0.0, 0.0]".into(), vec!["maps[0] (survey)", "not zero, not parallel"]),
        (classes, "classes = []".into(), vec!["maps[0] (survey).classes", "1 to 32 classes"]),
        ("colour = [0, 128, 0]", "colour = [0, 0, 0]".into(), vec!["maps[0] (survey).classes[1] (moss)", "each needs its own"]),
        ("spectrum = \"stone\" }]", "spectrum = \"day\" }]".into(), vec!["maps[0] (survey).classes[1] (moss).spectrum"]),
        ("degraded = { map = \"survey\", ", "degraded = { ".into(), vec!["materials.stone.degraded", "`classes` needs the `map`"]),
        ("map = \"survey\", classes", "map = \"surve\", classes".into(), vec!["materials.stone.degraded.map", "unknown map `surve`", "survey"]),
        ("max_fraction = 0.5", "max_fraction = 1.5".into(), vec!["materials.stone.degraded.soiling.max_fraction", "use 0 to 1"]),
        ("max_fraction = 0.5", "max_fraction = 0.5, rain_angle_deg = 85.0".into(), vec!["soiling.rain_angle_deg", "use 0 to 80"]),
        ("spectrum = \"soot\", max_fraction", "spectrum = \"sooty\", max_fraction".into(), vec!["materials.stone.degraded.soiling.spectrum", "sooty"]),
    ];
    for (from, to, words) in cases {
        let message = refusal(d, from, &to);
        for w in words {
            assert!(message.contains(w), "with `{to}`: `{w}` not in: {message}");
        }
    }
}

#[test]
fn a_lod_with_descending_ranges_is_refused_with_the_rule() {
    let dir = tempfile::tempdir().unwrap();
    let wrl = "#VRML V2.0 utf8\nLOD { range [ 20 10 ] level [ Shape { geometry Box { } } Shape { geometry Box { } } ] }\n";
    std::fs::write(dir.path().join("quad.wrl"), wrl).unwrap();
    std::fs::write(dir.path().join("photo.png"), png()).unwrap();
    std::fs::write(dir.path().join("map.png"), png()).unwrap();
    let scene = SCENE
        .replace("mesh = \"quad.obj\"", "mesh = \"quad.wrl\"")
        .replace("texture = \"photo.png\"\n", "");
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    let e =
        load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap_err().to_string();
    assert!(
        e.contains("quad.wrl") && e.contains("`range`") && e.contains("ascending order"),
        "{e}"
    );
}

#[test]
fn a_gltf_photo_that_is_not_an_image_or_outside_its_buffer_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0];
    let uv: [f32; 6] = [0.0, 1.0, 1.0, 1.0, 0.0, 0.0];
    let buffer: Vec<u8> = positions.iter().chain(&uv).flat_map(|v| v.to_le_bytes()).collect();
    let data = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let gltf = |image: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
            "materials":[{{"name":"stone","pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
            "textures":[{{"source":0}}],"images":[{image}],
            "buffers":[{{"byteLength":60,"uri":"data:application/octet-stream;base64,{data}"}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}},{{"buffer":0,"byteOffset":40,"byteLength":100}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,-1],"max":[1,0,0]}},
                         {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#
        )
    };
    std::fs::write(dir.path().join("map.png"), png()).unwrap();
    std::fs::write(dir.path().join("photo.png"), png()).unwrap();
    let scene = SCENE.replace("mesh = \"quad.obj\"", "mesh = \"scan.gltf\"");
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    for (image, words) in [
        (
            r#"{"uri":"data:image/gif;base64,R0lGODlh"}"#,
            vec!["scan.gltf", "image 0", "not a PNG or JPEG image"],
        ),
        (
            r#"{"bufferView":2,"mimeType":"image/png"}"#,
            vec!["scan.gltf", "image 0", "outside its buffer"],
        ),
    ] {
        std::fs::write(dir.path().join("scan.gltf"), gltf(image)).unwrap();
        let e = load_folder(&dir.path().join("scene.toml"), &Limits::default())
            .unwrap_err()
            .to_string();
        for w in words {
            assert!(e.contains(w), "`{w}` not in: {e}");
        }
    }
}
