//! Photo textures through a scene: texture coordinates read from OBJ (`vt`, v turned to count
//! from the top as glTF's do) and glTF (TEXCOORD_0), PNG and JPEG decoded, bad images and
//! untextured parts refused with the file and the fix, textures carried in bundles.

use restauro_scene::bundle::bundle_folder;
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::texture::Texture;
use restauro_scene::{Result, SceneError};
use std::path::Path;

const QUAD: &str =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";

/// A 2 × 2 RGB PNG: red, green / blue, white (8 bits).
fn png_bytes() -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, 2, 2);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut w = encoder.write_header().unwrap();
        w.write_image_data(&[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255]).unwrap();
    }
    out
}

fn load_with(dir: &Path, mesh: (&str, &[u8]), texture: (&str, &[u8])) -> Result<LoadedScene> {
    std::fs::write(dir.join(mesh.0), mesh.1).unwrap();
    std::fs::write(dir.join(texture.0), texture.1).unwrap();
    let toml = format!(
        "format = 1\n[camera]\nposition = [0.5, 0.5, 3.0]\ntarget = [0.5, 0.5, 0.0]\nup = [0, 1, 0]\nwidth = 8\nheight = 8\n\
         [spectra]\nday = {{ illuminant = \"D65\" }}\ngrey = {{ constant = 0.5 }}\n\
         [materials.stone]\nmodel = \"lambert\"\nreflectance = \"grey\"\ntexture = \"{}\"\n\
         [[objects]]\nname = \"quad\"\nmesh = \"{}\"\nmaterial = \"stone\"\nup_axis = \"z\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 0.0\nelevation_deg = 60.0\nspectrum = \"day\"\n",
        texture.0, mesh.0
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default())
}

#[test]
fn obj_texture_coordinates_count_from_the_top_and_the_png_is_decoded() {
    let dir = tempfile::tempdir().unwrap();
    let scene =
        load_with(dir.path(), ("quad.obj", QUAD.as_bytes()), ("photo.png", &png_bytes())).unwrap();
    let mesh = &scene.objects[0].mesh;
    let uv = mesh.texcoords.as_ref().expect("texture coordinates");
    // Each vertex's (u, 1 − v), whatever order single-indexing put the vertices in.
    for (p, t) in mesh.positions.iter().zip(uv) {
        assert_eq!([t[0], 1.0 - t[1]], [p[0], p[1]], "vertex {p:?}");
    }
    let texture = &scene.textures["photo.png"];
    assert_eq!((texture.width, texture.height), (2, 2));
    assert_eq!(texture.texels[0], [65535, 0, 0], "red, top left");
    assert_eq!(texture.texels[3], [65535; 3], "white, bottom right");
    // sRGB decoding: full red is 1, mid-grey 128 is 0.2158605 (IEC 61966-2-1).
    assert_eq!(texture.linear_rgb(0, 0), [1.0, 0.0, 0.0]);
    let grey = Texture { width: 1, height: 1, texels: vec![[128 * 257; 3]] };
    assert!((grey.linear_rgb(0, 0)[0] - 0.215_860_5).abs() < 1e-6);
}

