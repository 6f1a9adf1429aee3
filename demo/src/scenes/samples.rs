//! The paper's stone experiment (Rossi, Marini & Rizzi 2004, Fig. 12) as a scene: samples of
//! travertine and pudding stone, each as found and cleaned, laid on a neutral grey board beside
//! a white reference tile, lit from straight above by one CIE illuminant and seen from above.
//!
//! The light is a distant source at the zenith, so every sample receives exactly the same
//! illuminance and a sample's luminance is ρ·E/π: the renders differ only by the illuminant,
//! which is what the experiment asks. The white tile gives the Retinex its white, as a white
//! card beside samples does for an observer.
//!
//! The as-found stones are *derived*, as in the facade scene: an areal mixture of the clean stone
//! with the carbon-black soot proxy (30 %). The grey board and the white tile are ideal neutral
//! reflectances (flat 30 % and 90 %), written beside the scene as CSV files.

use super::aosta::STONE_SPECTRA;
use std::fmt::Write as _;

/// One square on the board.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The name a reader sees: `travertine, as found`.
    pub label: &'static str,
    /// The stone (`travertine`, `pudding stone`), or `white reference`.
    pub stone: &'static str,
    /// `as found`, `cleaned`, or `reference`.
    pub state: &'static str,
    /// The scene material.
    pub material: &'static str,
    /// Its centre on the board (m), and its edge.
    pub centre_m: [f64; 2],
    pub edge_m: f64,
}

/// The squares on the board, the white reference last.
pub const SAMPLES: [Sample; 5] = [
    Sample {
        label: "travertine, as found",
        stone: "travertine",
        state: "as found",
        material: "travertine_found",
        centre_m: [-0.40, 0.17],
        edge_m: 0.28,
    },
    Sample {
        label: "travertine, cleaned",
        stone: "travertine",
        state: "cleaned",
        material: "travertine_clean",
        centre_m: [-0.06, 0.17],
        edge_m: 0.28,
    },
    Sample {
        label: "pudding stone, as found",
        stone: "pudding stone",
        state: "as found",
        material: "puddinga_found",
        centre_m: [-0.40, -0.17],
        edge_m: 0.28,
    },
    Sample {
        label: "pudding stone, cleaned",
        stone: "pudding stone",
        state: "cleaned",
        material: "puddinga_clean",
        centre_m: [-0.06, -0.17],
        edge_m: 0.28,
    },
    Sample {
        label: "white reference",
        stone: "white reference",
        state: "reference",
        material: "white",
        centre_m: [0.34, 0.0],
        edge_m: 0.28,
    },
];

/// The reflectance of the white tile.
pub const WHITE_REFLECTANCE: f64 = 0.9;
/// The illuminance on the board, lux (a well-lit laboratory bench).
pub const ILLUMINANCE_LUX: f64 = 1000.0;
/// The camera: above the board's centre, looking down, +Y up in the image.
const CAMERA_HEIGHT_M: f64 = 2.0;
const VERTICAL_FOV_DEG: f64 = 26.0;
/// The board's half extents (m).
const BOARD_M: [f64; 2] = [0.62, 0.40];

/// The files of the scene.
pub struct SamplesScene {
    /// `samples.toml`.
    pub scene_toml: String,
    /// `board.obj`: the board and the squares, one group each.
    pub board_obj: String,
    /// `grey.csv` and `white.csv`.
    pub grey_csv: String,
    pub white_csv: String,
}

/// A pixel rectangle: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// Where the inner `fraction` of `sample` lies in an image of `width × height` of this scene:
/// the board point (x, y) is seen at pixel (W/2 + s·x, H/2 − s·y), with
/// s = (H/2) / (h·tan(fov/2)) pixels per metre for a camera at height h (the pinhole camera's
/// image plane, `restauro_render::camera`).
pub fn pixel_rect(sample: &Sample, width: u32, height: u32, fraction: f64) -> PixelRect {
    let s =
        f64::from(height) / 2.0 / (CAMERA_HEIGHT_M * (VERTICAL_FOV_DEG.to_radians() / 2.0).tan());
    let half = sample.edge_m * fraction / 2.0;
    let [cx, cy] = sample.centre_m;
    let px = |x: f64| (f64::from(width) / 2.0 + s * x).round().clamp(0.0, f64::from(width)) as u32;
    let py =
        |y: f64| (f64::from(height) / 2.0 - s * y).round().clamp(0.0, f64::from(height)) as u32;
    PixelRect { x0: px(cx - half), x1: px(cx + half), y0: py(cy + half), y1: py(cy - half) }
}

/// The scene under `illuminant` (a CIE name: `A`, `B`, `C`, `D65`, …), rendered at
/// `width × height` with `samples_per_pixel` (only antialiasing: the light is a direction).
pub fn generate(illuminant: &str, width: u32, height: u32, samples_per_pixel: u32) -> SamplesScene {
    SamplesScene {
        scene_toml: scene_toml(illuminant, width, height, samples_per_pixel),
        board_obj: board_obj(),
        grey_csv: neutral_csv("grey board", 0.3),
        white_csv: neutral_csv("white reference tile", WHITE_REFLECTANCE),
    }
}

