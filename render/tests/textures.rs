//! Photo textures as detail over a measured reflectance (`detail = "luminance"`): a photo equal
//! to its mean gives back the measured spectrum, the reflectance never leaves [0, 1], two texels
//! give reflectances in the ratio of their luminances (IEC 61966-2-1 decoding, BT.709 weights,
//! computed here from the 8-bit values), and a fine pattern seen from afar is filtered to its
//! mean instead of aliasing.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use std::path::Path;

/// An 8-bit RGB PNG, `texel(x, y)` the grey level (rows from the top).
fn png_file(path: &Path, width: u32, height: u32, texel: impl Fn(u32, u32) -> u8) {
    png_rgb(path, width, height, |x, y| [texel(x, y); 3]);
}

/// An 8-bit RGB PNG, `texel(x, y)` the colour (rows from the top).
fn png_rgb(path: &Path, width: u32, height: u32, texel: impl Fn(u32, u32) -> [u8; 3]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().unwrap();
    let mut data = Vec::with_capacity((width * height * 3) as usize);
    for y in 0..height {
        for x in 0..width {
            data.extend(texel(x, y));
        }
    }
    writer.write_image_data(&data).unwrap();
}

/// IEC 61966-2-1 §5.2: an 8-bit sRGB grey level's linear value (= its luminance).
fn linear(level: u8) -> f64 {
    let v = f64::from(level) / 255.0;
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// A square of `size_m` on the ground (z = 0), its texture coordinates repeating `repeat`
/// times each way, with the material `stone` of reflectance `rho` and the keys `photo` (the
/// texture's, or none).
fn scene(
    dir: &Path,
    size_m: f64,
    repeat: f64,
    rho: &str,
    camera: &str,
    photo: &str,
) -> LoadedScene {
    let h = size_m / 2.0;
    let obj = format!(
        "v {} {} 0\nv {h} {} 0\nv {h} {h} 0\nv {} {h} 0\nvt 0 {repeat}\nvt {repeat} {repeat}\nvt {repeat} 0\nvt 0 0\n\
         f 1/1 2/2 3/3 4/4\n",
        -h, -h, -h, -h
    );
    std::fs::write(dir.join("ground.obj"), obj).unwrap();
    let toml = format!(
        "format = 1\n{camera}\n[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 4\nmax_depth = 1\n\
         [spectra]\nday = {{ illuminant = \"D65\" }}\nstone = {rho}\n\
         [materials.stone]\nmodel = \"lambert\"\nreflectance = \"stone\"\n{photo}\n\
         [[objects]]\nname = \"ground\"\nmesh = \"ground.obj\"\nmaterial = \"stone\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 10000.0\nazimuth_deg = 180.0\nelevation_deg = 60.0\nspectrum = \"day\"\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

const ABOVE: &str = "[camera]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0, 1, 0]\n\
                     vertical_fov_deg = 30.0\nwidth = 16\nheight = 16";

fn prepare(scene: &LoadedScene) -> PreparedScene {
    let settings = Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: 4,
        max_depth: 1,
        seed: 7,
        grids: false,
        noise_target: 0.0,
    };
    PreparedScene::new(scene, None, settings).unwrap()
}

/// The reflectance the tracer uses where a ray straight down meets the ground at (x, y), with
/// the photo at full resolution.
fn reflectance_at(prepared: &PreparedScene, x: f32, y: f32) -> Spectrum {
    let hit = prepared.intersect(Vec3A::new(x, y, 5.0), Vec3A::NEG_Z, f32::INFINITY).unwrap();
    assert!(hit.detail.is_some(), "the ground is textured");
    let mut buffer = Spectrum::ZERO;
    *prepared.reflectance(&hit, 0.0, &mut buffer)
}

const TRAVERTINE: &str = "\"travertine_tufa_solid__eco_ward73\"";
const PHOTO: &str = "texture = \"photo.png\"";
const CHROMATIC: &str = "texture = \"photo.png\"\ndetail = \"chromatic\"";

#[test]
fn a_photo_equal_to_its_mean_gives_the_measured_spectrum() {
    let dir = tempfile::tempdir().unwrap();
    png_file(&dir.path().join("photo.png"), 8, 8, |_, _| 150);
    let loaded = scene(dir.path(), 2.0, 1.0, TRAVERTINE, ABOVE, PHOTO);
    let measured = loaded.spectra["stone"];
    let prepared = prepare(&loaded);
    for (x, y) in [(0.0, 0.0), (-0.9, 0.3), (0.77, -0.61)] {
        let rho = reflectance_at(&prepared, x, y);
        for (band, (got, want)) in rho.0.iter().zip(&measured.0).enumerate() {
            assert!((got - want).abs() <= 1e-6, "({x}, {y}), band {band}: {got} against {want}");
        }
    }
}

#[test]
fn two_texels_reflect_in_the_ratio_of_their_luminances_and_never_beyond_one() {
    let dir = tempfile::tempdir().unwrap();
    // Left half dark, right half light; rows alike.
    let (dark, light) = (40u8, 230u8);
    png_file(&dir.path().join("photo.png"), 2, 1, |x, _| if x == 0 { dark } else { light });
    let loaded = scene(dir.path(), 2.0, 1.0, "{ constant = 0.8 }", ABOVE, PHOTO);
    let prepared = prepare(&loaded);
    // Texel centres: u = 1/4 and 3/4, at x = −0.5 m and +0.5 m.
    let (left, right) = (reflectance_at(&prepared, -0.5, 0.0), reflectance_at(&prepared, 0.5, 0.0));
    // The dark texel's reflectance is ρₘ·Y/Ȳ, Ȳ the mean over the ground (the two texels'
    // mean: the photo covers it once); the light one's, 0.8 × 1.7, is clipped to 1.
    let mean = 0.5 * (linear(dark) + linear(light));
    assert!(
        (f64::from(left.0[40]) / 0.8 - linear(dark) / mean).abs() < 0.02,
        "the dark texel: {} against {}",
        left.0[40] / 0.8,
        linear(dark) / mean
    );
    // The light texel's reflectance is clipped to 1, and no point anywhere leaves [0, 1].
    assert_eq!(right.0[40], 1.0);
    for i in 0..41 {
        for j in 0..41 {
            let (x, y) = (-0.99 + 0.0495 * i as f32, -0.99 + 0.0495 * j as f32);
            let rho = reflectance_at(&prepared, x, y);
            assert!(rho.0.iter().all(|r| (0.0..=1.0).contains(r)), "({x}, {y}): {rho:?}");
        }
    }
}

/// A 2 × 1 photo whose texels are both below the mean's clipping: the reflectances are in the
/// ratio of the texels' luminances, to the filter's precision at the texel centres.
#[test]
fn the_ratio_of_two_texels_is_the_ratio_of_their_luminances() {
    let dir = tempfile::tempdir().unwrap();
    let (dark, light) = (60u8, 180u8);
    png_file(&dir.path().join("photo.png"), 2, 1, |x, _| if x == 0 { dark } else { light });
    let loaded = scene(dir.path(), 2.0, 1.0, "{ constant = 0.3 }", ABOVE, PHOTO);
    let prepared = prepare(&loaded);
    let (left, right) = (reflectance_at(&prepared, -0.5, 0.0), reflectance_at(&prepared, 0.5, 0.0));
    let want = linear(dark) / linear(light);
    for band in [0, 40, 80] {
        let ratio = f64::from(left.0[band] / right.0[band]);
        assert!((ratio / want - 1.0).abs() < 1e-4, "band {band}: {ratio} against {want}");
    }
}

/// Luminance (Y) of the rendered pixels in rows `rows`.
fn row_luminances(prepared: &PreparedScene, width: u32, rows: std::ops::Range<u32>) -> Vec<f64> {
    let tile = render_tile(
        prepared,
        Rect { x: 0, y: rows.start, width, height: rows.len() as u32 },
        false,
    );
    tile.xyz.iter().map(|p| f64::from(p[1])).collect()
}

fn spread(values: &[f64]) -> (f64, f64) {
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64;
    (mean, var.sqrt() / mean)
}

/// A checkerboard of 2 cm squares on a 400 m square ground, seen at grazing angles from eye
/// height: far off, a pixel spans hundreds of squares. Filtered by the ray's footprint each
/// pixel shows the mean, so the far rows are as smooth and as bright as the same ground
/// without the photo; sampled at full resolution they would be a random pick of black and
/// white squares (aliasing).
#[test]
fn a_fine_pattern_far_away_is_filtered_to_its_mean() {
    let dir = tempfile::tempdir().unwrap();
    png_file(&dir.path().join("photo.png"), 64, 64, |x, y| if (x + y) % 2 == 0 { 40 } else { 220 });
    // 400 m, the photo 312.5 times across: squares of 400/(312.5·64) = 2 cm.
    let camera = "[camera]\nposition = [0.0, 0.0, 1.6]\ntarget = [0.0, 100.0, 0.0]\nup = [0, 0, 1]\n\
                  vertical_fov_deg = 20.0\nwidth = 48\nheight = 32";
    let textured = prepare(&scene(dir.path(), 400.0, 312.5, "{ constant = 0.3 }", camera, PHOTO));
    let plain = prepare(&scene(dir.path(), 400.0, 312.5, "{ constant = 0.3 }", camera, ""));
    // Rows 0..12 look above the horizon? The target is 1° below it: the top half of the image
    // is sky (black here), so the far ground starts at the middle; take the rows just below.
    let far = 17..22;
    let (mean_t, spread_t) = spread(&row_luminances(&textured, 48, far.clone()));
    let (mean_p, _) = spread(&row_luminances(&plain, 48, far));
    assert!(mean_p > 0.0, "the far rows see the ground");
    assert!((mean_t / mean_p - 1.0).abs() < 0.05, "textured {mean_t} against plain {mean_p}");
    assert!(spread_t < 0.05, "the far rows vary by {spread_t} of their mean (aliasing)");
}

/// `detail = "chromatic"`: a photo of one colour gives back the measured spectrum; a stain of
/// another hue keeps it (the reflectance rises towards the red where the stain is red), where
/// luminance detail would only scale the spectrum.
#[test]
fn chromatic_detail_keeps_the_stains_hue_and_gives_back_the_measured_spectrum() {
    let dir = tempfile::tempdir().unwrap();
    png_rgb(&dir.path().join("photo.png"), 8, 8, |_, _| [200, 150, 110]);
    let loaded = scene(dir.path(), 2.0, 1.0, TRAVERTINE, ABOVE, CHROMATIC);
    let measured = loaded.spectra["stone"];
    let prepared = prepare(&loaded);
    for (x, y) in [(0.0, 0.0), (-0.9, 0.3)] {
        let rho = reflectance_at(&prepared, x, y);
        for (band, (got, want)) in rho.0.iter().zip(&measured.0).enumerate() {
            assert!((got - want).abs() <= 1e-6, "({x}, {y}), band {band}: {got} against {want}");
        }
    }
    // Left half the stone's own beige, right half a rust stain.
    png_rgb(&dir.path().join("photo.png"), 2, 1, |x, _| {
        if x == 0 { [200, 170, 140] } else { [170, 80, 50] }
    });
    let prepared = prepare(&scene(dir.path(), 2.0, 1.0, TRAVERTINE, ABOVE, CHROMATIC));
    let (clean, stain) =
        (reflectance_at(&prepared, -0.5, 0.0), reflectance_at(&prepared, 0.5, 0.0));
    let (blue, red) = (14, 64); // 450 nm, 700 nm
    let ratio = |band: usize| stain.0[band] / clean.0[band];
    assert!(
        ratio(red) > 1.5 * ratio(blue),
        "stain over clean: {} at 700 nm, {} at 450 nm",
        ratio(red),
        ratio(blue)
    );
    for rho in [clean, stain] {
        assert!(rho.0.iter().all(|r| (0.0..=1.0).contains(r)), "{rho:?}");
    }
}

/// A textured glTF, as a photogrammetry tool exports it: the part's base colour photo (a PNG in
/// a `data:` URI, moved by `KHR_texture_transform` half its width) shows as detail over the
/// spectrum the scene binds the part to, without the scene naming the photo; `detail = "none"`
/// turns it off.
#[test]
fn a_textured_gltf_shows_its_own_photo_over_the_bound_spectrum() {
    use base64::Engine as _;
    let dir = tempfile::tempdir().unwrap();
    let (dark, light) = (60u8, 180u8);
    png_file(&dir.path().join("photo.png"), 2, 1, |x, _| if x == 0 { dark } else { light });
    let image = base64::engine::general_purpose::STANDARD
        .encode(std::fs::read(dir.path().join("photo.png")).unwrap());
    // Y up: file (x, y, z) is world (x, −z, y); the quad lies on the ground, u along world x.
    let positions: [f32; 12] = [-1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0, 0.0, -1.0, -1.0, 0.0, -1.0];
    let uv: [f32; 8] = [0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut buffer: Vec<u8> = positions.iter().chain(&uv).flat_map(|v| v.to_le_bytes()).collect();
    buffer.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let data = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_texture_transform"],"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
        "materials":[{{"name":"stone","doubleSided":true,"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,
            "extensions":{{"KHR_texture_transform":{{"offset":[0.5,0.0]}}}}}}}}}}],
        "textures":[{{"source":0}}],
        "images":[{{"uri":"data:image/png;base64,{image}"}}],
        "buffers":[{{"byteLength":92,"uri":"data:application/octet-stream;base64,{data}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},{{"buffer":0,"byteOffset":80,"byteLength":12}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]}},
                     {{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},
                     {{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#
    );
    std::fs::write(dir.path().join("scan.gltf"), gltf).unwrap();
    let load = |detail: &str| {
        let toml = format!(
            "format = 1\n{ABOVE}\n[spectra]\nday = {{ illuminant = \"D65\" }}\nstone = {{ constant = 0.3 }}\n\
             [materials.stone]\nmodel = \"lambert\"\nreflectance = \"stone\"\n{detail}\n\
             [[objects]]\nname = \"scan\"\nmesh = \"scan.gltf\"\nmaterial = \"stone\"\n\
             [[lights]]\nkind = \"sun\"\nilluminance_lux = 10000.0\nazimuth_deg = 180.0\nelevation_deg = 60.0\nspectrum = \"day\"\n"
        );
        std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
        prepare(&load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap())
    };
    let prepared = load("");
    let (left, right) = (reflectance_at(&prepared, -0.5, 0.0), reflectance_at(&prepared, 0.5, 0.0));
    // The offset moved the photo half its width: the light texel is on the left now.
    let want = linear(light) / linear(dark);
    let ratio = f64::from(left.0[40] / right.0[40]);
    assert!((ratio / want - 1.0).abs() < 1e-4, "{ratio} against {want}");
    let plain = load("detail = \"none\"");
    let hit = plain.intersect(Vec3A::new(-0.5, 0.0, 5.0), Vec3A::NEG_Z, f32::INFINITY).unwrap();
    let mut buffer = Spectrum::ZERO;
    assert_eq!(plain.reflectance(&hit, 0.0, &mut buffer).0, [0.3; 81]);
}

/// IEC 61966-2-1 §5.3: a linear value's 8-bit sRGB code.
fn code(linear: f64) -> u8 {
    let v =
        if linear <= 0.003_130_8 { 12.92 * linear } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 };
    (v * 255.0).round().clamp(0.0, 255.0) as u8
}

/// A photo taken under a warm cast and balanced on the grey card it shows (`white_patch`) gives
/// the reflectances the photo without the cast gives, to within 8-bit rounding (chromatic
/// detail); unbalanced, its
/// stain's spectrum leans to the cast. The cast is a diagonal one that keeps grey's luminance,
/// which balancing on a grey patch undoes exactly.
#[test]
fn a_photo_balanced_on_its_grey_card_loses_its_cast() {
    // Grey card, stone, stone, rust stain (linear sRGB).
    let scene_colours =
        [[0.5, 0.5, 0.5], [0.45, 0.38, 0.28], [0.40, 0.35, 0.27], [0.35, 0.14, 0.09]];
    let green = (1.0 - 0.2126 * 1.25 - 0.0722 * 0.7) / 0.7152;
    let cast = [1.25, green, 0.7];
    let photo = |cast: [f64; 3]| {
        move |x: u32, _: u32| {
            let c: [f64; 3] = scene_colours[x as usize];
            [code(c[0] * cast[0]), code(c[1] * cast[1]), code(c[2] * cast[2])]
        }
    };
    let patch = "white_patch = { x = 0, y = 0, width = 1, height = 1 }";
    let stain_at = |dir: &Path, keys: &str| {
        let prepared = prepare(&scene(dir, 2.0, 1.0, TRAVERTINE, ABOVE, keys));
        // The stain's texel centre: u = 7/8.
        reflectance_at(&prepared, 0.75, 0.0)
    };
    let dir = tempfile::tempdir().unwrap();
    let chromatic = format!("{CHROMATIC}\n{patch}");
    png_rgb(&dir.path().join("photo.png"), 4, 1, photo([1.0; 3]));
    let truth = stain_at(dir.path(), CHROMATIC);
    png_rgb(&dir.path().join("photo.png"), 4, 1, photo(cast));
    let balanced = stain_at(dir.path(), &chromatic);
    let unbalanced = stain_at(dir.path(), CHROMATIC);
    let worst = |rho: &Spectrum| {
        rho.0.iter().zip(&truth.0).map(|(r, t)| (r / t - 1.0).abs()).fold(0.0f32, f32::max)
    };
    let (b, u) = (worst(&balanced), worst(&unbalanced));
    // Neighbouring 8-bit codes of the stain's blue are 3 % apart in linear value, and the
    // photo is rounded twice (cast, then balanced); the cast itself moves the stain by 25 %.
    assert!(b < 0.04, "balanced, the stain is {b} off the uncast photo's");
    assert!(u > 5.0 * b.max(0.01), "unbalanced {u}, balanced {b}: the cast should show");
}