#[test]
fn gltf_texture_coordinates_are_read() {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let uv: [f32; 6] = [0.0, 1.0, 1.0, 1.0, 0.0, 0.0];
    let mut buffer: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    buffer.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    use base64::Engine as _;
    let data = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}}}}]}}],
        "buffers":[{{"byteLength":60,"uri":"data:application/octet-stream;base64,{data}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#
    );
    let dir = tempfile::tempdir().unwrap();
    let scene =
        load_with(dir.path(), ("tri.gltf", gltf.as_bytes()), ("photo.png", &png_bytes())).unwrap();
    let uv_read = scene.objects[0].mesh.texcoords.clone().expect("TEXCOORD_0");
    assert_eq!(uv_read, vec![[0.0, 1.0], [1.0, 1.0], [0.0, 0.0]]);
}

fn refusal(result: Result<LoadedScene>) -> String {
    match result {
        Err(e @ SceneError::Invalid { .. }) => e.to_string(),
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn bad_photos_and_parts_without_coordinates_are_refused_with_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let flat = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    let m = refusal(load_with(d, ("flat.obj", flat.as_bytes()), ("photo.png", &png_bytes())));
    assert!(m.contains("has no texture coordinates") && m.contains("`stone`"), "{m}");
    let m = refusal(load_with(
        d,
        ("quad.obj", QUAD.as_bytes()),
        ("photo.png", b"\x89PNG\r\n\x1a\nnot really"),
    ));
    assert!(m.contains("photo.png") && m.contains("not a PNG image"), "{m}");
    let m = refusal(load_with(
        d,
        ("quad.obj", QUAD.as_bytes()),
        ("photo.jpg", b"\xff\xd8\xff\xe0 broken"),
    ));
    assert!(m.contains("photo.jpg") && m.contains("JPEG"), "{m}");
    let m = refusal(load_with(d, ("quad.obj", QUAD.as_bytes()), ("photo.tif", b"II*\0")));
    assert!(m.contains("`.tif` is not an image restauro reads"), "{m}");
    // Beyond the pixel limit, before the texels are allocated.
    load_with(d, ("quad.obj", QUAD.as_bytes()), ("photo.png", &png_bytes())).unwrap();
    let small = Limits { max_pixels: 3, ..Limits::default() };
    let e = load_folder(&d.join("scene.toml"), &small).unwrap_err().to_string();
    assert!(
        e.contains("2 × 2 texels is more than the 3 allowed") && e.contains("--max-pixels"),
        "{e}"
    );
}

#[test]
fn a_bundle_carries_the_photo() {
    let dir = tempfile::tempdir().unwrap();
    load_with(dir.path(), ("quad.obj", QUAD.as_bytes()), ("photo.png", &png_bytes())).unwrap();
    let bundle = bundle_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    let reference = bundle.scene.materials["stone"].texture.clone().unwrap();
    let hash = blake3::hash(&png_bytes()).to_hex().to_string();
    assert_eq!(reference, format!("blake3:{hash}.png"));
    let loaded = bundle.load(&Limits::default()).unwrap();
    assert_eq!(loaded.textures[&reference].width, 2);
}

/// A JPEG (4:2:0, written by Pillow) decodes to what libjpeg-turbo reads from it, within the
/// few levels by which correct decoders may differ (their IDCT and chroma upsampling are
/// implementation choices in ITU-T T.81), and less than one level on average. `data/texture/make.py` made both files.
#[test]
fn a_jpeg_decodes_as_an_independent_decoder_reads_it() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/texture");
    let bytes = std::fs::read(data.join("gradient.jpg")).unwrap();
    let texture =
        restauro_scene::texture::decode(&bytes, "jpg", &data.join("gradient.jpg"), 1 << 20)
            .unwrap();
    assert_eq!((texture.width, texture.height), (16, 8));
    let reference = std::fs::read_to_string(data.join("gradient.txt")).unwrap();
    let (mut worst, mut sum, mut n) = (0i32, 0i32, 0);
    for (y, row) in reference.lines().enumerate() {
        for (x, texel) in row.split(' ').enumerate() {
            let want: Vec<i32> = texel.split(',').map(|c| c.parse().unwrap()).collect();
            let got = texture.texels[y * 16 + x];
            for k in 0..3 {
                let d = (i32::from(got[k] / 257) - want[k]).abs();
                (worst, sum, n) = (worst.max(d), sum + d, n + 1);
            }
        }
    }
    let mean = f64::from(sum) / f64::from(n);
    assert!(
        worst <= 4 && mean < 1.0,
        "channels differ from libjpeg-turbo's by up to {worst} levels, {mean} on average"
    );
}

/// A `.gltf` whose photo is a file beside it: read at load, and embedded when bundled, so the
/// bundle alone (as a worker has it) still shows the part's photo.
#[test]
fn a_gltf_photo_beside_the_model_travels_in_the_bundle() {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0];
    let uv: [f32; 6] = [0.0, 1.0, 1.0, 1.0, 0.0, 0.0];
    let mut buffer: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    buffer.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri.bin"), &buffer).unwrap();
    std::fs::write(dir.path().join("albedo.png"), png_bytes()).unwrap();
    let gltf = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"material":0}]}],
        "materials":[{"name":"stone","pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
        "textures":[{"source":0}],"images":[{"uri":"albedo.png"}],
        "buffers":[{"byteLength":60,"uri":"tri.bin"}],
        "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,-1],"max":[1,0,0]},
                     {"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}]}"#;
    // The part's photo is read with the model (the scene's material, with a photo of its own,
    // takes precedence when it renders).
    let scene =
        load_with(dir.path(), ("tri.gltf", gltf.as_bytes()), ("photo.png", &png_bytes())).unwrap();
    let photo = scene.objects[0].mesh.groups[0].photo.as_ref().expect("the model's photo");
    assert_eq!(photo.texels[0], [65535, 0, 0]);
    let bundle = bundle_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    let loaded = bundle.load(&Limits::default()).unwrap();
    assert_eq!(loaded.objects[0].mesh.groups[0].photo.as_deref(), Some(&**photo));
}

/// The scene of [`load_with`] with `keys` added to its material.
fn load_with_keys(dir: &Path, keys: &str) -> Result<LoadedScene> {
    load_with(dir, ("quad.obj", QUAD.as_bytes()), ("photo.png", &png_bytes())).unwrap();
    let toml = std::fs::read_to_string(dir.join("scene.toml")).unwrap();
    let toml =
        toml.replace("texture = \"photo.png\"\n", &format!("texture = \"photo.png\"\n{keys}\n"));
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default())
}

/// A grey patch white-balances a photo: balanced on a patch of one colour, that patch comes out
/// neutral with its luminance kept (BT.709), and every other texel is scaled by the same gains.
#[test]
fn a_photo_balanced_on_a_patch_makes_the_patch_grey() {
    use restauro_scene::scene_file::PixelRect;
    // A warm card in the top row, two other colours below (8-bit codes × 257).
    let texels = vec![[200, 160, 120], [200, 160, 120], [90, 140, 60], [250, 250, 250]]
        .into_iter()
        .map(|c: [u16; 3]| c.map(|v| v * 257))
        .collect();
    let photo = Texture { width: 2, height: 2, texels };
    let card = PixelRect { x: 0, y: 0, width: 2, height: 1 };
    photo.check_patch(card).unwrap();
    let balanced = photo.white_balanced(card);
    let before = photo.linear_rgb(0, 0).map(f64::from);
    let after = balanced.linear_rgb(0, 0).map(f64::from);
    let y = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    for k in 0..3 {
        assert!(
            (after[k] - y(before)).abs() < 1e-4,
            "channel {k}: {after:?}, luminance {}",
            y(before)
        );
        // The same gain on another texel (16-bit rounding aside).
        let gain = y(before) / before[k];
        let (b, a) =
            (f64::from(photo.linear_rgb(0, 1)[k]), f64::from(balanced.linear_rgb(0, 1)[k]));
        assert!((a - (b * gain).min(1.0)).abs() < 1e-4, "channel {k}: {a} against {}", b * gain);
    }
}

#[test]
fn a_white_patch_outside_the_photo_black_or_without_a_photo_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    load_with_keys(d, "white_patch = { x = 1, y = 1, width = 1, height = 1 }").unwrap();
    let m = refusal(load_with_keys(d, "white_patch = { x = 1, y = 0, width = 2, height = 1 }"));
    assert!(m.contains("materials.stone.white_patch"), "{m}");
    assert!(m.contains("2 × 1 pixels at (1, 0) is not inside the photo's 2 × 2 pixels"), "{m}");
    let m = refusal(load_with_keys(d, "white_patch = { x = 0, y = 0, width = 0, height = 1 }"));
    assert!(m.contains("is not inside"), "{m}");
    // The red texel has no green or blue: no gain makes it grey.
    let m = refusal(load_with_keys(d, "white_patch = { x = 0, y = 0, width = 1, height = 1 }"));
    assert!(m.contains("the patch is black in green; choose a grey patch"), "{m}");
    let m = refusal(load_with_keys(
        d,
        "degraded = { reflectance = \"grey\", white_patch = { x = 1, y = 1, width = 1, height = 1 } }",
    ));
    assert!(m.contains("materials.stone.degraded.white_patch"), "{m}");
    assert!(m.contains("give the state a `texture`, or put `white_patch` on the material"), "{m}");
}