/// `board.obj`: the board, and on it the squares, each a group of one quad.
fn board_obj() -> String {
    let mut obj = String::from("# The stone samples board of restauro's demo (z = 0, +Z up).\n");
    let mut vertices = 0;
    let mut square = |obj: &mut String, group: &str, [cx, cy]: [f64; 2], [hx, hy]: [f64; 2], z| {
        let _ = writeln!(obj, "g {group}");
        for (x, y) in
            [(cx - hx, cy - hy), (cx + hx, cy - hy), (cx + hx, cy + hy), (cx - hx, cy + hy)]
        {
            let _ = writeln!(obj, "v {x:.4} {y:.4} {z:.4}");
        }
        let _ =
            writeln!(obj, "f {} {} {} {}", vertices + 1, vertices + 2, vertices + 3, vertices + 4);
        vertices += 4;
    };
    square(&mut obj, "board", [0.0, 0.0], BOARD_M, 0.0);
    // The squares lie 5 mm proud of the board, so they are distinct surfaces.
    for s in &SAMPLES {
        square(&mut obj, s.material, s.centre_m, [s.edge_m / 2.0; 2], 0.005);
    }
    obj
}

/// The CSV file of an ideal neutral reflectance `value`, named `name` in its comment.
fn neutral_csv(name: &str, value: f64) -> String {
    format!(
        "# {name}: an ideal neutral reflectance, {:.0} % at every wavelength (restauro demo).\n\
         wavelength_nm,reflectance\n380,{value}\n780,{value}\n",
        value * 100.0
    )
}

/// `samples.toml`: the camera above the board, the spectra and materials, the board with the
/// squares' materials by group, and the light from above.
fn scene_toml(illuminant: &str, width: u32, height: u32, samples_per_pixel: u32) -> String {
    let materials: String = SAMPLES
        .iter()
        .map(|s| format!("{} = \"{}\"", s.material, s.material))
        .chain(std::iter::once("board = \"board\"".to_owned()))
        .collect::<Vec<_>>()
        .join(", ");
    format!(
        r#"# The stone experiment of Rossi, Marini & Rizzi (2004), Fig. 12, generated by `restauro demo`:
# travertine and pudding stone, as found (DERIVED: 30 % soot-proxy mixture) and cleaned, on a
# neutral grey board beside a white reference tile, under CIE illuminant {illuminant} from above.
format = 1

[camera]
position = [0.0, 0.0, {CAMERA_HEIGHT_M}]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vertical_fov_deg = {VERTICAL_FOV_DEG}
width = {width}
height = {height}

[render]
# The light is a single direction: the direct light is exact, samples only antialias edges.
integrator = "whitted"
samples_per_pixel = {samples_per_pixel}
max_depth = 1
seed = 1

[spectra]
{STONE_SPECTRA}
grey = {{ file = "grey.csv" }}
white = {{ file = "white.csv" }}
light = {{ illuminant = "{illuminant}" }}

[materials.travertine_found]
model = "lambert"
reflectance = "travertine_soiled"

[materials.travertine_clean]
model = "lambert"
reflectance = "travertine"

[materials.puddinga_found]
model = "lambert"
reflectance = "puddinga_soiled"

[materials.puddinga_clean]
model = "lambert"
reflectance = "puddinga"

[materials.white]
model = "lambert"
reflectance = "white"

[materials.board]
model = "lambert"
reflectance = "grey"

[[objects]]
name = "board"
mesh = "board.obj"
materials = {{ {materials} }}

[[lights]]
# CIE illuminant {illuminant}, {ILLUMINANCE_LUX} lux, straight from above.
kind = "sun"
illuminance_lux = {ILLUMINANCE_LUX:.1}
azimuth_deg = 180.0
elevation_deg = 90.0
spectrum = "light"
"#
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_lie_on_the_board_apart_and_inside_the_image() {
        for (i, a) in SAMPLES.iter().enumerate() {
            for (k, &c) in a.centre_m.iter().enumerate() {
                assert!(c.abs() + a.edge_m / 2.0 < BOARD_M[k], "{} leaves the board", a.label);
            }
            for b in &SAMPLES[i + 1..] {
                let apart = (0..2)
                    .any(|k| (a.centre_m[k] - b.centre_m[k]).abs() >= (a.edge_m + b.edge_m) / 2.0);
                assert!(apart, "{} overlaps {}", a.label, b.label);
            }
            let r = pixel_rect(a, 480, 320, 1.0);
            assert!(r.x0 < r.x1 && r.y0 < r.y1 && r.x1 < 480 && r.y1 < 320, "{r:?}");
        }
    }
}
