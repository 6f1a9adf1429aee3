//! A scan's vertex colours (PLY `red`, `green`, `blue`) as detail over the measured spectrum the
//! scene binds the part to, as a photo gives it: one colour everywhere gives back the measured
//! spectrum; two colours give reflectances in the ratio of their luminances, interpolated
//! linearly across each triangle (IEC 61966-2-1 decoding and BT.709 weights computed here from
//! the 8-bit values); chromatic detail keeps a stain's hue and is interpolated after each
//! vertex's spectrum is evaluated; `detail = "none"` turns it off.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_scene::load::{Limits, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use std::path::Path;

/// A 2 m square on the ground (z = 0) as two triangles of a binary PLY, the vertices on the
/// left (x = −1) of colour `left`, those on the right (x = 1) of colour `right`.
fn ply(path: &Path, left: [u8; 3], right: [u8; 3]) {
    let mut b = b"ply\nformat binary_little_endian 1.0\ncomment a scan's vertex colours\n\
                  element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                  property uchar red\nproperty uchar green\nproperty uchar blue\n\
                  element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    let corners =
        [([-1.0f32, -1.0], left), ([1.0, -1.0], right), ([1.0, 1.0], right), ([-1.0, 1.0], left)];
    for ([x, y], colour) in corners {
        for v in [x, y, 0.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&colour);
    }
    for face in [[0i32, 1, 2], [0, 2, 3]] {
        b.push(3);
        face.iter().for_each(|i| b.extend_from_slice(&i.to_le_bytes()));
    }
    std::fs::write(path, b).unwrap();
}

/// The ground scanned with colours `left` and `right`, its part bound to a material of
/// reflectance `rho` with the extra keys `detail`, prepared for tracing.
fn prepare(left: [u8; 3], right: [u8; 3], rho: &str, detail: &str) -> (PreparedScene, Spectrum) {
    let dir = tempfile::tempdir().unwrap();
    ply(&dir.path().join("scan.ply"), left, right);
    let toml = format!(
        "format = 1\n[camera]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0, 1, 0]\n\
         vertical_fov_deg = 30.0\nwidth = 16\nheight = 16\n\
         [spectra]\nday = {{ illuminant = \"D65\" }}\nstone = {rho}\n\
         [materials.stone]\nmodel = \"lambert\"\nreflectance = \"stone\"\n{detail}\n\
         [[objects]]\nname = \"scan\"\nmesh = \"scan.ply\"\nup_axis = \"z\"\nmaterial = \"stone\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 10000.0\nazimuth_deg = 180.0\nelevation_deg = 60.0\nspectrum = \"day\"\n"
    );
    std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
    let loaded = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    (PreparedScene::new(&loaded, None, SETTINGS).unwrap(), loaded.spectra["stone"])
}

const SETTINGS: Settings = Settings {
    integrator: Integrator::Whitted,
    samples_per_pixel: 4,
    max_depth: 1,
    seed: 7,
    grids: false,
    noise_target: 0.0,
};

/// The reflectance the tracer uses where a ray straight down meets the ground at (x, y).
fn reflectance_at(prepared: &PreparedScene, x: f32, y: f32) -> Spectrum {
    let hit = prepared.intersect(Vec3A::new(x, y, 5.0), Vec3A::NEG_Z, f32::INFINITY).unwrap();
    let mut buffer = Spectrum::ZERO;
    *prepared.reflectance(&hit, 0.0, &mut buffer)
}