/// A material without a photo of its own balances its parts' own photos on its `white_patch`,
/// so the patch is checked against each of them: outside the scan's 256 × 256 photo, it is
/// refused naming the material, the part and the file.
#[test]
fn a_white_patch_outside_a_parts_own_photo_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scan = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scans/weathered-patch.glb");
    std::fs::copy(scan, dir.path().join("scan.glb")).unwrap();
    let load = |patch: &str| {
        let toml = format!(
            "format = 1\n[camera]\nposition = [0.0, -3.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 8\nheight = 8\n\
             [spectra]\nday = {{ illuminant = \"D65\" }}\ngrey = {{ constant = 0.5 }}\n\
             [materials.stone]\nmodel = \"lambert\"\nreflectance = \"grey\"\nwhite_patch = {patch}\n\
             [[objects]]\nname = \"scan\"\nmesh = \"scan.glb\"\nmaterial = \"stone\"\n\
             [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 0.0\nelevation_deg = 60.0\nspectrum = \"day\"\n"
        );
        std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
        load_folder(&dir.path().join("scene.toml"), &Limits::default())
    };
    load("{ x = 240, y = 0, width = 16, height = 16 }").unwrap();
    let m = refusal(load("{ x = 250, y = 0, width = 16, height = 16 }"));
    assert!(
        m.contains("materials.stone.white_patch: in the photo of part `travertine` of `scan.glb`: \
                    the rectangle of 16 × 16 pixels at (250, 0) is not inside the photo's 256 × 256 pixels"),
        "{m}"
    );
}
