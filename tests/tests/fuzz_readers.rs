//! A fuzz harness for every reader of outside input, on stable Rust inside `cargo test`: the
//! scene TOML (through the scene loader, on a folder), OBJ, PLY (ASCII and binary), glTF and
//! GLB, VRML97, IES LM-63, EULUMDAT, spectrum CSV, OpenEXR, and bundle archives and scene
//! folders sent as a zip.
//!
//! Each input is a valid seed file (generated here, or read from `data/` and the scene crate's
//! photometric fixtures) changed by a few seeded, deterministic mutations: bit flips,
//! truncations, inserted bytes, repeated blocks, deleted blocks, bytes and integers replaced
//! with interesting values (0, −1, 2^31, 2^64, NaN, …), numbers in text replaced with
//! interesting numbers (1e308, 18446744073709551616, -0, nan, …) and repeated lines. For each
//! input it asserts:
//! - **no panic**: the reader runs under `catch_unwind`, *and* `restauro_scene::guard`'s count
//!   of panics it turned into errors must not move. The readers are called exactly as restauro
//!   calls them, guard included, so a panic inside a third-party parser that the guard hides
//!   from users still fails here: it is a hole in the validation in front of that parser;
//! - **no hang**: each input runs on its own thread and must answer within
//!   `RESTAURO_FUZZ_TIMEOUT_S` seconds (default 20), through a channel's `recv_timeout`;
//! - **a refusal names the file**: the message holds the file's name (for the scene TOML, the
//!   scene file or a file in its folder);
//! - **no inf or NaN once accepted**: an accepted scene is prepared for tracing (its BVH built)
//!   and three pixels traced with finite XYZ; an accepted spectrum has finite XYZ under it and
//!   as a light; an accepted EXR has finite pixels.
//!
//! Every failure names the reader, the seed file, the input number and the mutations, and
//! keeps the input under `$TMPDIR/restauro-fuzz-failures/`; `RESTAURO_FUZZ_ONLY=<reader>:<n>`
//! runs that one input again (with the same `RESTAURO_FUZZ_SEED`).
//!
//! The quick run (`cargo test`) tries 300 inputs per reader, 3600 in all (and the seeds and
//! kept findings unmutated), in about 4 s with the test profile. A longer run is one command
//! away; the test profile keeps overflow checks, which find more (330 000 inputs take about six
//! minutes on one core), and `--release` runs faster:
//!
//! ```sh
//! RESTAURO_FUZZ_INPUTS=330000 RESTAURO_FUZZ_SEED=1 \
//!     cargo test -p restauro-tests --test fuzz_readers -- --nocapture
//! RESTAURO_FUZZ_INPUTS=200000 cargo test --release -p restauro-tests --test fuzz_readers -- --nocapture
//! ```
//!
//! (`RESTAURO_FUZZ_INPUTS` is the total, shared by the readers; a different
//! `RESTAURO_FUZZ_SEED` explores different mutations; `RESTAURO_FUZZ_VERBOSE=1` prints every
//! refusal, to see how deep the mutations reach.) Inputs that once found a defect are kept under
//! `tests/fuzz-findings/` (see [`findings`]), so the quick run reads them every time.
//!
//! Why the guard's conversions count as failures rather than calling each parser below the
//! guard: the guard is part of the reader as users run it, and calling below it would need a
//! second, test-only entry point into every reader; counting keeps one path and still fails.

use exr::prelude::{
    AnyChannel, AnyChannels, Blocks, Compression, Encoding, FlatSamples, Image, Layer,
    LayerAttributes, LineOrder, SmallVec, Vec2, WritableImage, f16,
};
use restauro_assets::load_scene;
use restauro_image::image_files::{MAX_PIXELS, XyzImage, read_exr, write_spectral_exr};
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{film_xyz, pixel};
use restauro_scene::guard;
use restauro_scene::load::Limits;
use restauro_scene::scene_file::Integrator;
use restauro_spectral::colorimetry::{Observer, relative_xyz};
use restauro_spectral::csv::{Quantity, load as load_csv};
use restauro_spectral::photometry::LuminousSpectrum;
use restauro_spectral::tabulated::Coverage;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

// ---------------------------------------------------------------------------------------------
// Deterministic randomness and mutations

/// SplitMix64: small, fast, and the same everywhere.
struct Rng(u64);