/// IEC 61966-2-1 §5.2: an 8-bit sRGB code's linear value.
fn linear(code: u8) -> f64 {
    let v = f64::from(code) / 255.0;
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// Rec. ITU-R BT.709 relative luminance of an 8-bit sRGB colour.
fn luminance(rgb: [u8; 3]) -> f64 {
    0.2126 * linear(rgb[0]) + 0.7152 * linear(rgb[1]) + 0.0722 * linear(rgb[2])
}

const TRAVERTINE: &str = "\"travertine_tufa_solid__eco_ward73\"";
const POINTS: [(f32, f32); 5] = [(0.0, 0.0), (-0.9, 0.3), (0.77, -0.61), (0.2, 0.95), (-0.4, -0.8)];

#[test]
fn one_colour_everywhere_gives_the_measured_spectrum() {
    for detail in ["", "detail = \"chromatic\""] {
        let (prepared, measured) = prepare([190, 160, 120], [190, 160, 120], TRAVERTINE, detail);
        for (x, y) in POINTS {
            let rho = reflectance_at(&prepared, x, y);
            for (band, (got, want)) in rho.0.iter().zip(&measured.0).enumerate() {
                assert!(
                    (got - want).abs() <= 1e-6,
                    "`{detail}` ({x}, {y}), band {band}: {got} against {want}"
                );
            }
        }
    }
}

/// Dark on the left, light on the right: Y(x) runs linearly from one to the other, its mean
/// over the square is their mean, and ρ(x) = min(1, ρₘ·Y(x)/Ȳ).
#[test]
fn two_colours_reflect_in_the_ratio_of_their_interpolated_luminances() {
    let (dark, light) = ([60, 50, 40], [220, 210, 200]);
    let (y_dark, y_light) = (luminance(dark), luminance(light));
    let mean = 0.5 * (y_dark + y_light);
    let (prepared, _) = prepare(dark, light, "{ constant = 0.5 }", "");
    for (x, y) in POINTS {
        let share = f64::from(x + 1.0) / 2.0;
        let want = (0.5 * (y_dark + share * (y_light - y_dark)) / mean).min(1.0);
        let rho = reflectance_at(&prepared, x, y);
        for got in rho.0 {
            assert!((f64::from(got) / want - 1.0).abs() < 1e-4, "({x}, {y}): {got} against {want}");
        }
    }
    // A bright side over a bright spectrum is held at 1.
    let (prepared, _) = prepare(dark, light, "{ constant = 0.9 }", "");
    for (x, y) in POINTS.into_iter().chain([(0.95, 0.0)]) {
        let rho = reflectance_at(&prepared, x, y);
        assert!(rho.0.iter().all(|r| (0.0..=1.0).contains(r)), "({x}, {y}): {rho:?}");
    }
    assert_eq!(reflectance_at(&prepared, 0.95, 0.0).0, [1.0; 81]);
}

/// Chromatic detail from a red rust stain on the left and green lichen on the right: the
/// stain's side reflects more at 700 nm than at 450 nm relative to the lichen's; and halfway
/// the reflectance is the mean of the two sides' (each vertex's spectrum evaluated, then
/// interpolated: a spectrum fitted to the mean colour would not be).
#[test]
fn chromatic_detail_keeps_each_vertex_hue_and_interpolates_spectra() {
    let (rust, lichen) = ([180, 110, 80], [110, 140, 90]);
    // Dark enough that neither side reaches 1, where it would be held.
    let (prepared, _) = prepare(rust, lichen, "{ constant = 0.1 }", "detail = \"chromatic\"");
    let (left, right) =
        (reflectance_at(&prepared, -0.95, 0.1), reflectance_at(&prepared, 0.95, 0.1));
    let middle = reflectance_at(&prepared, 0.0, 0.1);
    let (blue, red) = (14, 64); // 450 nm, 700 nm
    let ratio = |band: usize| left.0[band] / right.0[band];
    assert!(
        ratio(red) > 1.5 * ratio(blue),
        "rust over lichen: {} at 700 nm, {} at 450 nm",
        ratio(red),
        ratio(blue)
    );
    for band in 0..81 {
        let want = 0.5 * (left.0[band] + right.0[band]);
        assert!(
            (middle.0[band] - want).abs() < 1e-5,
            "band {band}: {} halfway against {want}, the mean of the sides",
            middle.0[band]
        );
    }
    for rho in [left, middle, right] {
        assert!(rho.0.iter().all(|r| (0.0..1.0).contains(r)), "{rho:?}");
    }
}

#[test]
fn detail_none_leaves_the_measured_spectrum() {
    let (prepared, measured) =
        prepare([20, 20, 20], [240, 240, 240], TRAVERTINE, "detail = \"none\"");
    for (x, y) in POINTS {
        let hit = prepared.intersect(Vec3A::new(x, y, 5.0), Vec3A::NEG_Z, f32::INFINITY).unwrap();
        assert!(hit.detail.is_none());
        assert_eq!(reflectance_at(&prepared, x, y).0, measured.0);
    }
}

/// A glTF scan's `COLOR_0` (linear by the glTF specification, here normalized bytes) gives the
/// same detail: the luminances interpolated, relative to their mean.
#[test]
fn a_gltf_scans_color_0_gives_the_same_detail() {
    use base64::Engine as _;
    let dir = tempfile::tempdir().unwrap();
    // Y up: file (x, y, z) is world (x, −z, y); dark on the left, light on the right.
    let positions: [f32; 12] = [-1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0, 0.0, -1.0, -1.0, 0.0, -1.0];
    let (dark, light) = ([40u8, 30, 20, 255], [200u8, 190, 180, 255]);
    let colours = [dark, light, light, dark];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut buffer: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    buffer.extend(colours.iter().flatten());
    buffer.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let data = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"COLOR_0":1}},"indices":2}}]}}],
        "buffers":[{{"byteLength":76,"uri":"data:application/octet-stream;base64,{data}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":16}},{{"buffer":0,"byteOffset":64,"byteLength":12}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]}},
                     {{"bufferView":1,"componentType":5121,"normalized":true,"count":4,"type":"VEC4"}},
                     {{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#
    );
    std::fs::write(dir.path().join("scan.gltf"), gltf).unwrap();
    let toml = "format = 1\n[camera]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0, 1, 0]\nwidth = 16\nheight = 16\n\
         [spectra]\nday = { illuminant = \"D65\" }\nstone = { constant = 0.3 }\n\
         [materials.stone]\nmodel = \"lambert\"\nreflectance = \"stone\"\n\
         [[objects]]\nname = \"scan\"\nmesh = \"scan.gltf\"\nmaterial = \"stone\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 10000.0\nazimuth_deg = 180.0\nelevation_deg = 60.0\nspectrum = \"day\"\n";
    std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
    let loaded = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    let prepared = PreparedScene::new(&loaded, None, SETTINGS).unwrap();
    // Linear values: a byte over 255, weighed by BT.709.
    let y = |c: [u8; 4]| {
        0.2126 * f64::from(c[0]) / 255.0
            + 0.7152 * f64::from(c[1]) / 255.0
            + 0.0722 * f64::from(c[2]) / 255.0
    };
    let mean = 0.5 * (y(dark) + y(light));
    for (x, yy) in POINTS {
        let share = f64::from(x + 1.0) / 2.0;
        let want = 0.3 * (y(dark) + share * (y(light) - y(dark))) / mean;
        let got = f64::from(reflectance_at(&prepared, x, yy).0[40]);
        assert!((got / want - 1.0).abs() < 1e-4, "({x}, {yy}): {got} against {want}");
    }
}