impl Rng {
    fn new(key: &[u64]) -> Self {
        let mut r = Rng(0x9e37_79b9_7f4a_7c15);
        for &k in key {
            r.0 ^= k;
            r.next();
        }
        r
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n` > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A string's stable hash (FNV-1a), to key the randomness by reader name.
fn hash(text: &str) -> u64 {
    text.bytes()
        .fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

const INTERESTING_BYTES: &[u8] = &[
    0x00, 0x01, 0x7f, 0x80, 0xff, b'\n', b'\r', b' ', b'-', b'9', b'"', b'[', b']', b'{', b'}',
    b',', b'#', b'.', b'/', 0xe9,
];

const INTERESTING_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1",
    "2",
    "3",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999",
    "1e308",
    "-1e308",
    "1e39",
    "1e-45",
    "1e-320",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e9",
    "1e10",
    "0.5",
    "-0.5",
    "1.5",
    "3.4028236e38",
    "1e300",
    "0x10",
    "",
];

const INTERESTING_INTEGERS: &[u64] = &[
    0,
    1,
    0x7f,
    0x80,
    0xff,
    0xffff,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    u64::MAX,
    0x7ff8_0000_0000_0000, // f64 NaN
    0x7f80_0000,           // f32 infinity
    0x7fc0_0000,           // f32 NaN
];

/// Change `bytes` by one to four mutations; returns what was done, for the failure report.
fn mutate(bytes: &mut Vec<u8>, rng: &mut Rng) -> Vec<String> {
    let mut done = Vec::new();
    // Half the inputs carry one mutation, so that many still parse and reach the checks of
    // values; the others up to four.
    let count = if rng.below(2) == 0 { 1 } else { 1 + rng.below(4) };
    for _ in 0..count {
        let len = bytes.len();
        let at = rng.below(len + 1);
        // Numbers replaced (5) weigh three times: most formats here are text, and values reach
        // deeper than syntax.
        let op = match rng.below(12) {
            10 | 11 => 5,
            op => op,
        };
        // A mutation that finds nothing to change (no number, no line, too short) says nothing.
        let did = match op {
            0 => Some(flip_bits(bytes, rng)),
            1 => {
                bytes.truncate(at);
                Some(format!("truncate at {at}"))
            }
            2 => Some(insert_random_bytes(bytes, rng, at)),
            3 if len > 0 => Some(repeat_a_block(bytes, rng, at)),
            4 if len > 0 => {
                let i = rng.below(len);
                let b = INTERESTING_BYTES[rng.below(INTERESTING_BYTES.len())];
                bytes[i] = b;
                Some(format!("byte {i} = {b:#04x}"))
            }
            5 => replace_a_number(bytes, rng),
            6 if len >= 8 => Some(replace_an_integer(bytes, rng)),
            7 if len > 0 => {
                let start = rng.below(len);
                let n = 1 + rng.below((len - start).min(64));
                bytes.drain(start..start + n);
                Some(format!("delete bytes {start}..{}", start + n))
            }
            8 => repeat_a_line(bytes, rng),
            _ => copy_a_block_elsewhere(bytes, rng),
        };
        done.extend(did);
    }
    done
}

/// One to eight bits flipped, anywhere.
fn flip_bits(bytes: &mut [u8], rng: &mut Rng) -> String {
    let len = bytes.len();
    let n = 1 + rng.below(8);
    for _ in 0..n {
        if len > 0 {
            let i = rng.below(len);
            bytes[i] ^= 1 << rng.below(8);
        }
    }
    format!("flip {n} bits")
}

/// One to sixteen random bytes inserted at `at`.
fn insert_random_bytes(bytes: &mut Vec<u8>, rng: &mut Rng, at: usize) -> String {
    let n = 1 + rng.below(16);
    let insert: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
    bytes.splice(at..at, insert);
    format!("insert {n} random bytes at {at}")
}

/// A block of the input (up to 256 bytes) repeated at `at`, up to 16 times (one time in eight
/// up to 4096 times). `bytes` is not empty.
fn repeat_a_block(bytes: &mut Vec<u8>, rng: &mut Rng, at: usize) -> String {
    let len = bytes.len();
    let start = rng.below(len);
    let n = 1 + rng.below((len - start).min(256));
    let most = if rng.below(8) == 0 { 4096 } else { 16 };
    let times = 1 + rng.below(most);
    let block = bytes[start..start + n].to_vec();
    let insert: Vec<u8> = block.iter().copied().cycle().take(n * times).collect();
    bytes.splice(at..at, insert);
    format!("repeat bytes {start}..{} {times} times at {at}", start + n)
}

/// A run of digits (with its sign and decimals) replaced by an interesting number; nothing
/// when the input has no digit.
fn replace_a_number(bytes: &mut Vec<u8>, rng: &mut Rng) -> Option<String> {
    let len = bytes.len();
    let starts: Vec<usize> = (0..len)
        .filter(|&i| bytes[i].is_ascii_digit() && (i == 0 || !bytes[i - 1].is_ascii_digit()))
        .collect();
    if starts.is_empty() {
        return None;
    }
    let start = starts[rng.below(starts.len())];
    let mut end = start;
    while end < len && (bytes[end].is_ascii_digit() || bytes[end] == b'.' || bytes[end] == b'e') {
        end += 1;
    }
    let number = INTERESTING_NUMBERS[rng.below(INTERESTING_NUMBERS.len())];
    bytes.splice(start..end, number.bytes());
    Some(format!("number at {start} = `{number}`"))
}

/// 1, 2, 4 or 8 bytes replaced by an interesting integer, big- or little-endian. `bytes` holds
/// at least 8.
fn replace_an_integer(bytes: &mut [u8], rng: &mut Rng) -> String {
    let len = bytes.len();
    let i = rng.below(len - 7);
    let v = INTERESTING_INTEGERS[rng.below(INTERESTING_INTEGERS.len())];
    let width = [1, 2, 4, 8][rng.below(4)];
    let big = rng.below(2) == 0;
    let b = if big { v.to_be_bytes() } else { v.to_le_bytes() };
    let b = if big { &b[8 - width..] } else { &b[..width] };
    bytes[i..i + width].copy_from_slice(b);
    format!("{width} bytes at {i} = {v:#x} ({})", if big { "BE" } else { "LE" })
}

/// A whole line repeated one to eight times; nothing when the input is empty.
fn repeat_a_line(bytes: &mut Vec<u8>, rng: &mut Rng) -> Option<String> {
    let len = bytes.len();
    let starts: Vec<usize> = std::iter::once(0)
        .chain((0..len).filter(|&i| bytes[i] == b'\n').map(|i| i + 1))
        .filter(|&i| i < len)
        .collect();
    if starts.is_empty() {
        return None;
    }
    let start = starts[rng.below(starts.len())];
    let end = bytes[start..].iter().position(|&b| b == b'\n').map_or(len, |i| start + i + 1);
    let times = 1 + rng.below(8);
    let line: Vec<u8> = bytes[start..end].repeat(times);
    bytes.splice(end..end, line);
    Some(format!("repeat line at {start} {times} times"))
}

/// A piece of the file itself spliced in elsewhere (a moved block); nothing when the input is
/// shorter than two bytes.
fn copy_a_block_elsewhere(bytes: &mut Vec<u8>, rng: &mut Rng) -> Option<String> {
    let len = bytes.len();
    if len <= 1 {
        return None;
    }
    let start = rng.below(len);
    let n = 1 + rng.below((len - start).min(128));
    let block = bytes[start..start + n].to_vec();
    let to = rng.below(len);
    let end = (to + n).min(bytes.len());
    bytes.splice(to..end, block);
    Some(format!("copy {start}..{} over {to}", start + n))
}

// ---------------------------------------------------------------------------------------------
// Seeds

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
}

fn read(path: &str) -> Vec<u8> {
    std::fs::read(repo(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

const GREY_CSV: &str = "# a neutral grey\nwavelength_nm,reflectance\n380,0.3\n780,0.3\n";

/// A scene around one mesh (or light file), every part grey, lit by a sun (and `lights`).
fn scene_around(mesh: &str, lights: &str) -> String {
    format!(
        r#"format = 1
[camera]
position = [0.5, -6.0, 0.5]
target = [0.3, 0.0, 0.4]
width = 16
height = 12

[render]
samples_per_pixel = 1
max_depth = 2

[spectra]
grey = {{ file = "grey.csv" }}
light = {{ illuminant = "D65" }}

[materials.grey]
model = "lambert"
reflectance = "grey"

[[objects]]
name = "m"
mesh = "{mesh}"
material = "grey"

[[lights]]
kind = "sun"
illuminance_lux = 1000.0
azimuth_deg = 180.0
elevation_deg = 40.0
spectrum = "light"
{lights}
"#
    )
}

const QUAD_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3 4\n";

/// The quad with texture coordinates, for the photo textures.
const TEXTURED_QUAD_OBJ: &str =
    "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";

/// The quad as a photogrammetry export names it: its library `input.mtl` and a part.
const LIBRARY_QUAD_OBJ: &str = "mtllib input.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl stone\nf 1/1 2/2 3/3 4/4\n";

/// Material libraries as exporters write them (Agisoft Metashape, RealityCapture, Blender).
fn mtl_seeds() -> Vec<(String, Vec<u8>)> {
    [
        ("metashape.mtl", "newmtl stone\nKa 1.000000 1.000000 1.000000\nKd 1.000000 1.000000 1.000000\nKs 0.000000 0.000000 0.000000\nTr 1.000000\nillum 1\nNs 0.000000\nmap_Kd photo.png\n"),
        ("options.mtl", "# Blender MTL\nnewmtl stone\nNs 250\nKd 0.8 0.8 0.8\nd 1\nmap_Kd -s 1 1 1 -o 0 0 0 -clamp on photo.png\nnewmtl other\nmap_Kd textures\\photo.png\n"),
    ]
    .into_iter()
    .map(|(name, text)| (name.to_owned(), text.as_bytes().to_vec()))
    .collect()
}

/// Photo textures: small PNGs of every colour type and depth, and a JPEG made by Pillow.
fn texture_seeds(extension: &str) -> Vec<(String, Vec<u8>)> {
    if extension == "jpg" {
        return vec![("gradient.jpg".into(), read("scene/tests/data/texture/gradient.jpg"))];
    }
    let kinds = [
        (png::ColorType::Rgb, png::BitDepth::Eight, 3),
        (png::ColorType::Rgba, png::BitDepth::Sixteen, 8),
        (png::ColorType::Grayscale, png::BitDepth::Eight, 1),
        (png::ColorType::GrayscaleAlpha, png::BitDepth::Eight, 2),
    ];
    kinds
        .iter()
        .map(|&(colour, depth, bytes_per_texel)| {
            let mut out = Vec::new();
            {
                let mut encoder = png::Encoder::new(&mut out, 5, 3);
                encoder.set_color(colour);
                encoder.set_depth(depth);
                let mut w = encoder.write_header().unwrap();
                let data: Vec<u8> =
                    (0..15 * bytes_per_texel).map(|i| (i * 37 % 251) as u8).collect();
                w.write_image_data(&data).unwrap();
            }
            (format!("{colour:?}-{depth:?}.png"), out)
        })
        .collect()
}

fn obj_seeds() -> Vec<(String, Vec<u8>)> {
    let board = restauro_demo::scenes::samples::generate("D65", 16, 12, 1).board_obj;
    let rich = "# parts by material and group, texture coordinates, normals, negative indices\n\
        mtllib other.mtl\no block\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1 1.0\nv 0.5 0 1.5 0.2 0.3 0.4\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvn 0 -1 0\ng front\nusemtl stone\nf 1/1/1 2/2/1 3/3/1\n\
        f -5//1 -3//1 -2//1\nusemtl joint\nf 3 4 5\nl 1 2\nf 1 2 3 4 5\n";
    vec![("board.obj".into(), board.into_bytes()), ("rich.obj".into(), rich.as_bytes().to_vec())]
}

fn ply_ascii_seeds() -> Vec<(String, Vec<u8>)> {
    let quad = "ply\nformat ascii 1.0\ncomment a quad and a triangle\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0 255 0 9\n2 0 0 0 128 9\n2 0 3 7 7 7\n0 0 3 9 200 100\n1 0 4 1 2 3\n4 0 1 2 3\n3 3 2 4\n";
    let double = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\nelement face 1\nproperty list ushort uint vertex_index\nelement extra 1\nproperty short s\nend_header\n0 0 0 0.5 0.25 1\n1.5e0 0 0 0 0 0\n0 0 1 1 1 1\n3 0 1 2\n-7\n";
    vec![("quad.ply".into(), quad.into()), ("double.ply".into(), double.into())]
}

fn ply_binary(big: bool) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_{}_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar flags\nelement face 2\nproperty list uchar int vertex_indices\nproperty uint tag\nend_header\n",
        if big { "big" } else { "little" }
    )
    .into_bytes();
    let f32b = |v: f32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
    let i32b = |v: i32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
    for (v, flag) in [
        ([0.0f32, 0.0, 0.0], 1u8),
        ([1.0, 0.0, 0.0], 2),
        ([1.0, 0.0, 1.0], 3),
        ([0.0, 0.0, 1.0], 4),
    ] {
        for c in v {
            b.extend_from_slice(&f32b(c));
        }
        b.push(flag);
    }
    for face in [&[0, 1, 2][..], &[0, 2, 3]] {
        b.push(face.len() as u8);
        for &i in face {
            b.extend_from_slice(&i32b(i));
        }
        b.extend_from_slice(&i32b(7));
    }
    b
}

fn ply_binary_seeds() -> Vec<(String, Vec<u8>)> {
    vec![("little.ply".into(), ply_binary(false)), ("big.ply".into(), ply_binary(true))]
}

/// The binary part of the glTF seeds: positions of two triangles (f32 VEC3), then u16 indices.
fn gltf_bin() -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]] {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 1, 3, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin
}

fn gltf_json(buffer: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0}},{{"rotation":[0,0,0.7071068,0.7071068],"children":[2,3]}},
{{"mesh":0,"translation":[10,0,0],"scale":[2,2,2]}},{{"mesh":0,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,5,0,1]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}},{{"attributes":{{"POSITION":2}}}}]}}],
"materials":[{{"name":"marble","doubleSided":true,"pbrMetallicRoughness":{{"baseColorFactor":[0.9,0.8,0.7,1]}}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}},
{{"bufferView":0,"byteOffset":12,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48,"byteStride":12}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
"buffers":[{{"byteLength":60{buffer}}}]}}"#
    )
}

fn gltf_seeds() -> Vec<(String, Vec<u8>)> {
    use base64::Engine;
    let data = base64::engine::general_purpose::STANDARD.encode(gltf_bin());
    let json = gltf_json(&format!(r#","uri":"data:application/octet-stream;base64,{data}""#));
    vec![("model.gltf".into(), json.into_bytes())]
}

/// A GLB container (glTF 2.0 §4.4): header, JSON chunk, BIN chunk, each padded to 4 bytes.
fn glb_seeds() -> Vec<(String, Vec<u8>)> {
    let mut json = gltf_json("").into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin = gltf_bin(); // 60 bytes, already a multiple of 4
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    vec![("model.glb".into(), glb)]
}

fn vrml_seeds() -> Vec<(String, Vec<u8>)> {
    let world = r#"#VRML V2.0 utf8
# A tile used twice, a concave face, a switch, a level of detail and a viewpoint.
WorldInfo { title "fuzz" info [ "seed" ] }
DEF view Viewpoint { position 0 1.6 10 orientation 0 1 0 0.2 fieldOfView 0.8 description "front" }
DEF outer Transform {
  translation 1 0 0 rotation 0 1 0 0.5 scale 2 2 2 scaleOrientation 1 0 0 0.3 center 0 1 0
  children [
    DEF tile Shape {
      appearance Appearance { material Material { diffuseColor 0.8 0.7 0.6 } }
      geometry IndexedFaceSet {
        coord Coordinate { point [0 0 0, 1 0 0, 1 1 0, 0.5 0.4 0, 0 1 0] }
        coordIndex [0 1 2 3 4 -1, 0 1 2 -1]
        ccw TRUE solid FALSE convex FALSE creaseAngle 0.5
      }
    }
    Transform { translation 0 0 2 children [ USE tile ] }
  ]
}
Switch { whichChoice 0 choice [ Group { children [ USE tile ] } ] }
LOD { level [ Transform { translation 0 3 0 children USE tile } ] }
Shape { geometry Box { size 1 1 1 } }
ROUTE view.bindTime TO outer.set_translation
"#;
    // Prototypes (nested, with IS, DEF/USE in a body, an EXTERNPROTO of the file and one
    // not) around every primitive, with a light and text that are noted.
    let protos = r##"#VRML V2.0 utf8
PROTO Post [ field SFFloat r 0.5 field SFColor c 0.8 0.7 0.6 ] {
  Shape { appearance Appearance { material Material { diffuseColor IS c } } geometry Cylinder { radius IS r height 3 } }
}
PROTO Bay [ field SFFloat r 0.5 exposedField SFVec3f at 0 0 0 eventIn SFVec3f set_at ] {
  PROTO Cap [ field SFFloat s 1 ] { Shape { geometry Cone { bottomRadius IS s height 1 side TRUE bottom FALSE } } }
  Transform { translation IS at set_translation IS set_at children [
    DEF p Post { r IS r }
    Transform { translation 0 2 0 children [ Cap { s IS r } USE p ] }
  ] }
  DirectionalLight { }
}
EXTERNPROTO Pier [ field SFFloat r ] [ "lib.wrl#Pier" "#Post" ]
EXTERNPROTO Statue [ ] "http://example.org/statue.wrl"
Bay { at 2 0 0 } DEF b2 Bay { r 0.25 } Pier { r 1 } Statue { }
Transform { rotation 0 1 0 0.3 scale 1 2 1 children [
  Shape { geometry Box { size 1 2 3 } }
  Shape { geometry Sphere { radius 0.7 } }
  Shape { geometry ElevationGrid { xDimension 3 zDimension 2 xSpacing 0.5 zSpacing 1 height [0 0.1 0.2, 0.3 0.4 0.5] ccw FALSE solid FALSE creaseAngle 1 } }
  Shape { geometry Extrusion { spine [0 0 0, 1 1 0, 2 1 1, 0 0 0] crossSection [1 0, 0 1, -1 0, 0 -1, 1 0] scale [1 1, 0.5 0.5, 1 2, 1 1] orientation [0 1 0 0.5] convex FALSE creaseAngle 0.8 } }
  Shape { geometry Text { string "Tempio" } }
  PointLight { } Inline { url "other.wrl" }
] }
"##;
    vec![("world.wrl".into(), world.into()), ("protos.wrl".into(), protos.into())]
}

fn photometric_seeds(extension: &str) -> Vec<(String, Vec<u8>)> {
    let dir = repo("scene/tests/data/photometric");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(extension))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|n| (n.clone(), read(&format!("scene/tests/data/photometric/{n}"))))
        .collect()
}

fn csv_seeds() -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = [
        "data/spectra/travertine_tufa_solid__eco_ward73.csv",
        "data/spectra/carbon_black_soot_proxy__usgs_GDS68.csv",
        "data/spectra/lichen_xanthoria_orange_on_rock__usgs_Xanthoria-1.csv",
    ]
    .iter()
    .map(|p| (Path::new(p).file_name().unwrap().to_string_lossy().into_owned(), read(p)))
    .collect();
    out.push((
        "lamp.csv".into(),
        b"# a lamp, relative power\n380,10\n555,100\n600,150\n780,40\n".to_vec(),
    ));
    out
}

fn exr_image(width: usize, height: usize) -> XyzImage {
    let pixels = (0..width * height).map(|i| [i as f32 * 0.1, 1.0 + i as f32, 0.5]).collect();
    XyzImage {
        width,
        height,
        pixels,
        emitter: Some((0..width * height).map(|i| i % 5 == 0).collect()),
        lit_by: None,
        white: None,
    }
}

/// A bundle archive of a small Aosta facade (`scene bundle --out`).
fn archive_seeds(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let aosta = restauro_demo::scenes::aosta::generate(16, 9, 1);
    let folder = dir.join("archive-seed");
    std::fs::create_dir_all(folder.join("meshes")).unwrap();
    std::fs::write(folder.join("aosta.toml"), &aosta.scene_toml).unwrap();
    std::fs::write(folder.join("meshes/facade.obj"), &aosta.facade_obj).unwrap();
    let limits = restauro_scene::limits::Limits::default();
    let bundle = restauro_assets::bundle_scene(&folder.join("aosta.toml"), &limits).unwrap();
    let path = dir.join("aosta.tar");
    restauro_assets::archive::write_archive(&bundle, &path).unwrap();
    vec![("aosta.tar".into(), std::fs::read(&path).unwrap())]
}

/// The Aosta folder as a file manager zips it, its entries deflated, and stored.
fn zip_seeds() -> Vec<(String, Vec<u8>)> {
    use std::io::Write;
    let aosta = restauro_demo::scenes::aosta::generate(16, 9, 1);
    [zip::CompressionMethod::Deflated, zip::CompressionMethod::Stored]
        .into_iter()
        .map(|method| {
            let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
            let options = zip::write::SimpleFileOptions::default().compression_method(method);
            for (name, text) in [
                ("aosta/aosta.toml", &aosta.scene_toml),
                ("aosta/meshes/facade.obj", &aosta.facade_obj),
            ] {
                w.start_file(name, options).unwrap();
                w.write_all(text.as_bytes()).unwrap();
            }
            (format!("aosta-{method:?}.zip"), w.finish().unwrap().into_inner())
        })
        .collect()
}

fn exr_seeds(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let path = dir.join("spectral.exr");
    write_spectral_exr(
        &path,
        &exr_image(12, 6),
        vec![(380.0, vec![0.5; 72]), (385.0, vec![1.5; 72])],
        &[("restauroNote", "seed")],
    )
    .unwrap();
    out.push(("spectral.exr".to_owned(), std::fs::read(&path).unwrap()));
    let (w, h) = (16, 8);
    let compressions = [
        ("none", Compression::Uncompressed),
        ("rle", Compression::RLE),
        ("zip1", Compression::ZIP1),
        ("zip16", Compression::ZIP16),
        ("piz", Compression::PIZ),
        ("pxr24", Compression::PXR24),
        ("b44", Compression::B44),
    ];
    for (i, (name, compression)) in compressions.into_iter().enumerate() {
        let blocks = if i % 2 == 0 { Blocks::ScanLines } else { Blocks::Tiles(Vec2(8, 4)) };
        let half =
            |v: f32| (0..w * h).map(|k| f16::from_f32(v + k as f32 * 0.25)).collect::<Vec<_>>();
        let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::from_vec(vec![
            AnyChannel::new("R", FlatSamples::F16(half(0.1))),
            AnyChannel::new("G", FlatSamples::F32((0..w * h).map(|k| k as f32).collect())),
            AnyChannel::new("B", FlatSamples::F16(half(2.0))),
        ]);
        let layer = Layer::new(
            (w, h),
            LayerAttributes::default(),
            Encoding { compression, blocks, line_order: LineOrder::Increasing },
            AnyChannels::sort(list),
        );
        let mut bytes = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer).write().to_buffered(&mut bytes).unwrap();
        out.push((format!("{name}.exr"), bytes.into_inner()));
    }
    out
}

/// Inputs that found a defect, kept under `tests/fuzz-findings/<reader>/` so that every quick
/// run reads them again (those reduced to a few lines are regression tests beside the reader
/// instead, e.g. `scene/tests/bad_input.rs`).
mod findings {
    /// (file name, bytes) of the findings kept for `reader`.
    pub fn of(reader: &str) -> Vec<(String, Vec<u8>)> {
        let dir = super::repo("tests/fuzz-findings").join(reader);
        let Ok(entries) = std::fs::read_dir(&dir) else { return Vec::new() };
        let mut out: Vec<(String, Vec<u8>)> = entries
            .map(|e| e.unwrap().path())
            .map(|p| {
                (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap())
            })
            .collect();
        out.sort();
        out
    }
}

// ---------------------------------------------------------------------------------------------
// Readers

/// Where one reader's inputs live: a scene folder with the files around the fuzzed one.
struct Bench {
    dir: tempfile::TempDir,
}

impl Bench {
    fn new(files: &[(&str, &[u8])]) -> Self {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in files {
            let path = dir.path().join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, bytes).unwrap();
        }
        Self { dir }
    }

    /// The folder, as the loader names it (symbolic links resolved).
    fn folder(&self) -> PathBuf {
        self.dir.path().canonicalize().unwrap()
    }
}

/// What a reader made of an input: accepted, or refused with this message.
type Outcome = Result<(), String>;

/// A scene loaded, prepared for tracing and three pixels traced: nothing infinite or NaN.
fn load_and_trace(scene: &Path) -> Outcome {
    let loaded = load_scene(scene, &Limits::default()).map_err(|e| e.to_string())?;
    for o in &loaded.objects {
        if let Some(p) =
            o.mesh.positions.iter().find(|p| !p.iter().all(|c| c.is_finite() && c.abs() <= 1e9))
        {
            panic!("accepted, but object `{}` has a vertex at {p:?}", o.name);
        }
    }
    let settings = Settings {
        integrator: Integrator::Path,
        samples_per_pixel: 1,
        max_depth: loaded.file.render.max_depth.min(3),
        seed: 1,
        grids: false,
        noise_target: 0.0,
    };
    // Everything hidden is the tracer's refusal to make, not a reader's.
    let Ok(prepared) = PreparedScene::new(&loaded, None, settings) else { return Ok(()) };
    let (w, h) = (loaded.camera.width, loaded.camera.height);
    for (x, y) in [(w / 2, h / 2), (0, 0), (w - 1, h - 1)] {
        let xyz = film_xyz(&pixel(&prepared, x, y));
        assert!(xyz.iter().all(|v| v.is_finite()), "accepted, but pixel ({x}, {y}) is {xyz:?}");
    }
    Ok(())
}

struct Reader {
    name: &'static str,
    /// The fuzzed file's name in its folder (its extension chooses the format).
    file: &'static str,
    seeds: Vec<(String, Vec<u8>)>,
    /// The files around it.
    bench: Bench,
    /// Read the input (already written to `file` in the bench folder, which is given).
    run: fn(&Path) -> Outcome,
    /// Whether a refusal's message names the file (the bench folder is given).
    names_file: fn(&Path, &str) -> bool,
}

/// Every fuzzed file is called `input.<extension>`.
fn names_own_file(_: &Path, message: &str) -> bool {
    message.contains("input.")
}

/// Every reader fuzzed, in the order they run: the scene file, the meshes and their material
/// libraries, textures, photometric files, spectrum CSV, archives and zipped folders, EXR.
fn readers() -> Vec<Reader> {
    let mut all = vec![scene_reader()];
    all.extend(mesh_readers());
    all.extend(texture_and_light_readers());
    all.push(csv_reader());
    all.extend(archive_and_exr_readers());
    all
}

/// A mesh reader: the mesh `file` of a grey scene, loaded and traced.
fn mesh_reader(name: &'static str, file: &'static str, seeds: Vec<(String, Vec<u8>)>) -> Reader {
    Reader {
        name,
        file,
        seeds,
        bench: Bench::new(&[
            ("grey.csv", GREY_CSV.as_bytes()),
            ("scene.toml", scene_around(file, "").as_bytes()),
        ]),
        run: |folder| load_and_trace(&folder.join("scene.toml")),
        names_file: names_own_file,
    }
}

/// The readers of meshes (OBJ, PLY, glTF, GLB, VRML97) and of OBJ's material libraries.
fn mesh_readers() -> Vec<Reader> {
    let grey = GREY_CSV.as_bytes();
    vec![
        mesh_reader("obj", "input.obj", obj_seeds()),
        mesh_reader("ply-ascii", "input.ply", ply_ascii_seeds()),
        mesh_reader("ply-binary", "input.ply", ply_binary_seeds()),
        mesh_reader("gltf", "input.gltf", gltf_seeds()),
        mesh_reader("glb", "input.glb", glb_seeds()),
        Reader {
            // A world beside the fuzzed one, for its Inline to draw.
            bench: Bench::new(&[
                ("grey.csv", grey),
                ("other.wrl", b"#VRML V2.0 utf8\nShape { geometry Box { size 0.2 0.2 0.2 } }\n"),
                ("scene.toml", scene_around("input.wrl", "").as_bytes()),
            ]),
            ..mesh_reader("vrml", "input.wrl", vrml_seeds())
        },
        Reader {
            name: "mtl",
            file: "input.mtl",
            seeds: mtl_seeds(),
            bench: Bench::new(&[
                ("grey.csv", grey),
                ("quad.obj", LIBRARY_QUAD_OBJ.as_bytes()),
                ("photo.png", texture_seeds("png").remove(0).1.as_slice()),
                ("scene.toml", scene_around("quad.obj", "").as_bytes()),
            ]),
            run: |folder| load_and_trace(&folder.join("scene.toml")),
            names_file: names_own_file,
        },
    ]
}

/// The readers of a material's texture (PNG, JPEG) and of a luminaire's photometric file (IES
/// LM-63, EULUMDAT), each in a grey scene around a quad.
fn texture_and_light_readers() -> Vec<Reader> {
    let grey = GREY_CSV.as_bytes();
    let lamp = |file: &str| {
        format!(
            "[[lights]]\nkind = \"point\"\nposition = [0.5, -2.0, 2.0]\nintensity_cd = 500.0\nspectrum = \"light\"\nies = \"{file}\"\naim = [0.5, 0.0, 0.5]\n"
        )
    };
    let light_reader = |name: &'static str, file: &'static str, extension: &str| Reader {
        name,
        file,
        seeds: photometric_seeds(extension),
        bench: Bench::new(&[
            ("grey.csv", grey),
            ("quad.obj", QUAD_OBJ.as_bytes()),
            ("scene.toml", scene_around("quad.obj", &lamp(file)).as_bytes()),
        ]),
        run: |folder| load_and_trace(&folder.join("scene.toml")),
        names_file: names_own_file,
    };

    let texture_reader = |name: &'static str, file: &'static str, detail: &str| Reader {
        name,
        file,
        seeds: texture_seeds(file.rsplit('.').next().unwrap_or("")),
        bench: Bench::new(&[
            ("grey.csv", grey),
            ("quad.obj", TEXTURED_QUAD_OBJ.as_bytes()),
            (
                "scene.toml",
                scene_around("quad.obj", "")
                    .replace(
                        "reflectance = \"grey\"\n",
                        &format!(
                            "reflectance = \"grey\"\ntexture = \"{file}\"\ndetail = \"{detail}\"\n"
                        ),
                    )
                    .as_bytes(),
            ),
        ]),
        run: |folder| load_and_trace(&folder.join("scene.toml")),
        names_file: names_own_file,
    };
    vec![
        texture_reader("png", "input.png", "luminance"),
        texture_reader("jpeg", "input.jpg", "chromatic"),
        light_reader("ies", "input.ies", ".ies"),
        light_reader("ldt", "input.ldt", ".ldt"),
    ]
}

/// The scene TOML itself: the demo's scenes and one that uses every kind of file and light.
fn scene_reader() -> Reader {
    let grey = GREY_CSV.as_bytes();
    let aosta = restauro_demo::scenes::aosta::generate(16, 9, 1);
    let samples = restauro_demo::scenes::samples::generate("A", 16, 12, 1);
    let facade = "g travertine\nv 0 0 0\nv 1 0 0\nv 1 0 1\nf 1 2 3\ng puddinga\nf 1 3 2\ng mortar\nf 2 3 1\ng paving\nf 1 2 3\ng ground\nf 3 2 1\ng interior\nf 2 1 3\n";
    let everything = format!(
        "{}\n[[objects]]\nname = \"scan\"\nmesh = \"meshes/scan.ply\"\nmaterial = \"grey\"\ntransform = {{ translate = [0.0, 1.0, 0.0], rotate_deg = [0.0, 0.0, 30.0], scale = [1.0, 2.0, 1.0] }}\nup_axis = \"y\"\n\n[[objects]]\nname = \"model\"\nmesh = \"meshes/model.glb\"\nmaterials = {{ marble = \"shiny\" }}\nmaterial = \"grey\"\n\n[[objects]]\nname = \"world\"\nmesh = \"meshes/world.wrl\"\nmaterial = \"grey\"\nreplaces = {{ object = \"m\", groups = [\"default\"] }}\n\n[materials.shiny]\nmodel = \"cook-torrance\"\nreflectance = \"dirty\"\nroughness = 0.3\nior = 1.5\ndegraded = {{ reflectance = \"grey\", map = \"survey\", classes = [\"crust\"] }}\n\n[[maps]]\nname = \"survey\"\nimage = \"maps/survey.png\"\ncorner = [0.0, 0.0, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 0.0, 1.0]\nclasses = [{{ name = \"crust\", colour = [0, 0, 0], spectrum = \"soot\" }}, {{ name = \"moss\", colour = [0, 128, 0], spectrum = \"grey\" }}]\n\n[spectra.lamp]\nfile = \"spectra/lamp.csv\"\nextrapolate = true\n\n[spectra.dirty]\nmix = [{{ spectrum = \"grey\", weight = 0.6 }}, {{ spectrum = \"soot\", weight = 0.4 }}]\n\n[[lights]]\nkind = \"spot\"\nposition = [0.0, -3.0, 3.0]\naim = [0.0, 0.0, 0.0]\nintensity_cd = 2000.0\ncone_deg = 20.0\nfalloff_deg = 5.0\nspectrum = \"lamp\"\nies = \"lamps/lamp.ldt\"\n\n[[lights]]\nkind = \"sky\"\npreset = \"overcast\"\nspectrum = \"light\"\n\n[[lights]]\nkind = \"sun\"\nspectrum = \"light\"\npreset = \"sun\"\nsite = {{ latitude_deg = 45.7, longitude_deg = 7.3, height_m = 580.0, datetime = \"2026-06-21T12:00:00+02:00\" }}\n\n[variants.as-found]\nstate = \"degraded\"\nstates = {{ \"model/marble\" = \"base\" }}\n",
        scene_around("quad.obj", "")
            .replace("[spectra]\n", "[spectra]\nsoot = \"carbon_black_soot_proxy__usgs_GDS68\"\n")
    );
    let ldt = read("scene/tests/data/photometric/ldt_isym4_quadrant.ldt");
    let (scan, model, world) = (ply_ascii_seeds(), glb_seeds(), vrml_seeds());
    let lamp_csv = b"380,10\n555,100\n780,40\n";
    let survey = texture_seeds("png").remove(0).1;
    let scene_files: Vec<(&str, &[u8])> = vec![
        ("grey.csv", grey),
        ("white.csv", samples.white_csv.as_bytes()),
        ("board.obj", samples.board_obj.as_bytes()),
        ("meshes/facade.obj", facade.as_bytes()),
        ("quad.obj", QUAD_OBJ.as_bytes()),
        ("meshes/scan.ply", scan[0].1.as_slice()),
        ("meshes/model.glb", model[0].1.as_slice()),
        ("meshes/world.wrl", world[0].1.as_slice()),
        ("lamps/lamp.ldt", ldt.as_slice()),
        ("spectra/lamp.csv", lamp_csv),
        ("maps/survey.png", survey.as_slice()),
    ];
    let scene_bench = Bench::new(&scene_files);

    Reader {
        name: "scene",
        file: "input.toml",
        seeds: vec![
            ("aosta.toml".into(), aosta.scene_toml.into_bytes()),
            ("aosta-overcast.toml".into(), aosta.overcast_toml.into_bytes()),
            ("aosta-clear.toml".into(), aosta.clear_toml.into_bytes()),
            ("samples.toml".into(), samples.scene_toml.into_bytes()),
            ("everything.toml".into(), everything.into_bytes()),
        ],
        bench: scene_bench,
        run: |folder| load_and_trace(&folder.join("input.toml")),
        // The scene file, or a file in its folder (named by its path).
        names_file: |folder, m| m.contains(&folder.display().to_string()),
    }
}

/// The reader of spectrum CSV files.
fn csv_reader() -> Reader {
    Reader {
        name: "csv",
        file: "input.csv",
        seeds: csv_seeds(),
        bench: Bench::new(&[]),
        run: read_csv_as_reflectance_and_light,
        names_file: names_own_file,
    }
}

/// A spectrum CSV read as a reflectance, when it is one (a refusal must still name the file),
/// and as a light, which is what decides: nothing infinite or NaN once accepted.
fn read_csv_as_reflectance_and_light(folder: &Path) -> Outcome {
    let path = folder.join("input.csv");
    let bytes = std::fs::read(&path).unwrap();
    let shown = path.display().to_string();
    let text = restauro_scene::assets::utf8_text(bytes, &path).map_err(|e| e.to_string())?;
    let d65 = restauro_spectral::Illuminant::D65.spd().unwrap();
    // As a reflectance, when it is one (a refusal must still name the file) …
    match load_csv(&text, &shown, Quantity::Reflectance, Coverage::HoldEnds) {
        Ok(loaded) => {
            let xyz = relative_xyz(&loaded.spectrum, &d65, Observer::Cie1931TwoDegree);
            assert!(xyz.to_array().iter().all(|v| v.is_finite()), "reflectance XYZ {xyz:?}");
        }
        Err(e) => assert!(e.to_string().contains("input.csv"), "refused without the file: {e}"),
    }
    // … and as a light, which is what decides.
    let loaded = load_csv(&text, &shown, Quantity::RelativePower, Coverage::HoldEnds)
        .map_err(|e| e.to_string())?;
    let s = loaded.spectrum;
    assert!(s.is_finite(), "accepted, but the spectrum is {s:?}");
    if !s.is_black() {
        let white = relative_xyz(&restauro_spectral::Spectrum::ONE, &s, Observer::Cie1931TwoDegree);
        assert!(white.to_array().iter().all(|v| v.is_finite()), "as an illuminant: XYZ {white:?}");
    }
    if let Ok(light) = LuminousSpectrum::new(&s, &shown) {
        assert!(light.per_lumen.is_finite(), "as a light: {:?}", light.per_lumen);
    }
    Ok(())
}

/// The readers of bundle archives, scene folders sent as a zip, and OpenEXR images.
fn archive_and_exr_readers() -> Vec<Reader> {
    let exr_dir = tempfile::tempdir().unwrap();
    let exr = exr_seeds(exr_dir.path());
    let archive = archive_seeds(exr_dir.path());
    vec![
        Reader {
            name: "archive",
            file: "input.tar",
            seeds: archive,
            bench: Bench::new(&[]),
            run: |folder| load_and_trace(&folder.join("input.tar")),
            names_file: names_own_file,
        },
        Reader {
            name: "folder-zip",
            file: "input.zip",
            seeds: zip_seeds(),
            bench: Bench::new(&[]),
            run: |folder| {
                let bytes = std::fs::read(folder.join("input.zip")).unwrap();
                let limits = Limits::default();
                let bundle = restauro_assets::folder::bundle_folder_archive(&bytes, None, &limits)
                    .map_err(|e| e.to_string())?;
                bundle.load(&limits).map(|_| ()).map_err(|e| e.to_string())
            },
            // The zip's own refusals name the upload; the scene's, the file in it.
            names_file: |_, message| {
                message.starts_with("the folder sent") || message.contains("aosta/")
            },
        },
        Reader {
            name: "exr",
            file: "input.exr",
            seeds: exr,
            bench: Bench::new(&[]),
            run: |folder| {
                let image =
                    read_exr(&folder.join("input.exr"), MAX_PIXELS).map_err(|e| e.to_string())?;
                assert!(
                    image.pixels.iter().flatten().all(|v| v.is_finite()),
                    "accepted, but not finite"
                );
                Ok(())
            },
            names_file: names_own_file,
        },
    ]
}

// ---------------------------------------------------------------------------------------------
// The run

fn env_number(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(v) => v.parse().unwrap_or_else(|_| panic!("{name}={v} is not a whole number")),
        Err(_) => default,
    }
}

struct Failure {
    reader: &'static str,
    seed: String,
    input: u64,
    mutations: Vec<String>,
    problem: String,
    kept: PathBuf,
}

/// One input: written into the bench, read on its own thread within the timeout.
/// A seed (`must_accept`) must also be accepted, or the mutations start from nothing valid.
fn try_input(
    reader: &Reader,
    bytes: &[u8],
    timeout: Duration,
    must_accept: bool,
) -> Result<bool, String> {
    let folder = reader.bench.folder();
    std::fs::write(folder.join(reader.file), bytes).unwrap();
    let before = guard::panics_caught();
    let (send, receive) = mpsc::channel();
    let run = reader.run;
    let inside = folder.clone();
    std::thread::spawn(move || {
        let _ = send.send(std::panic::catch_unwind(|| run(&inside)));
    });
    let result = receive
        .recv_timeout(timeout)
        .map_err(|_| format!("no answer within {} s (a hang)", timeout.as_secs()))?;
    let caught = guard::panics_caught() - before;
    match result {
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(format!("panicked: {what}"))
        }
        Ok(_) if caught > 0 => Err(format!(
            "the panic guard caught {caught} panic(s) inside a third-party parser (the last at {}): \
             the validation in front of it has a hole",
            guard::last_caught_panic().unwrap_or_default()
        )),
        Ok(Err(message)) if must_accept => Err(format!("a seed is refused: {message}")),
        Ok(Err(message)) if !(reader.names_file)(&folder, &message) => {
            Err(format!("refused without naming the file: {message}"))
        }
        Ok(outcome) => {
            if let (Err(message), Ok(_)) = (&outcome, std::env::var("RESTAURO_FUZZ_VERBOSE")) {
                eprintln!(
                    "fuzz: {} refused: {}",
                    reader.name,
                    message.chars().take(200).collect::<String>()
                );
            }
            Ok(outcome.is_ok())
        }
    }
}

#[test]
fn every_reader_survives_mutated_input() {
    let total = env_number("RESTAURO_FUZZ_INPUTS", 3600);
    let base = env_number("RESTAURO_FUZZ_SEED", 0);
    let timeout = Duration::from_secs(env_number("RESTAURO_FUZZ_TIMEOUT_S", 20));
    let only = std::env::var("RESTAURO_FUZZ_ONLY").ok();
    let readers = readers();
    let per_reader = (total / readers.len() as u64).max(1);
    let kept_dir = std::env::temp_dir().join("restauro-fuzz-failures");
    let mut failures: Vec<Failure> = Vec::new();
    let started = Instant::now();
    let mut tried = 0u64;
    for reader in &readers {
        let reader_started = Instant::now();
        let mut accepted = 0u64;
        let mut inputs: Vec<(String, Vec<u8>, Vec<String>, u64)> = Vec::new();
        // The seeds themselves and the kept findings first, unmutated.
        for (name, bytes) in &reader.seeds {
            inputs.push((name.clone(), bytes.clone(), vec!["none (the seed)".into()], u64::MAX));
        }
        for (name, bytes) in findings::of(reader.name) {
            inputs.push((name, bytes, vec!["none (a kept finding)".into()], u64::MAX));
        }
        for n in 0..per_reader {
            if let Some(only) = &only
                && *only != format!("{}:{n}", reader.name)
            {
                continue;
            }
            let mut rng = Rng::new(&[base, hash(reader.name), n]);
            let (name, seed) = &reader.seeds[rng.below(reader.seeds.len())];
            let mut bytes = seed.clone();
            let mutations = mutate(&mut bytes, &mut rng);
            inputs.push((name.clone(), bytes, mutations, n));
        }
        if only.is_some() {
            inputs.retain(|i| i.3 != u64::MAX);
        }
        for (seed, bytes, mutations, n) in inputs {
            tried += 1;
            // A crash (a stack overflow aborts the process) cannot be reported afterwards: the
            // input being read is kept, named, before it is read.
            std::fs::create_dir_all(&kept_dir).unwrap();
            std::fs::write(
                kept_dir.join("in-progress.txt"),
                format!(
                    "{} (seed {seed}, input {n}; RESTAURO_FUZZ_SEED={base} RESTAURO_FUZZ_ONLY={}:{n})\nmutations: {}\n",
                    reader.name,
                    reader.name,
                    mutations.join(", ")
                ),
            )
            .unwrap();
            std::fs::write(kept_dir.join(format!("in-progress-{}", reader.file)), &bytes).unwrap();
            let is_seed = n == u64::MAX && mutations[0] == "none (the seed)";
            let result = try_input(reader, &bytes, timeout, is_seed);
            accepted += u64::from(result == Ok(true));
            if let Err(problem) = result {
                std::fs::create_dir_all(&kept_dir).unwrap();
                let kept = kept_dir.join(format!("{}-{base}-{n}-{}", reader.name, reader.file));
                std::fs::write(&kept, &bytes).unwrap();
                let hang = problem.contains("a hang");
                failures.push(Failure {
                    reader: reader.name,
                    seed,
                    input: n,
                    mutations,
                    problem,
                    kept,
                });
                if hang {
                    break; // its thread still runs on the bench's files
                }
            }
        }
        eprintln!(
            "fuzz: {:<10} {per_reader} inputs in {:.1} s, {accepted} accepted",
            reader.name,
            reader_started.elapsed().as_secs_f64()
        );
    }
    eprintln!(
        "fuzz: {tried} inputs in {:.1} s, {} failures",
        started.elapsed().as_secs_f64(),
        failures.len()
    );
    if !failures.is_empty() {
        let report: Vec<String> = failures
            .iter()
            .take(20)
            .map(|f| {
                format!(
                    "- {} (seed {}, input {}; RESTAURO_FUZZ_SEED={base} RESTAURO_FUZZ_ONLY={}:{}): {}\n  mutations: {}\n  kept as {}",
                    f.reader, f.seed, f.input, f.reader, f.input, f.problem, f.mutations.join(", "), f.kept.display()
                )
            })
            .collect();
        panic!("{} of {tried} inputs failed:\n{}", failures.len(), report.join("\n"));
    }
}
